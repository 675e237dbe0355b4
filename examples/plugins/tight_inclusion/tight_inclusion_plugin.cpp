// Tight-Inclusion (Wang et al. 2021, github.com/Continuous-Collision-Detection/Tight-Inclusion) as a ccdbench plugin:
// the worked example of docs/audit.md and reports/plugins/. Only this adapter is ours; the library is
// fetched and built beside it (this folder's CMakeLists.txt says how) and never committed.
//
// Each query calls ticcd::vertexFaceCCD / edgeEdgeCCD as the library's README and its own benchmark app do: the
// vertices in ccdbench's order (which is Tight-Inclusion's), err = (-1, -1, -1) so the library computes its own
// floating-point filters per query, ms = the thickness δ (its minimum separation), tolerance 1e-6 and at most 1e6
// iterations (the values both recommend), t_max = 1, breadth-first search. A contact is reported with the library's
// TOI. The library answers "contact" when it stops at max_itr undecided, as a conservative method does; it has no
// error outcome, so none is reported. Its logger is the plugin's own, on stderr and in no registry: the library's
// default one registers its name process-wide in spdlog (a shared library on Debian), which a second plugin built on
// the library (ipc-toolkit's, reports/field/) would find taken in one process.
#include <ccdbench/ccdbench_plugin.hpp>

#include <spdlog/sinks/stdout_sinks.h>
#include <tight_inclusion/ccd.hpp>
#include <tight_inclusion/logger.hpp>

#include <Eigen/Core>

#include <memory>

namespace {

/// Tight-Inclusion's recommended solving precision (the target size of an inclusion box, in time and space).
constexpr double kTolerance = 1e-6;
/// Tight-Inclusion's recommended iteration limit; past it the query is answered "contact" (conservatively).
constexpr long kMaxIterations = 1000000;

class TightInclusion {
 public:
  TightInclusion() { ticcd::set_logger(std::make_shared<spdlog::logger>("ticcd", std::make_shared<spdlog::sinks::stderr_sink_mt>())); }
  bool point_triangle_ccd(const Eigen::Vector3d& p_t0, const Eigen::Vector3d& t0_t0, const Eigen::Vector3d& t1_t0, const Eigen::Vector3d& t2_t0,
                          const Eigen::Vector3d& p_t1, const Eigen::Vector3d& t0_t1, const Eigen::Vector3d& t1_t1, const Eigen::Vector3d& t2_t1,
                          double& toi, double min_distance, double tmax) const {
    double output_tolerance = kTolerance;
    return ticcd::vertexFaceCCD(p_t0, t0_t0, t1_t0, t2_t0, p_t1, t0_t1, t1_t1, t2_t1, kComputeFilters, min_distance, toi, kTolerance, tmax,
                                kMaxIterations, output_tolerance);
  }
  bool edge_edge_ccd(const Eigen::Vector3d& ea0_t0, const Eigen::Vector3d& ea1_t0, const Eigen::Vector3d& eb0_t0, const Eigen::Vector3d& eb1_t0,
                     const Eigen::Vector3d& ea0_t1, const Eigen::Vector3d& ea1_t1, const Eigen::Vector3d& eb0_t1, const Eigen::Vector3d& eb1_t1,
                     double& toi, double min_distance, double tmax) const {
    double output_tolerance = kTolerance;
    return ticcd::edgeEdgeCCD(ea0_t0, ea1_t0, eb0_t0, eb1_t0, ea0_t1, ea1_t1, eb0_t1, eb1_t1, kComputeFilters, min_distance, toi, kTolerance, tmax,
                              kMaxIterations, output_tolerance);
  }

 private:
  /// err < 0: the library computes the floating-point filters from the query itself (its README's advice for single
  /// queries; a simulator would compute them once from the scene's bounding box).
  const Eigen::Array3d kComputeFilters{-1, -1, -1};
};

}  // namespace

CCDBENCH_PLUGIN_FROM_CCD_CLASS(TightInclusion, Eigen::Vector3d, "tight-inclusion", TIGHT_INCLUSION_VER,
                               "Tight-Inclusion's ticcd::vertexFaceCCD / edgeEdgeCCD: tolerance 1e-6, 1e6 iterations, ms = the thickness",
                               CCDBENCH_THREAD_SAFE | CCDBENCH_REPORTS_TOI | CCDBENCH_CONSERVATIVE)
