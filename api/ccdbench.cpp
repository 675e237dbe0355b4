// ccdbench's C++ API (api/ccdbench/ccdbench.hpp): each call in a known floating-point environment, the harness's
// own functions underneath, standard types in and out.

#include "ccdbench/ccdbench.hpp"

#include "ccd/config.hpp"
#include "core/error.hpp"
#include "datasets/atomic_file.hpp"
#include "datasets/input_file.hpp"
#include "datasets/procedural_scenes.hpp"
#include "datasets/query_file.hpp"
#include "datasets/scene_file.hpp"
#include "harness/queries/scoring.hpp"
#include "harness/run.hpp"
#include "harness/run/record_fields.hpp"
#include "harness/run/records.hpp"
#include "reference/elementary_pair.hpp"
#include "strategies/plugin/fp_environment.hpp"
#include "strategies/plugin/host_method.hpp"
#include "strategies/plugin/isolation.hpp"
#include "strategies/registry.hpp"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>
#include <nlohmann/json.hpp>

#include <dlfcn.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <sstream>
#include <stdexcept>

namespace ccdbench {

static_assert(sizeof(Rows) == 24 * sizeof(double), "a pair's rows are 24 doubles, as a query array's (N, 8, 3) rows are");

namespace detail {

struct SceneData {
  std::string label, file;
  ccd::datasets::SceneSequence sequence;
  std::vector<std::array<std::uint32_t, 3>> faces;
};

/// Makes a Scene of a scene file (absolute) under a label.
struct SceneAccess {
  static Scene load(const std::filesystem::path& absolute, const std::string& label) {
    auto data = std::make_shared<SceneData>(SceneData{label,
                                                      (std::filesystem::is_directory(absolute) ? absolute / "scene.json" : absolute).string(),
                                                      ccd::datasets::load_scene_file(absolute),
                                                      {}});
    for (const ccd::Face& face : data->sequence.scene().topology().faces()) data->faces.push_back({face[0], face[1], face[2]});
    Scene scene;
    scene.data_ = std::move(data);
    return scene;
  }
};

}  // namespace detail

namespace {

using nlohmann::json;

/// The environment every call runs in: IEEE round to nearest, no flush-to-zero, no denormals-are-zero, every
/// exception masked (x87 control word 0x037f, MXCSR 0x1f80: the x86-64 System V defaults), which the exact
/// reference and the conservative tests assume (docs/DESIGN.md §8). The caller's is put back on return, exception
/// or not.
class KnownFloatingPoint {
 public:
  KnownFloatingPoint() : caller_(ccd::plugin::FpEnvironment::current()) { ccd::plugin::FpEnvironment{0x037f, 0x1f80}.install(); }
  ~KnownFloatingPoint() { caller_.install(); }
  KnownFloatingPoint(const KnownFloatingPoint&) = delete;
  KnownFloatingPoint& operator=(const KnownFloatingPoint&) = delete;

