// Rational root parity (RRP: Schneider's reimplementation of root parity in rationals,
// github.com/Continuous-Collision-Detection/Rational-Root-Parity, the commit CCD-Wrapper pins) as a ccdbench plugin
// (reports/field/README.md). Only this adapter is ours.
//
// Called as CCD-Wrapper calls it (src/ccd.cpp): eccd::vertexFaceCCD(v, f0, f1, f2 at t = 0, then at t = 1) and
// eccd::edgeEdgeCCD(ea0, ea1, eb0, eb1, ...). It answers yes or no, with no TOI and no minimum separation. Its faults
// are its own and stay in its answers: when its random rays all fail it writes TF<rand>.txt or EE<rand>.txt into the
// working directory (an isolated child's own) and answers no; a pair that does not move, or moves rigidly by one
// translation, is answered no without a test, even where it touches.
#include "field_adapter.hpp"

#include <ccdbench/ccdbench_plugin.hpp>

#include <ECCD.hpp>

namespace {

class RationalRootParity {
 public:
  bool point_triangle_ccd(const Eigen::Vector3d& p_t0, const Eigen::Vector3d& t0_t0, const Eigen::Vector3d& t1_t0, const Eigen::Vector3d& t2_t0,
                          const Eigen::Vector3d& p_t1, const Eigen::Vector3d& t0_t1, const Eigen::Vector3d& t1_t1, const Eigen::Vector3d& t2_t1,
                          double& /*toi*/, double min_distance, double /*tmax*/) const {
    field::require_zero_thickness(min_distance);
    return field::keeping_library_messages([&] { return eccd::vertexFaceCCD(p_t0, t0_t0, t1_t0, t2_t0, p_t1, t0_t1, t1_t1, t2_t1); });
  }
  bool edge_edge_ccd(const Eigen::Vector3d& ea0_t0, const Eigen::Vector3d& ea1_t0, const Eigen::Vector3d& eb0_t0, const Eigen::Vector3d& eb1_t0,
                     const Eigen::Vector3d& ea0_t1, const Eigen::Vector3d& ea1_t1, const Eigen::Vector3d& eb0_t1, const Eigen::Vector3d& eb1_t1,
                     double& /*toi*/, double min_distance, double /*tmax*/) const {
    field::require_zero_thickness(min_distance);
    return field::keeping_library_messages([&] { return eccd::edgeEdgeCCD(ea0_t0, ea1_t0, eb0_t0, eb1_t0, ea0_t1, ea1_t1, eb0_t1, eb1_t1); });
  }
};

}  // namespace

CCDBENCH_PLUGIN_FROM_CCD_CLASS(RationalRootParity, Eigen::Vector3d, "rational-root-parity", FIELD_LIBRARY_COMMIT,
                               "Rational root parity (eccd::vertexFaceCCD / edgeEdgeCCD): yes or no, no TOI, δ = 0 only", CCDBENCH_CONSERVATIVE)
