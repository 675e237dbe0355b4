#pragma once
/// @file
/// ccdbench's C++ API: what the `ccdbench` program does, as calls and typed results. The exact oracle (vertex-face
/// and edge-edge at any thickness δ >= 0: whether the pair comes within δ during the step, and the exact earliest
/// contact as the two doubles around it), query files (read, write, score methods against their labels), scenes
/// (built-in, generated, loaded; frames as arrays), strategies by spec, runs of cells over steps verified against the
/// exact truth, and the gate.
///
/// Installed with the program: `find_package(ccdbench)` gives `ccdbench::library` (this header and
/// libccdbench.so). Only standard types cross it: CGAL, GMP, Eigen and TBB stay inside. Every call runs in a known
/// floating-point environment (round to nearest, no flush-to-zero, no denormals-are-zero), whatever the caller's
/// (a program built with -Ofast has FTZ and DAZ on), and gives the caller's back when it returns.
///
/// Versioning is semantic: a release that changes or removes anything declared here raises the major version; one
/// that only adds raises the minor. CCDBENCH_API_VERSION_* are the version this header is of, version() the
/// library's, and the CMake package's version is the same.
///
/// Errors: bad input (a malformed file, a value out of range) throws std::invalid_argument with "FILE:WHERE:
/// REASON" where there is a file; anything else std::runtime_error.

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#define CCDBENCH_API_VERSION_MAJOR 0
#define CCDBENCH_API_VERSION_MINOR 2
#define CCDBENCH_API_VERSION_PATCH 0

#if defined(CCDBENCH_BUILDING_LIBRARY)
#define CCDBENCH_API __attribute__((visibility("default")))
#else
#define CCDBENCH_API
#endif

