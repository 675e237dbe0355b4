// Minimum Separation Root Finder (MSRF: Harmon et al.'s minimum-separation CCD as ported in
// github.com/Continuous-Collision-Detection/Minimum-Separation-Root-Finder, the commit CCD-Wrapper pins) as a ccdbench
// plugin (reports/field/README.md). Only this adapter is ours.
//
// Called as CCD-Wrapper's benchmark calls it (a minimum-separation method: ccd::vertexFaceMSCCD with the benchmark's
// --minimum-separation, 0 by default): msccd::root_finder::vertexFaceMSCCD(v, f0, f1, f2 at t = 0, then at t = 1,
// min_distance, toi) and edgeEdgeMSCCD(ea0, ea1, eb0, eb1, ...), min_distance = the thickness δ, its TOI reported
// (CCD-Wrapper checks it is in [0, 1] and throws it away). The library accepts a root where the squared distance is
// at most h^2 + 0.1 h (h the separation): its false alarms at small h are its own.
#include "field_adapter.hpp"

#include <ccdbench/ccdbench_plugin.hpp>

#include <minimum_separation_root_finder.hpp>

namespace {

class MinimumSeparationRootFinder {
 public:
  bool point_triangle_ccd(const Eigen::Vector3d& p_t0, const Eigen::Vector3d& t0_t0, const Eigen::Vector3d& t1_t0, const Eigen::Vector3d& t2_t0,
                          const Eigen::Vector3d& p_t1, const Eigen::Vector3d& t0_t1, const Eigen::Vector3d& t1_t1, const Eigen::Vector3d& t2_t1,
                          double& toi, double min_distance, double /*tmax*/) const {
    return field::keeping_library_messages(
        [&] { return msccd::root_finder::vertexFaceMSCCD(p_t0, t0_t0, t1_t0, t2_t0, p_t1, t0_t1, t1_t1, t2_t1, min_distance, toi); });
  }
  bool edge_edge_ccd(const Eigen::Vector3d& ea0_t0, const Eigen::Vector3d& ea1_t0, const Eigen::Vector3d& eb0_t0, const Eigen::Vector3d& eb1_t0,
                     const Eigen::Vector3d& ea0_t1, const Eigen::Vector3d& ea1_t1, const Eigen::Vector3d& eb0_t1, const Eigen::Vector3d& eb1_t1,
                     double& toi, double min_distance, double /*tmax*/) const {
    return field::keeping_library_messages(
        [&] { return msccd::root_finder::edgeEdgeMSCCD(ea0_t0, ea1_t0, eb0_t0, eb1_t0, ea0_t1, ea1_t1, eb0_t1, eb1_t1, min_distance, toi); });
  }
};

}  // namespace

CCDBENCH_PLUGIN_FROM_CCD_CLASS(
    MinimumSeparationRootFinder, Eigen::Vector3d, "msrf", FIELD_LIBRARY_COMMIT,
    "Minimum Separation Root Finder (msccd::root_finder::vertexFaceMSCCD / edgeEdgeMSCCD): min_distance = the thickness, its TOI",
    CCDBENCH_REPORTS_TOI)
