// Interval root finder (IRF: the multivariate interval test of Redon et al. 2002 solved as Snyder 1992, from
// github.com/Continuous-Collision-Detection/Interval-Based, the commit CCD-Wrapper pins) as a ccdbench plugin
// (reports/field/README.md). Only this adapter is ours.
//
// Called as CCD-Wrapper calls it (src/ccd.cpp): intervalccd::vertexFaceCCD_Interval(v, f0, f1, f2 at t = 0, then at
// t = 1, toi) and intervalccd::edgeEdgeCCD_Interval(ea0, ea1, eb0, eb1, ..., toi), with the library's default tolerance
// (input_tol = 1e-6). Its TOI (the lower end of the earliest interval) is reported, which CCD-Wrapper throws away. It
// has no minimum separation. It has no iteration cap: a query it cannot settle runs until ccdbench's per-query
// timeout ends it (an error of that query).
#include "field_adapter.hpp"

#include <ccdbench/ccdbench_plugin.hpp>

#include <interval_ccd/interval_ccd.hpp>

namespace {

class IntervalRootFinder {
 public:
  bool point_triangle_ccd(const Eigen::Vector3d& p_t0, const Eigen::Vector3d& t0_t0, const Eigen::Vector3d& t1_t0, const Eigen::Vector3d& t2_t0,
                          const Eigen::Vector3d& p_t1, const Eigen::Vector3d& t0_t1, const Eigen::Vector3d& t1_t1, const Eigen::Vector3d& t2_t1,
                          double& toi, double min_distance, double /*tmax*/) const {
    field::require_zero_thickness(min_distance);
    return field::keeping_library_messages(
        [&] { return intervalccd::vertexFaceCCD_Interval(p_t0, t0_t0, t1_t0, t2_t0, p_t1, t0_t1, t1_t1, t2_t1, toi); });
  }
  bool edge_edge_ccd(const Eigen::Vector3d& ea0_t0, const Eigen::Vector3d& ea1_t0, const Eigen::Vector3d& eb0_t0, const Eigen::Vector3d& eb1_t0,
                     const Eigen::Vector3d& ea0_t1, const Eigen::Vector3d& ea1_t1, const Eigen::Vector3d& eb0_t1, const Eigen::Vector3d& eb1_t1,
                     double& toi, double min_distance, double /*tmax*/) const {
    field::require_zero_thickness(min_distance);
    return field::keeping_library_messages(
        [&] { return intervalccd::edgeEdgeCCD_Interval(ea0_t0, ea1_t0, eb0_t0, eb1_t0, ea0_t1, ea1_t1, eb0_t1, eb1_t1, toi); });
  }
};

}  // namespace

CCDBENCH_PLUGIN_FROM_CCD_CLASS(IntervalRootFinder, Eigen::Vector3d, "irf", FIELD_LIBRARY_COMMIT,
                               "IRF (intervalccd::vertexFaceCCD_Interval / edgeEdgeCCD_Interval): tolerance 1e-6, its TOI, δ = 0 only",
                               CCDBENCH_REPORTS_TOI | CCDBENCH_CONSERVATIVE)