namespace ccdbench {

struct Version {
  int major = 0, minor = 0, patch = 0;
};

/// The library's version (compare with CCDBENCH_API_VERSION_* of the header compiled against).
CCDBENCH_API Version version();

using Point = std::array<double, 3>;

/// A pair's 8 points in Tight-Inclusion's order: vertex-face v_t0, f0_t0, f1_t0, f2_t0, v_t1, f0_t1, f1_t1, f2_t1;
/// edge-edge ea0_t0, ea1_t0, eb0_t0, eb1_t0, ea0_t1, ea1_t1, eb0_t1, eb1_t1. Motion is linear over t in [0, 1].
using Rows = std::array<Point, 8>;

/// The same points as exact rationals: each coordinate "p/q" or an integer, in decimal (query files' form).
using RationalRows = std::array<std::array<std::string, 3>, 8>;

enum class PairKind { vertex_face, edge_edge };

/// What the exact reference says of a pair.
struct ExactAnswer {
  /// Whether the closed primitives come within δ of each other for some t in [0, 1]. Exact.
  bool collides = false;
  /// When it collides and the TOI was asked for: the largest double <= the earliest such t, and the smallest
  /// double >= it (equal when that t is a double).
  std::optional<double> toi_lower, toi_upper;
  /// Decided by the certified floating-point filter (else by exact root isolation).
  bool by_filter = false;
};

/// The exact answer for a pair given as doubles (each taken as the rational it is) at thickness δ >= 0.
/// @throws std::invalid_argument for a coordinate or δ that is not finite, or δ < 0.
CCDBENCH_API ExactAnswer exact_oracle(PairKind kind, const Rows& rows, double thickness, bool want_toi = true);

/// The exact answer for a pair given as rationals (a query file's own coordinates, which its labels belong to), at
/// thickness δ >= 0 given as a rational. @throws std::invalid_argument for text that is not a rational.
CCDBENCH_API ExactAnswer exact_oracle(PairKind kind, const RationalRows& rows, const std::string& thickness, bool want_toi = true);

/// The exact answers for `count` pairs of one kind (rows[i] for pair i) at thickness δ >= 0, on every core.
/// @throws std::invalid_argument as the single-pair form does, naming the pair.
CCDBENCH_API std::vector<ExactAnswer> exact_oracle(PairKind kind, const Rows* rows, std::size_t count, double thickness, bool want_toi = true);

/// A query file (CSV of rationals, 8 rows a query; docs/data.md "Inputs").
struct QueryFile {
  std::string path;
  PairKind kind = PairKind::vertex_face;
  /// Per query: its rationals, the doubles nearest them, whether those doubles are the query exactly, its label
  /// (1 collides at δ = 0, 0 not, -1 unlabelled).
  std::vector<RationalRows> exact;
  std::vector<Rows> rounded;
  std::vector<bool> exactly_double;
  std::vector<int> truth;
};

/// Reads a query file; its kind from its folder (vertex-face/, edge-edge/) or name (*vf.csv, *ee.csv).
CCDBENCH_API QueryFile read_query_file(const std::string& path);

/// The exact answers for every query of `file`, on its rationals (which its labels belong to), at thickness δ >= 0
/// given as a rational, on every core.
CCDBENCH_API std::vector<ExactAnswer> exact_oracle(const QueryFile& file, const std::string& thickness = "0", bool want_toi = true);

/// Writes `file`'s queries (their rationals and labels) to `path`, atomically; the kind is the path's, as read.
CCDBENCH_API void write_query_file(const std::string& path, const QueryFile& file);

/// A method's score on one query file, or on every file ("(all)"), as `ccdbench queries` prints it.
struct Score {
  std::string method, file;
  std::size_t queries = 0, reported = 0, errors = 0, unlabelled = 0;
  /// Counted over the labelled queries; nullopt when none is.
  std::optional<std::size_t> positives, false_negatives, false_positives;
  double ns_per_query = 0;
  /// With toi: TOIs compared with the exact earliest contact, those later than it, and the error's statistics.
  std::size_t toi_checked = 0, toi_late = 0;
  std::optional<double> toi_error_max, toi_error_median, toi_error_p99;
  /// With repeats > 1: queries whose answer (outcome, TOI bits, or whether it was an error) differed between passes.
  std::size_t changed_between_passes = 0;
};

/// Scores methods (narrow phases by spec: "conservative", "cubic64:eta=1e-6", "exact", "plugin:PATH", answer files
/// "answers:FILE") on query files or folders, per file and in total, at thickness δ.
CCDBENCH_API std::vector<Score> score_queries(const std::vector<std::string>& paths, const std::vector<std::string>& methods, double thickness = 0,
                                              bool toi = false, int repeats = 1);

// MethodBatch and MethodAnswers are deliberately not the plugin layer's HostBatch and HostAnswers
// (strategies/plugin/host_method.hpp in ccdbench's sources), though both carry one batch's pairs and answers: these
// are this installed API's, in its words (PairKind, Rows), and change only with its major version; those are internal,
// in the narrow phases' words (a vertex_face flag, rows as flat doubles as a plugin gets them), free to change, and
// the strategies library must not include api/. register_method (api/ccdbench.cpp) translates one into the other.

/// A method of the calling program, audited as a plugin is (Python's callables enter this way): once registered
/// under NAME, `callable:NAME` names it wherever a narrow phase is named: as a method of score_queries, and in a
/// run's strategy (`full+callable:NAME`: full's broad phase gives it each step's candidate pairs, of one kind per
/// call). It is asked from one thread at a time, in batches, and gets a copy of the pairs' rows. It answers
/// per pair: hits 1 (contact) or 0 (apart); TOIs for every pair (NaN on a contact is an error) or none at all (a
/// method without TOIs: its first answer decides, and a later batch that differs is an error); an error message (or
/// none). A throw, answers of another size, a TOI outside [0, 1], or a change of the floating-point environment, the
/// working directory or the C locale (put back) is an error of the pairs it concerns, counted apart, never an answer
/// (a batch that throws is asked again one pair at a time). MethodInterrupted ends the call instead. Its cells are
/// never kept for a later run (its code has no digest). A crash or a hang inside it is the calling process's.
struct MethodBatch {
  PairKind kind = PairKind::vertex_face;
  const Rows* rows = nullptr;
  std::size_t count = 0;
  double thickness = 0;
};
struct MethodAnswers {
  std::vector<std::uint8_t> hits;
  std::vector<double> tois;
  std::vector<std::string> errors;
};
using Method = std::function<void(const MethodBatch&, MethodAnswers&)>;

/// Thrown by a Method to end the call that runs it (a user's interrupt) instead of failing its batch; the call
/// (score_queries, run) then throws it to its caller, the cells finished before kept.
struct MethodInterrupted : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// Registers `method` as `callable:NAME` until unregister_method(NAME); `batch`: pairs asked at a time (0: a whole
/// step's pairs of one kind, or a whole query file, in one call). @throws std::invalid_argument for a name that is
/// empty, holds ':' or '+', or is taken.
CCDBENCH_API void register_method(const std::string& name, Method method, std::size_t batch = 0);
CCDBENCH_API void unregister_method(const std::string& name);

/// A built-in procedural scene and its parameters with their defaults.
struct SceneInfo {
  std::string name, description;
  std::vector<std::pair<std::string, double>> parameters;
};
CCDBENCH_API std::vector<SceneInfo> builtin_scenes();

namespace detail {
struct SceneData;
struct SceneAccess;
}  // namespace detail

/// A scene: its mesh (every object in one numbering), its thickness, and its frames.
class CCDBENCH_API Scene {
 public:
  const std::string& label() const;
  /// The scene file it is read from (for a generated scene, the one written into the cache).
  const std::string& file() const;
  std::size_t num_vertices() const;
  const std::vector<std::array<std::uint32_t, 3>>& faces() const;
  std::size_t num_frames() const;
  double thickness() const;
  /// Every vertex's position in frame k. @throws std::out_of_range for k >= num_frames().
  std::vector<Point> frame(std::size_t k) const;

