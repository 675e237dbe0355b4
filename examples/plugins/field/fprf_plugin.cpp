// Floating-Point Root Finder (FPRF: Vouga et al.'s CTCD, github.com/Continuous-Collision-Detection/Floating-Point-Root-Finder,
// the commit CCD-Wrapper pins) as a ccdbench plugin (reports/field/README.md). Only this adapter is ours.
//
// Called as CCD-Wrapper calls it (src/ccd.cpp): CTCD::vertexFaceCTCD(v, f0, f1, f2 at t = 0, then at t = 1, eta, t)
// and CTCD::edgeEdgeCTCD(ea0, ea1, eb0, eb1, ..., eta, t), with eta, its distance ("returns true if the edges ever come
// closer than a distance eta", CTCD.h), the thickness δ (CCD-Wrapper passes 0). Its earliest time t is reported as
// the TOI, which CCD-Wrapper computes and throws away. Its header warns that edgeEdgeCTCD "does not work correctly if
// two edges are parallel at the time of intersection": those misses are the library's.
#include "field_adapter.hpp"

#include <ccdbench/ccdbench_plugin.hpp>

#include <CTCD.h>

namespace {

class FloatingPointRootFinder {
 public:
  bool point_triangle_ccd(const Eigen::Vector3d& p_t0, const Eigen::Vector3d& t0_t0, const Eigen::Vector3d& t1_t0, const Eigen::Vector3d& t2_t0,
                          const Eigen::Vector3d& p_t1, const Eigen::Vector3d& t0_t1, const Eigen::Vector3d& t1_t1, const Eigen::Vector3d& t2_t1,
                          double& toi, double min_distance, double /*tmax*/) const {
    return field::keeping_library_messages(
        [&] { return CTCD::vertexFaceCTCD(p_t0, t0_t0, t1_t0, t2_t0, p_t1, t0_t1, t1_t1, t2_t1, min_distance, toi); });
  }
  bool edge_edge_ccd(const Eigen::Vector3d& ea0_t0, const Eigen::Vector3d& ea1_t0, const Eigen::Vector3d& eb0_t0, const Eigen::Vector3d& eb1_t0,
                     const Eigen::Vector3d& ea0_t1, const Eigen::Vector3d& ea1_t1, const Eigen::Vector3d& eb0_t1, const Eigen::Vector3d& eb1_t1,
                     double& toi, double min_distance, double /*tmax*/) const {
    return field::keeping_library_messages(
        [&] { return CTCD::edgeEdgeCTCD(ea0_t0, ea1_t0, eb0_t0, eb1_t0, ea0_t1, ea1_t1, eb0_t1, eb1_t1, min_distance, toi); });
  }
};

}  // namespace

CCDBENCH_PLUGIN_FROM_CCD_CLASS(FloatingPointRootFinder, Eigen::Vector3d, "fprf", FIELD_LIBRARY_COMMIT,
                               "Floating-Point Root Finder (CTCD::vertexFaceCTCD / edgeEdgeCTCD): eta = the thickness, its TOI", CCDBENCH_REPORTS_TOI)
