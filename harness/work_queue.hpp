#pragma once
/// @file
/// Work spread over MPI ranks (`mpirun -n N ccdbench run|truth|queries`), or done in plan order in one process.
///
/// Rank 0 plans: it lists the work items (each a text every rank can carry out, and the items it must wait for)
/// and hands them out one at a time to whichever rank asks next: a work queue, so a slow item never idles the
/// others. Rank 0 works too, on a thread of its own, while its main thread hands out work (only that thread calls
/// MPI: MPI_THREAD_FUNNELED). Every result comes back to rank 0, which alone prints and writes outputs.
///
/// Without MPI, or when not launched by mpirun, or with one rank, the items run in plan order on the calling thread:
/// the single-process program is what it was before MPI.
///
/// A rank that dies (killed, or an error it cannot report) ends the run: mpirun stops every rank and says which
/// one died. What rank 0 had written by then (finished cells, cached truth) stays, so a rerun does the rest.

#include <cstddef>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace ccd::harness {

/// This process among the ranks of the run: 0 of 1 without MPI.
struct RankInfo {
  int rank = 0;
  int size = 1;
  /// Among the ranks on this rank's node (MPI_COMM_TYPE_SHARED): which one, and how many. They take the node's GPUs
  /// in turn (strategies::DeviceTurn).
  int node_rank = 0;
  int node_size = 1;
};

/// Starts MPI when built with it and launched by mpirun (OpenMPI's or a PMI launcher's environment); otherwise
/// nothing. One per process, in main, before any command runs; MPI is finalized by its destructor.
class RankSession {
 public:
  RankSession(int& argc, char**& argv);
  ~RankSession();
  RankSession(const RankSession&) = delete;
  RankSession& operator=(const RankSession&) = delete;

  /// Ends every rank of the run with `exit_code` (MPI_Abort) when there is more than one; returns otherwise. For
  /// a failure on one rank that the others cannot know of: a rank that returned instead would leave them waiting.
  static void end_all_ranks(int exit_code);
};

RankInfo rank_info();

/// The MPI library's own version text (MPI_Get_library_version: "Open MPI v4.1.4, ..."), or "" without MPI.
std::string mpi_library_version();

/// What rank 0 prints (to stderr) if it is terminated while work is under way, e.g. by mpirun after another rank
/// died: where the finished work is kept and how to do the rest (at most 4 KiB; empty: nothing). Only under MPI
/// with more than one rank.
void say_on_termination(const std::string& message);

/// One unit of work: what to do (text for `work`, the same on every rank) and the items that must finish before it
/// starts (indices of earlier items).
struct WorkItem {
  std::string payload;
  std::vector<std::size_t> after;
  /// An estimate of the item's work, in any unit its plan shares: of the items ready, ranks are handed the costliest
  /// first (ties: see `group`), so that a long item does not start last and run alone while the other ranks idle
  /// (longest processing time first). One process runs the items in plan order whatever their cost.
  double cost = 0;
  /// Items of one group share what a rank loads for them (a scene's frames): of the costliest ready items, a rank is
  /// handed one of the group it worked on last, so that it does not load another scene while one it holds has equal
  /// work left (the paper sweep's cells of one scene at two δ cost the same).
  std::optional<std::size_t> group = std::nullopt;
};

/// Of the items not handed out yet (`waiting`) whose items to wait for have `finished`, the one rank 0 hands out next
/// to a rank that worked last on `group`: the costliest; among equals, one of `group`; then the first in plan order.
/// nullopt when none is ready.
std::optional<std::size_t> next_ready_item(const std::vector<WorkItem>& items, const std::vector<bool>& waiting, const std::vector<bool>& finished,
                                           std::optional<std::size_t> group = std::nullopt);

/// Carries out one item's payload on the rank that took it; returns the result, sent back to rank 0.
using WorkFunction = std::function<std::string(const std::string& payload)>;
/// Called on rank 0, on the calling thread, once per finished item, in the order results arrive (under MPI, after
/// the ranks that sent them have been handed their next item).
using DoneFunction = std::function<void(std::size_t item, const std::string& result, int rank)>;

/// Runs every item exactly once. Collective: every rank calls it. On rank 0, `items` is the plan and `done` sees
/// every result; on the other ranks both are ignored and `work` runs on what rank 0 hands out until it says stop.
/// An exception from `work` on rank 0's own thread is rethrown here; one on another rank is printed by that rank as
/// an error and ends the run (end_all_ranks with 2 for bad input, else 1).
void distribute(const std::vector<WorkItem>& items, const WorkFunction& work, const DoneFunction& done);

}  // namespace ccd::harness
