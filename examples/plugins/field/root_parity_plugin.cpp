// Root parity (RP: Brochu, Edwards and Bridson 2012, from
// github.com/Continuous-Collision-Detection/Root-Parity-and-Bernstein-Sign-Classification, the commit CCD-Wrapper pins)
// as a ccdbench plugin (reports/field/README.md). Only this adapter is ours.
//
// Called as CCD-Wrapper calls it (src/ccd.cpp): rootparity::RootParityCollisionTest(x0..x3 at t = 0, x0..x3 at t = 1,
// is_edge_edge).run_test(), vertex-face as (v, f1, f0, f2): the point is x0 and the triangle (x1, x2, x3)
// (rootparitycollisiontest.h), with the face's first two corners given in CCD-Wrapper's order; edge-edge as
// (ea0, ea1, eb0, eb1). It answers yes or no (an odd number of roots), no TOI and no minimum separation. The library
// keeps the rounding mode in a process-wide global and calls rand(): a call that leaves the rounding mode changed is
// that call's error in ccdbench, never hidden here.
#include "field_adapter.hpp"

#include <ccdbench/ccdbench_plugin.hpp>

#include <rootparitycollisiontest.h>

namespace {

Vec3d vec(const Eigen::Vector3d& p) { return Vec3d(p.data()); }

class RootParity {
 public:
  bool point_triangle_ccd(const Eigen::Vector3d& p_t0, const Eigen::Vector3d& t0_t0, const Eigen::Vector3d& t1_t0, const Eigen::Vector3d& t2_t0,
                          const Eigen::Vector3d& p_t1, const Eigen::Vector3d& t0_t1, const Eigen::Vector3d& t1_t1, const Eigen::Vector3d& t2_t1,
                          double& /*toi*/, double min_distance, double /*tmax*/) const {
    field::require_zero_thickness(min_distance);
    // The test keeps references to its eight points: they live here until it has run.
    const Vec3d x0 = vec(p_t0), x1 = vec(t1_t0), x2 = vec(t0_t0), x3 = vec(t2_t0);
    const Vec3d y0 = vec(p_t1), y1 = vec(t1_t1), y2 = vec(t0_t1), y3 = vec(t2_t1);
    return field::keeping_library_messages([&] { return rootparity::RootParityCollisionTest(x0, x1, x2, x3, y0, y1, y2, y3, false).run_test(); });
  }
  bool edge_edge_ccd(const Eigen::Vector3d& ea0_t0, const Eigen::Vector3d& ea1_t0, const Eigen::Vector3d& eb0_t0, const Eigen::Vector3d& eb1_t0,
                     const Eigen::Vector3d& ea0_t1, const Eigen::Vector3d& ea1_t1, const Eigen::Vector3d& eb0_t1, const Eigen::Vector3d& eb1_t1,
                     double& /*toi*/, double min_distance, double /*tmax*/) const {
    field::require_zero_thickness(min_distance);
    const Vec3d x0 = vec(ea0_t0), x1 = vec(ea1_t0), x2 = vec(eb0_t0), x3 = vec(eb1_t0);
    const Vec3d y0 = vec(ea0_t1), y1 = vec(ea1_t1), y2 = vec(eb0_t1), y3 = vec(eb1_t1);
    return field::keeping_library_messages([&] { return rootparity::RootParityCollisionTest(x0, x1, x2, x3, y0, y1, y2, y3, true).run_test(); });
  }
};

}  // namespace

CCDBENCH_PLUGIN_FROM_CCD_CLASS(RootParity, Eigen::Vector3d, "root-parity", FIELD_LIBRARY_COMMIT,
                               "Root parity (rootparity::RootParityCollisionTest): yes or no, no TOI, δ = 0 only", CCDBENCH_CONSERVATIVE)
