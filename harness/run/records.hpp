#pragma once
/// @file
/// The records `ccdbench run` writes, as types: a cell's step records and its summary (docs/DESIGN.md §5). Each has
/// one serializer (to_json) and one reader (from_json); the cell files, results.jsonl, --json, --report and the
/// exchange between MPI ranks all go through them, so a field is added in one place.

#include "strategies/strategy.hpp"

#include <nlohmann/json.hpp>

#include <array>
#include <cstddef>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace ccd::harness {

/// The version of the records `run` writes (step records and summaries, in --out, --json and --report), in each
/// record's "schema". 2 added each step's time per repeat (ms_repeats), the summary's per-repeat totals
/// (ms_per_repeat), the TOI error's median and 99th percentile, and each step's first missed pairs (missed_pairs):
/// what `compare` needs. Records without it are of version 1.
inline constexpr int kRecordSchema = 2;

/// At most this many missed pairs of a step are kept in its record, each with its 24 coordinates (about 550 bytes):
/// compare lists and writes to replay the pairs a change newly misses from them. Enough for the few misses a gated
/// method has; a step that misses more is compared by counts (compare says so), and its record stays under 60 KB.
inline constexpr std::size_t kKeptMissedPairs = 100;

/// Where and how a record was measured (docs/DESIGN.md §5, provenance): every step record and summary carries it.
struct RecordEnvironment {
  std::string machine, build_type, git_revision, executable;
  /// Library versions by name, and what the strategy adds (an OpenCL cell's platform, device and driver).
  nlohmann::json provenance = nlohmann::json::object();
  std::size_t threads = 0;
  int rank = 0;
};

/// What a verdict counts, of a step or of a cell over its steps: colliding truth pairs, those missed (never tested /
/// tested wrong) and the false alarms.
struct VerdictCounts {
  std::size_t colliding = 0, missed = 0, missed_culled = 0, missed_tested = 0, false_alarms = 0;
  /// Scenes with analytic shapes only.
  std::optional<std::size_t> colliding_face_shape, missed_face_shape;
  /// Adds `other`'s counts (a step's to its cell's); the shape counts where either has them.
  VerdictCounts& operator+=(const VerdictCounts& other);
};

/// A missed pair as a step record keeps it: its kind, its ids (v, f; or a0, a1, b0, b1) and its 24 coordinates
/// (Tight-Inclusion's order), so that compare can write the pairs a change newly misses as query files without the
/// scene.
struct MissedPair {
  bool vertex_face = true;
  std::vector<std::size_t> ids;
  std::array<double, 24> rows{};
  /// Its kind as the records spell it: "vf" or "ee".
  const char* kind() const { return vertex_face ? "vf" : "ee"; }
};

/// The verdict of one step against the exact truth (--verify exact).
struct StepVerdict : VerdictCounts {
  /// The first kKeptMissedPairs missed pairs with their coordinates (missed_pair_records), when any was missed.
  std::optional<std::vector<MissedPair>> missed_pairs;
  /// With --toi.
  struct Toi {
    std::size_t checked = 0, late = 0;
    double error_max = 0;
  };
  std::optional<Toi> toi;
};

/// One step of one cell.
struct StepRecord {
  int schema = kRecordSchema;
  std::string scene, strategy;
  double thickness = 0;
  std::size_t step = 0;
  /// Median over the timed passes, and every pass's.
  double ms = 0;
  std::vector<double> ms_repeats;
  std::map<std::string, double> stages;
  std::size_t candidate_pairs = 0, elementary_tests = 0, kept_bytes = 0, history_bytes = 0, device_bytes = 0, reported = 0;
  /// The answers digest (pairs and TOI bits); cells judged by triangle pairs have none.
  std::optional<std::string> answers;
  /// Answers that could not be given, and the first one's message (both only when there are some).
  std::size_t errors = 0;
  std::string error_first;
  /// The strategy's own counts (apccd's session_start, nf, ...), in its order; written as fields of their own.
  std::vector<std::pair<std::string, double>> counters;
  std::optional<StepVerdict> verdict;
  RecordEnvironment environment;
};

/// The verdict of a cell over its steps (--verify exact).
struct CellVerdict : VerdictCounts {
  /// Why each miss was missed, by cause.
  nlohmann::json miss_causes = nlohmann::json::object();
  /// Truth pairs and faces in contact by pair of objects ("cloth/ball").
  std::map<std::string, std::size_t> colliding_by_objects, faces_in_contact_by_objects;
  /// With --toi: the exact earliest contact against every reported TOI.
  struct Toi {
    std::size_t checked = 0, late = 0, missing = 0;
    double error_max = 0, error_mean = 0;
    std::optional<double> error_median, error_p99;  // none where no TOI was checked
  };
  std::optional<Toi> toi;
};

