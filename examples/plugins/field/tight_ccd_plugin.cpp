// TightCCD (Wang et al. 2015, github.com/Continuous-Collision-Detection/TightCCD, the commit CCD-Wrapper pins) as a
// ccdbench plugin (reports/field/README.md). Only this adapter is ours.
//
// Called as CCD-Wrapper calls it (src/ccd.cpp): bsc_tightbound::Intersect_VF_robust(f0, f1, f2, v at t = 0, then at
// t = 1), the face BEFORE the vertex (getBezier: the normal of the first three points against the fourth), and
// bsc_tightbound::Intersect_EE_robust(ea0, ea1, eb0, eb1, ...). It answers yes or no (nonzero is yes), with no TOI and
// no minimum separation. Its header defines functions that are not inline, so it is included here, in the plugin's
// one source, and its own bsc_tightbound.cpp (which only includes it) is not compiled.
#include "field_adapter.hpp"

#include <ccdbench/ccdbench_plugin.hpp>

#include <bsc_tightbound.h>

namespace {

Vec3d vec(const Eigen::Vector3d& p) { return Vec3d(p.data()); }

class TightCcd {
 public:
  bool point_triangle_ccd(const Eigen::Vector3d& p_t0, const Eigen::Vector3d& t0_t0, const Eigen::Vector3d& t1_t0, const Eigen::Vector3d& t2_t0,
                          const Eigen::Vector3d& p_t1, const Eigen::Vector3d& t0_t1, const Eigen::Vector3d& t1_t1, const Eigen::Vector3d& t2_t1,
                          double& /*toi*/, double min_distance, double /*tmax*/) const {
    field::require_zero_thickness(min_distance);
    return field::keeping_library_messages([&] {
      return bsc_tightbound::Intersect_VF_robust(vec(t0_t0), vec(t1_t0), vec(t2_t0), vec(p_t0), vec(t0_t1), vec(t1_t1), vec(t2_t1), vec(p_t1)) != 0;
    });
  }
  bool edge_edge_ccd(const Eigen::Vector3d& ea0_t0, const Eigen::Vector3d& ea1_t0, const Eigen::Vector3d& eb0_t0, const Eigen::Vector3d& eb1_t0,
                     const Eigen::Vector3d& ea0_t1, const Eigen::Vector3d& ea1_t1, const Eigen::Vector3d& eb0_t1, const Eigen::Vector3d& eb1_t1,
                     double& /*toi*/, double min_distance, double /*tmax*/) const {
    field::require_zero_thickness(min_distance);
    return field::keeping_library_messages([&] {
      return bsc_tightbound::Intersect_EE_robust(vec(ea0_t0), vec(ea1_t0), vec(eb0_t0), vec(eb1_t0), vec(ea0_t1), vec(ea1_t1), vec(eb0_t1),
                                                 vec(eb1_t1)) != 0;
    });
  }
};

}  // namespace

CCDBENCH_PLUGIN_FROM_CCD_CLASS(TightCcd, Eigen::Vector3d, "tight-ccd", FIELD_LIBRARY_COMMIT,
                               "TightCCD (bsc_tightbound::Intersect_VF_robust / Intersect_EE_robust, face first): yes or no, no TOI, δ = 0 only",
                               CCDBENCH_CONSERVATIVE)
