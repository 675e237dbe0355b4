// Bernstein sign classification (BSC: Tang et al. 2014, from
// github.com/Continuous-Collision-Detection/Root-Parity-and-Bernstein-Sign-Classification, the commit CCD-Wrapper pins)
// as a ccdbench plugin (reports/field/README.md). Only this adapter is ours.
//
// Called as CCD-Wrapper calls it (src/ccd.cpp): bsc::Intersect_VF_robust(f0, f1, f2, v at t = 0, then at t = 1), the
// face BEFORE the vertex: the code takes the normal of its first three points against the fourth (DNF_Culling), though
// the comment above it in bsc.h names the vertex first; and bsc::Intersect_EE_robust(ea0, ea1, eb0, eb1, ...). It
// answers yes or no, with no TOI and no minimum separation. It throws on a large share of queries ("Inflection points
// are not handled exactly in BSC!"): each is an error of its query, never a hit (CCD-Wrapper answers such a query `true`).
#include "field_adapter.hpp"

#include <ccdbench/ccdbench_plugin.hpp>

#include <bsc.h>

namespace {

Vec3d vec(const Eigen::Vector3d& p) { return Vec3d(p.data()); }

class BernsteinSignClassification {
 public:
  bool point_triangle_ccd(const Eigen::Vector3d& p_t0, const Eigen::Vector3d& t0_t0, const Eigen::Vector3d& t1_t0, const Eigen::Vector3d& t2_t0,
                          const Eigen::Vector3d& p_t1, const Eigen::Vector3d& t0_t1, const Eigen::Vector3d& t1_t1, const Eigen::Vector3d& t2_t1,
                          double& /*toi*/, double min_distance, double /*tmax*/) const {
    field::require_zero_thickness(min_distance);
    return field::keeping_library_messages(
        [&] { return bsc::Intersect_VF_robust(vec(t0_t0), vec(t1_t0), vec(t2_t0), vec(p_t0), vec(t0_t1), vec(t1_t1), vec(t2_t1), vec(p_t1)); });
  }
  bool edge_edge_ccd(const Eigen::Vector3d& ea0_t0, const Eigen::Vector3d& ea1_t0, const Eigen::Vector3d& eb0_t0, const Eigen::Vector3d& eb1_t0,
                     const Eigen::Vector3d& ea0_t1, const Eigen::Vector3d& ea1_t1, const Eigen::Vector3d& eb0_t1, const Eigen::Vector3d& eb1_t1,
                     double& /*toi*/, double min_distance, double /*tmax*/) const {
    field::require_zero_thickness(min_distance);
    return field::keeping_library_messages([&] {
      return bsc::Intersect_EE_robust(vec(ea0_t0), vec(ea1_t0), vec(eb0_t0), vec(eb1_t0), vec(ea0_t1), vec(ea1_t1), vec(eb0_t1), vec(eb1_t1));
    });
  }
};

}  // namespace

CCDBENCH_PLUGIN_FROM_CCD_CLASS(
    BernsteinSignClassification, Eigen::Vector3d, "bsc", FIELD_LIBRARY_COMMIT,
    "Bernstein sign classification (bsc::Intersect_VF_robust / Intersect_EE_robust, face first): yes or no, no TOI, δ = 0 only",
    CCDBENCH_CONSERVATIVE)