 private:
  ccd::plugin::FpEnvironment caller_;
};

/// Runs `call` in the known environment, on an arena of its own: TBB's worker threads take the floating-point
/// settings of the thread that makes an arena, so a caller's FTZ never reaches them. The harness's bad-input error
/// becomes std::invalid_argument with its FILE:WHERE: REASON.
template <class Call>
auto guarded(Call call) {
  const KnownFloatingPoint known;
  tbb::task_arena arena;
  try {
    return arena.execute(call);
  } catch (const ccd::InputError& error) {
    throw std::invalid_argument(error.what());
  } catch (const ccd::plugin::HostMethodInterrupted& interrupted) {
    throw MethodInterrupted(interrupted.message);
  }
}

/// Isolated plugins run in a child of the ccdbench program, which a process using this library is not: the program
/// installed beside the library (PREFIX/lib/libccdbench.so, PREFIX/bin/ccdbench; build/lib and build/bin in the
/// build tree), found from where the library was loaded, when the library is loaded.
const bool kHostProgramSet = [] {
  Dl_info info;
  if (::dladdr(reinterpret_cast<void*>(&version), &info) != 0 && info.dli_fname != nullptr) {
    std::error_code error;
    const std::filesystem::path library = std::filesystem::canonical(info.dli_fname, error);
    if (!error) ccd::plugin::set_host_program((library.parent_path().parent_path() / "bin" / "ccdbench").string());
  }
  return true;
}();

ccd::reference::PairKind reference_kind(PairKind kind) {
  return kind == PairKind::vertex_face ? ccd::reference::PairKind::vertex_face : ccd::reference::PairKind::edge_edge;
}

ExactAnswer answer_of(const ccd::reference::Decision& decision) {
  ExactAnswer answer;
  answer.collides = decision.collides;
  answer.by_filter = decision.decided_by == ccd::reference::DecidedBy::filter;
  answer.toi_lower = decision.toi_floor;
  answer.toi_upper = decision.toi_ceiling;
  return answer;
}

mpq_class rational(const std::string& text, const std::string& what) {
  mpq_class value;
  if (text.empty() || value.set_str(text, 10) != 0) throw std::invalid_argument(what + " '" + text + "' is not a rational (p/q or an integer)");
  value.canonicalize();
  return value;
}

ccd::reference::DecisionRequest decision_request(bool want_toi) {
  ccd::reference::DecisionRequest request;
  request.want_toi = want_toi;
  return request;
}

/// The summaries given to the gate, read back from each one's record as check reads a results file.
ccd::harness::GateResults gate_results(const std::string& name, const std::vector<CellSummary>& results) {
  ccd::harness::GateResults file{name, {}};
  for (std::size_t i = 0; i < results.size(); ++i) {
    file.summaries.push_back(
        ccd::harness::read_summary(json::parse(results[i].json), name, "entry " + std::to_string(i), ccd::harness::SummaryUse::gate));
  }
  return file;
}

/// The API's summary: made from the type, in this one place (Python's come from here too).
CellSummary cell_summary(const ccd::harness::CellSummary& s) {
  CellSummary cell;
  cell.scene = s.scene;
  cell.strategy = s.strategy;
  cell.spec = s.spec;
  cell.thickness = s.thickness;
  cell.thickness_from_scene = s.thickness_from_scene;
  cell.steps = s.steps;
  cell.reported = s.reported;
  cell.errors = s.errors;
  cell.ms_per_step = s.ms_per_step;
  if (s.verdict) {
    cell.colliding = s.verdict->colliding;
    cell.missed = s.verdict->missed;
    cell.missed_culled = s.verdict->missed_culled;
    cell.missed_tested = s.verdict->missed_tested;
    cell.false_alarms = s.verdict->false_alarms;
    if (s.verdict->toi) {
      cell.toi_late = s.verdict->toi->late;
      cell.toi_error_max = s.verdict->toi->error_max;
    }
  }
  cell.nondeterministic = s.nondeterministic_at_step.has_value();
  cell.json = json(s).dump();
  return cell;
}

/// The API's score: made from the type, in this one place (Python's come from here too); the TOI error's statistics
/// as the harness computes them for every reader.
Score score_of(const ccd::harness::QueryScore& s) {
  Score score;
  score.method = s.method;
  score.file = s.file;
  score.queries = s.queries;
  score.reported = s.reported;
  score.errors = s.errors;
  score.unlabelled = s.unlabelled;
  score.positives = s.labelled(s.positives);
  score.false_negatives = s.labelled(s.false_negatives);
  score.false_positives = s.labelled(s.false_positives);
  score.ns_per_query = s.ns_per_query;
  score.toi_checked = s.toi_checked;
  score.toi_late = s.toi_late;
  score.changed_between_passes = s.changed_between_passes;
  if (const std::optional<ccd::harness::ToiErrors> errors = ccd::harness::toi_errors_of(s)) {
    score.toi_error_max = errors->max;
    score.toi_error_median = errors->median;
    score.toi_error_p99 = errors->p99;
  }
  return score;
}

}  // namespace

Version version() { return {CCDBENCH_API_VERSION_MAJOR, CCDBENCH_API_VERSION_MINOR, CCDBENCH_API_VERSION_PATCH}; }

namespace {

/// The reference on a pair of doubles (each the rational it is), in the caller's guarded environment.
ExactAnswer decide_doubles(PairKind kind, const Rows& rows, double thickness, bool want_toi) {
  std::array<ccd::Vec3, 8> points;
  for (std::size_t r = 0; r < 8; ++r) points[r] = ccd::Vec3(rows[r][0], rows[r][1], rows[r][2]);
  return answer_of(ccd::reference::decide(reference_kind(kind), points, thickness, decision_request(want_toi)));
}

/// A pair's rationals read; a malformed one is refused naming `where` ("PATH: query Q ") and its row and coordinate.
ccd::reference::ExactPair exact_pair(PairKind kind, const RationalRows& rows, const std::string& where) {
  ccd::reference::ExactPair pair;
  pair.kind = reference_kind(kind);
  for (std::size_t r = 0; r < 8; ++r) {
    for (std::size_t k = 0; k < 3; ++k)
      pair.rows[r][k] = rational(rows[r][k], where + "row " + std::to_string(r) + " coordinate " + std::to_string(k));
  }
  return pair;
}

mpq_class rational_thickness(const std::string& thickness) {
  const mpq_class delta = rational(thickness, "thickness");
  if (delta < 0) throw std::invalid_argument("thickness must be >= 0");
  return delta;
}

void require_thickness(double thickness) {
  if (!std::isfinite(thickness) || thickness < 0) throw std::invalid_argument("thickness must be a finite number >= 0");
}

}  // namespace

ExactAnswer exact_oracle(PairKind kind, const Rows& rows, double thickness, bool want_toi) {
  require_thickness(thickness);
  return guarded([&] { return decide_doubles(kind, rows, thickness, want_toi); });
}

ExactAnswer exact_oracle(PairKind kind, const RationalRows& rows, const std::string& thickness, bool want_toi) {
  return guarded([&] {
    const ccd::reference::ExactPair pair = exact_pair(kind, rows, "");
    return answer_of(ccd::reference::decide(pair, rational_thickness(thickness), decision_request(want_toi)));
  });
}

std::vector<ExactAnswer> exact_oracle(PairKind kind, const Rows* rows, std::size_t count, double thickness, bool want_toi) {
  require_thickness(thickness);
  for (std::size_t i = 0; i < count; ++i) {
    for (const Point& point : rows[i]) {
      for (double coordinate : point) {
        if (!std::isfinite(coordinate)) throw std::invalid_argument("pair " + std::to_string(i) + ": a coordinate is not finite");
      }
    }
  }
  return guarded([&] {
    std::vector<ExactAnswer> answers(count);
    tbb::parallel_for(std::size_t{0}, count, [&](std::size_t i) { answers[i] = decide_doubles(kind, rows[i], thickness, want_toi); });
    return answers;
  });
}

std::vector<ExactAnswer> exact_oracle(const QueryFile& file, const std::string& thickness, bool want_toi) {
  return guarded([&] {
    const mpq_class delta = rational_thickness(thickness);
    // Every rational read first (a malformed one is refused before any work), then decided on every core.
    std::vector<ccd::reference::ExactPair> pairs;
    pairs.reserve(file.exact.size());
    for (std::size_t q = 0; q < file.exact.size(); ++q)
      pairs.push_back(exact_pair(file.kind, file.exact[q], file.path + ": query " + std::to_string(q) + " "));
    std::vector<ExactAnswer> answers(pairs.size());
    tbb::parallel_for(std::size_t{0}, pairs.size(),
                      [&](std::size_t q) { answers[q] = answer_of(ccd::reference::decide(pairs[q], delta, decision_request(want_toi))); });
    return answers;
  });
}

void register_method(const std::string& name, Method method, std::size_t batch) {
  if (!method) throw std::invalid_argument("register_method: no method given for '" + name + "'");
  ccd::plugin::HostMethodSettings settings;
  settings.batch = batch;
  ccd::plugin::register_host_method(
      name,
      [method = std::move(method)](const ccd::plugin::HostBatch& pairs, ccd::plugin::HostAnswers& answers) {
        MethodBatch asked{pairs.vertex_face ? PairKind::vertex_face : PairKind::edge_edge, reinterpret_cast<const Rows*>(pairs.rows), pairs.count,
                          pairs.thickness};
        MethodAnswers given;
        try {
          method(asked, given);
        } catch (const MethodInterrupted& interrupted) {
          throw ccd::plugin::HostMethodInterrupted{interrupted.what()};
        }
        answers.hits = std::move(given.hits);
        answers.tois = std::move(given.tois);
        answers.errors = std::move(given.errors);
      },
      settings);
}

void unregister_method(const std::string& name) { ccd::plugin::unregister_host_method(name); }

QueryFile read_query_file(const std::string& path) {
  return guarded([&] {
    const ccd::datasets::QueryFile read = ccd::datasets::read_query_file(path);
    QueryFile file;
    file.path = read.path.string();
    file.kind = read.kind == ccd::datasets::QueryKind::vertex_face ? PairKind::vertex_face : PairKind::edge_edge;
    for (const ccd::datasets::Query& query : read.queries) {
      RationalRows exact;
      Rows rounded;
      for (std::size_t r = 0; r < 8; ++r) {
        for (std::size_t k = 0; k < 3; ++k) {
          exact[r][k] = query.exact[r][k].get_str();
          rounded[r][k] = query.rounded[r][static_cast<int>(k)];
        }
      }
      file.exact.push_back(std::move(exact));
      file.rounded.push_back(rounded);
      file.exactly_double.push_back(query.exactly_double);
      file.truth.push_back(query.truth ? (*query.truth ? 1 : 0) : -1);
    }
    return file;
  });
}

void write_query_file(const std::string& path, const QueryFile& file) {
  if (file.truth.size() != file.exact.size()) throw std::invalid_argument("a query file needs one label (1, 0 or -1) per query");
  guarded([&] {
    std::vector<ccd::datasets::Query> queries(file.exact.size());
    for (std::size_t q = 0; q < queries.size(); ++q) {
      for (std::size_t r = 0; r < 8; ++r) {
        for (std::size_t k = 0; k < 3; ++k) {
          queries[q].exact[r][k] = rational(file.exact[q][r][k], "query " + std::to_string(q) + " row " + std::to_string(r));
          queries[q].rounded[r][static_cast<int>(k)] = queries[q].exact[r][k].get_d();
        }
      }
      if (file.truth[q] >= 0) queries[q].truth = file.truth[q] == 1;
    }
    ccd::datasets::write_query_file(path, queries);
    return 0;
  });
}

std::vector<Score> score_queries(const std::vector<std::string>& paths, const std::vector<std::string>& methods, double thickness, bool toi,
                                 int repeats) {
  require_thickness(thickness);
  if (repeats < 1) throw std::invalid_argument("repeats must be at least 1");
  return guarded([&] {
    for (const std::string& method : methods) {
      if (method.rfind("answers:", 0) != 0) ccd::harness::make_query_method(method);
    }
    std::vector<std::filesystem::path> inputs(paths.begin(), paths.end());
    std::vector<ccd::datasets::QueryFile> files;
    for (const auto& path : ccd::datasets::discover_query_files(inputs)) files.push_back(ccd::datasets::read_query_file(path));
    if (files.empty()) throw std::invalid_argument("no query files found under the given paths");
    ccd::harness::bind_answer_files(methods, files);
    const ccd::harness::QueryScoringRequest request{methods, thickness, repeats, toi, false};
    std::vector<Score> scores;
    for (const ccd::harness::QueryScore& score : ccd::harness::score_query_files(files, request)) scores.push_back(score_of(score));
    return scores;
  });
}

std::vector<SceneInfo> builtin_scenes() {
  std::vector<SceneInfo> scenes;
  for (const ccd::datasets::ProceduralSceneInfo& info : ccd::datasets::procedural_scenes()) {
    SceneInfo scene{info.name, info.description, {}};
    for (const ccd::datasets::SceneParameter& parameter : info.parameters) scene.parameters.emplace_back(parameter.name, parameter.default_value);
    scenes.push_back(std::move(scene));
  }
  return scenes;
}

const std::string& Scene::label() const { return data_->label; }
const std::string& Scene::file() const { return data_->file; }
std::size_t Scene::num_vertices() const { return data_->sequence.scene().topology().num_vertices(); }
const std::vector<std::array<std::uint32_t, 3>>& Scene::faces() const { return data_->faces; }
std::size_t Scene::num_frames() const { return data_->sequence.num_frames(); }
double Scene::thickness() const { return data_->sequence.scene().thickness(); }

std::vector<Point> Scene::frame(std::size_t k) const {
  if (k >= num_frames()) throw std::out_of_range("frame " + std::to_string(k) + " of a scene of " + std::to_string(num_frames()) + " frames");
  return guarded([&] {
    std::vector<Point> points;
    for (const ccd::Vec3& p : data_->sequence.frame(k)) points.push_back({p.x(), p.y(), p.z()});
    return points;
  });
}

Scene load_scene(const std::string& path) {
  return guarded([&] { return detail::SceneAccess::load(std::filesystem::absolute(path), ccd::harness::scene_file_label(path)); });
}

Scene generate_scene(const std::string& name, const std::map<std::string, double>& parameters) {
  return guarded([&] {
    const ccd::datasets::SceneParameters given(parameters.begin(), parameters.end());
    // Absolute: a relative CCDBENCH_CACHE_DIR must not move with the working directory.
    return detail::SceneAccess::load(std::filesystem::absolute(ccd::datasets::generate_cached_scene(name, given).scene_file), name);
  });
}

std::vector<std::string> strategy_names() {
  std::vector<std::string> names;
  for (const ccd::strategies::StrategyEntry& entry : ccd::strategies::strategy_entries()) names.push_back(entry.name);
  return names;
}

void validate_strategy(const std::string& spec) {
  guarded([&] {
    ccd::strategies::validate(ccd::strategies::parse_strategy_spec(spec));
    return 0;
  });
}

std::vector<CellSummary> run(const RunRequest& request) {
  return guarded([&] {
    ccd::harness::RunOptions options;
    for (const Scene& scene : request.scenes) {
      const std::string file = scene.file();
      options.scenes.push_back({scene.label(), [file] { return ccd::datasets::load_scene_file(file); }});
    }
    if (options.scenes.empty()) throw std::invalid_argument("a run needs at least one scene");
    options.thicknesses = request.thicknesses;
    options.verify = request.verify;
    options.toi = request.toi;
    ccd::harness::complete_run_request(options, request.strategies);
    options.repeats = request.repeats;
    options.max_steps = request.max_steps;
    options.out = std::filesystem::absolute(request.out);
    options.command_line = "ccdbench::run (the C++ API)";
    std::vector<CellSummary> cells;
    for (const ccd::harness::CellRecord& cell : ccd::harness::run_benchmark(options).cells) cells.push_back(cell_summary(cell.summary));
    return cells;
  });
}

std::vector<std::string> write_baseline(const std::string& baseline_file, const std::vector<CellSummary>& results, const std::string& margin) {
  return guarded([&] {
    const ccd::harness::BaselineMargin parsed = ccd::harness::BaselineMargin::parse(margin);
    ccd::datasets::require_writable_file(baseline_file);
    std::ostringstream warnings;
    const json baseline = ccd::harness::write_baseline({gate_results("(results given to ccdbench::write_baseline)", results)}, parsed, {}, warnings);
    ccd::datasets::write_json_file(baseline_file, baseline);
    std::vector<std::string> lines;
    for (const json& entry : baseline) lines.push_back(entry.dump());
    std::istringstream in(warnings.str());
    for (std::string line; std::getline(in, line);) lines.push_back(line);
    return lines;
  });
}

GateResult check(const std::string& baseline_file, const std::vector<CellSummary>& results) {
  return guarded([&] {
    const json baseline = ccd::datasets::read_json_file(baseline_file, "baseline file");
    const ccd::harness::GateVerdict verdict =
        ccd::harness::gate_results(baseline, baseline_file, {gate_results("(results given to ccdbench::check)", results)}, {});
    GateResult result;
    result.passed = verdict.passed();
    result.lines = ccd::harness::gate_lines(verdict);
    return result;
  });
}

}  // namespace ccdbench