/// A cell's summary: a strategy over every step of a scene at one δ.
struct CellSummary {
  int schema = kRecordSchema;
  std::string scene, strategy;
  /// The strategy as --strategy gave it (what check and compare match a cell by); empty in a record without it
  /// (schema 1).
  std::string spec;
  /// The strategy as given, else (a record without spec) its resolved name.
  const std::string& given() const { return spec.empty() ? strategy : spec; }
  std::size_t triangles = 0, vertices = 0, steps = 0;
  double thickness = 0;
  /// Whether δ is the scene's own (else the command line's): what check and compare match a cell's δ by.
  bool thickness_from_scene = true;
  double ms_per_step = 0, ms_per_step_mean = 0, unattributed_ms_mean = 0;
  /// A cell's start, outside its timed steps: making the strategy and its init on the first frame (trees, an OpenCL
  /// context, program and device buffers, a plugin's load or its child process), median over the passes, ms. What a
  /// sweep of many short cells spends beside its steps.
  double setup_ms = 0;
  std::vector<double> ms_per_repeat;
  std::map<std::string, double> stage_ms, stage_ms_mean;
  struct Counter {
    double mean = 0, max = 0;
  };
  std::map<std::string, Counter> counters;
  /// Means over the steps (candidates, tests) and peaks (memory, bytes).
  double candidate_pairs = 0, elementary_tests = 0, kept_bytes = 0, history_bytes = 0, device_bytes = 0, host_peak_bytes = 0;
  std::string host_peak_of;  // "cell", or "process" where the peak could not be reset
  /// An isolated plugin's child processes: the largest peak resident memory of those ended during the timed passes,
  /// added to host_peak_bytes (the two peaks summed: an upper bound of the two processes' memory at once); 0 for a
  /// cell that started none.
  double child_peak_bytes = 0;
  std::size_t reported = 0;
  strategies::Judging judged_by = strategies::Judging::elementary_pairs;
  bool verified = false;
  int repeats = 1;
  std::string cell;  // the cell file's stem
  std::size_t errors = 0;
  /// False for a summary read back that does not count its errors (one made by an older ccdbench, or by hand):
  /// the gate refuses it. Not written (the serializer writes `errors`).
  bool errors_counted = true;
  std::optional<std::string> errors_written;
  std::optional<std::size_t> nondeterministic_at_step;
  /// With `run --interleave`: one id shared by the cells of a scene and δ whose timed passes ran in turn (pass 1 of
  /// each, then pass 2, ...), unique to that run; compare tests two such cells' times pass by pass.
  std::optional<std::string> interleave_group;
  std::string finished_at;
  std::optional<CellVerdict> verdict;
  RecordEnvironment environment;
  /// Set once the cell is kept: its key (CellKey::to_json), and whether this run took it from an earlier one.
  std::optional<nlohmann::json> key;
  bool resumed = false;
  /// Set by attach_speedups for a run's output: the speed-up over the entry's baseline and its strategy, null where
  /// there is none.
  struct Speedup {
    std::optional<double> ratio;
    std::optional<std::string> over;
  };
  std::optional<Speedup> speedup;
};

/// A finished cell: its summary and its steps, as a cell file holds it.
struct CellRecord {
  CellSummary summary;
  std::vector<StepRecord> steps;
};

/// A measure of a summary that compare judges and shows, named as the summary's field is: none where the summary has
/// none (not verified, no --toi, errors not counted).
struct Measure {
  const char* name;
  std::optional<double> (*of)(const CellSummary& s);
  /// A count (written as an integer), not a quantity.
  bool count = false;
};

namespace measures {
extern const Measure missed, errors, false_alarms, toi_late, toi_error_median, toi_error_p99, toi_error_max, host_peak_bytes, device_bytes,
    ms_per_step;
}  // namespace measures

/// The cells of one strategy that it refused (several δ only): the scenes and δ, and the first refusal's reason.
struct LeftOut {
  std::string spec;
  std::vector<std::string> scenes;
  std::string reason;
};

/// What a run gives: its cells (kept or computed) in the order of scenes, δ and --strategy, each summary with the
/// spec as given and its speed-up over its baseline strategy in this invocation (attach_speedups), and the cells
/// left out. Empty on a rank other than 0.
struct RunResult {
  std::vector<CellRecord> cells;
  std::vector<LeftOut> left_out;
};

void to_json(nlohmann::json& j, const MissedPair& p);
void from_json(const nlohmann::json& j, MissedPair& p);
void to_json(nlohmann::json& j, const RecordEnvironment& e);
void from_json(const nlohmann::json& j, RecordEnvironment& e);
void to_json(nlohmann::json& j, const StepRecord& r);
void from_json(const nlohmann::json& j, StepRecord& r);
void to_json(nlohmann::json& j, const CellSummary& s);
void from_json(const nlohmann::json& j, CellSummary& s);
void to_json(nlohmann::json& j, const CellRecord& c);
void from_json(const nlohmann::json& j, CellRecord& c);

}  // namespace ccd::harness
