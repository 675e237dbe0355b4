// ipc-toolkit's TightInclusionCCD (github.com/ipc-sim/ipc-toolkit, src/ipc/ccd/tight_inclusion_ccd.cpp) as a ccdbench
// plugin (reports/field/README.md): Tight-Inclusion as a simulator built on ipc-toolkit calls it. Only this adapter is
// ours.
//
// The class as ipc-toolkit constructs it by default: tolerance 1e-6, at most 1e7 iterations, conservative rescaling
// 0.8, and point_triangle_ccd / edge_edge_ccd with min_distance = the thickness δ and tmax = 1. Its TOI is reported as
// the class returns it, rescaling included: it first asks Tight-Inclusion for contact at a separation grown by up to
// 1e-4 (a fifth of the gap, at most), so its TOI is earlier than the contact by design, and where that TOI is below
// 1e-6 it asks again at δ with no iteration cap and returns 0.8 of that TOI. A pair already within δ at t = 0 is a
// contact at 0. That is the TOI a simulation gets; the table judges it against the exact contact like any other.
// ipc-toolkit's and Tight-Inclusion's loggers are the plugin's own (private_loggers.hpp): ipc-toolkit's prints errors
// only (its trace lines, an iteration cap reached, change no answer).
#include "field_adapter.hpp"
#include "private_loggers.hpp"

#include <ccdbench/ccdbench_plugin.hpp>

#include <ipc/ccd/tight_inclusion_ccd.hpp>

namespace {

class IpcTightInclusion {
 public:
  IpcTightInclusion() { field::use_private_loggers(); }
  bool point_triangle_ccd(const Eigen::Vector3d& p_t0, const Eigen::Vector3d& t0_t0, const Eigen::Vector3d& t1_t0, const Eigen::Vector3d& t2_t0,
                          const Eigen::Vector3d& p_t1, const Eigen::Vector3d& t0_t1, const Eigen::Vector3d& t1_t1, const Eigen::Vector3d& t2_t1,
                          double& toi, double min_distance, double tmax) const {
    return ccd_.point_triangle_ccd(p_t0, t0_t0, t1_t0, t2_t0, p_t1, t0_t1, t1_t1, t2_t1, toi, min_distance, tmax);
  }
  bool edge_edge_ccd(const Eigen::Vector3d& ea0_t0, const Eigen::Vector3d& ea1_t0, const Eigen::Vector3d& eb0_t0, const Eigen::Vector3d& eb1_t0,
                     const Eigen::Vector3d& ea0_t1, const Eigen::Vector3d& ea1_t1, const Eigen::Vector3d& eb0_t1, const Eigen::Vector3d& eb1_t1,
                     double& toi, double min_distance, double tmax) const {
    return ccd_.edge_edge_ccd(ea0_t0, ea1_t0, eb0_t0, eb1_t0, ea0_t1, ea1_t1, eb0_t1, eb1_t1, toi, min_distance, tmax);
  }

 private:
  const ipc::TightInclusionCCD ccd_;  // its defaults: TightInclusionCCD::DEFAULT_TOLERANCE, ..._MAX_ITERATIONS, ..._CONSERVATIVE_RESCALING
};

}  // namespace

CCDBENCH_PLUGIN_FROM_CCD_CLASS(
    IpcTightInclusion, Eigen::Vector3d, "ipc-tight-inclusion", FIELD_LIBRARY_COMMIT,
    "ipc-toolkit's TightInclusionCCD: tolerance 1e-6, 1e7 iterations, conservative rescaling 0.8, min_distance = the thickness",
    CCDBENCH_THREAD_SAFE | CCDBENCH_REPORTS_TOI | CCDBENCH_CONSERVATIVE)