 private:
  friend struct detail::SceneAccess;
  std::shared_ptr<const detail::SceneData> data_;
};

/// Reads a scene file (or a folder holding scene.json).
CCDBENCH_API Scene load_scene(const std::string& path);

/// Generates built-in scene `name` with these parameters (the others at their defaults) into ccdbench's cache, or
/// reads what a call with the same parameters generated before. Its label is `name`. @throws std::invalid_argument for an unknown scene
/// or parameter.
CCDBENCH_API Scene generate_scene(const std::string& name, const std::map<std::string, double>& parameters = {});

/// The strategies a spec can name (full, apccd, ...).
CCDBENCH_API std::vector<std::string> strategy_names();

/// Checks a strategy spec (NAME[+NARROW][:key=value...]) without running it. @throws std::invalid_argument naming
/// what is wrong.
CCDBENCH_API void validate_strategy(const std::string& spec);

/// What to run: every strategy over every step of every scene, at each thickness.
struct RunRequest {
  std::vector<Scene> scenes;
  std::vector<std::string> strategies{"full"};
  /// nullopt: the scene's own δ; empty: {nullopt}.
  std::vector<std::optional<double>> thicknesses;
  /// Verify every step against the exact truth; also compare every reported TOI with the exact earliest contact.
  bool verify = true, toi = false;
  int repeats = 1;
  /// Only the first N steps of each scene (0: all).
  std::size_t max_steps = 0;
  /// The results folder (cells kept for a later run, results.jsonl), as `run --out`.
  std::string out = "ccdbench-results";
};

/// One cell's result (scene x strategy x δ), as `ccdbench run --json` writes it.
struct CellSummary {
  std::string scene, strategy, spec;
  double thickness = 0;
  bool thickness_from_scene = true;
  std::size_t steps = 0, reported = 0, errors = 0;
  double ms_per_step = 0;
  /// With verify: the colliding pairs of the truth, those missed (and how many never tested / tested wrong), and
  /// the false alarms.
  std::optional<std::size_t> colliding, missed, missed_culled, missed_tested, false_alarms;
  /// With toi: TOIs later than the exact earliest contact.
  std::optional<std::size_t> toi_late;
  std::optional<double> toi_error_max;
  /// Whether its answers differed between two passes (code from outside ccdbench only).
  bool nondeterministic = false;
  /// The whole record (JSON), every field docs/DESIGN.md §5 lists.
  std::string json;
};

/// Runs the cells and returns their summaries, in the order of scenes, thicknesses and strategies.
CCDBENCH_API std::vector<CellSummary> run(const RunRequest& request);

/// The gate's verdict on summaries: whether they pass the baseline (a `ccdbench check --baseline` file) and its
/// lines, one per result and per unmatched entry.
struct GateResult {
  bool passed = false;
  std::vector<std::string> lines;
};
CCDBENCH_API GateResult check(const std::string& baseline_file, const std::vector<CellSummary>& results);

/// Writes the gate's baseline of these summaries to `baseline_file` (as `ccdbench check --write-baseline`): one
/// entry per result, allowing `margin` more missed pairs, errors and late TOIs ("N" or "P%"); refuses, as
/// std::invalid_argument, what check would fail whatever the entry. Returns the entries' lines.
CCDBENCH_API std::vector<std::string> write_baseline(const std::string& baseline_file, const std::vector<CellSummary>& results,
                                                     const std::string& margin = "0");

}  // namespace ccdbench
