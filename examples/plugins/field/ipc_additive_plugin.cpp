// ipc-toolkit's AdditiveCCD (Li et al. 2021's additive CCD, github.com/ipc-sim/ipc-toolkit,
// src/ipc/ccd/additive_ccd.cpp) as a ccdbench plugin (reports/field/README.md). Only this adapter is ours.
//
// The class as ipc-toolkit constructs it by default: no iteration cap, conservative rescaling 0.9, and
// point_triangle_ccd / edge_edge_ccd with min_distance = the thickness δ and tmax = 1. It advances by lower bounds of
// the time to close the distance and stops at the first time the distance (less δ) is below the gap, a tenth of the
// pair's initial distance (less δ): a contact is reported where the pair comes within that gap, and its TOI is that
// time, earlier than the contact by design. A pair already within δ at t = 0 is a contact at 0. ipc-toolkit says it
// is not provably conservative (its header); the table counts what it misses. ipc-toolkit's and Tight-Inclusion's
// loggers are the plugin's own (private_loggers.hpp): ipc-toolkit's prints errors only (its warnings, a gap below
// machine epsilon or an initial distance within δ, change no answer).
#include "field_adapter.hpp"
#include "private_loggers.hpp"

#include <ccdbench/ccdbench_plugin.hpp>

#include <ipc/ccd/additive_ccd.hpp>

namespace {

class IpcAdditive {
 public:
  IpcAdditive() { field::use_private_loggers(); }
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
  const ipc::AdditiveCCD ccd_;  // its defaults: AdditiveCCD::UNLIMITTED_ITERATIONS, AdditiveCCD::DEFAULT_CONSERVATIVE_RESCALING
};

}  // namespace

CCDBENCH_PLUGIN_FROM_CCD_CLASS(IpcAdditive, Eigen::Vector3d, "ipc-additive", FIELD_LIBRARY_COMMIT,
                               "ipc-toolkit's AdditiveCCD: no iteration cap, conservative rescaling 0.9, min_distance = the thickness",
                               CCDBENCH_THREAD_SAFE | CCDBENCH_REPORTS_TOI)
