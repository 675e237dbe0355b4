#include "harness/run.hpp"

#include "core/error.hpp"
#include "datasets/atomic_file.hpp"
#include "datasets/procedural_scenes.hpp"
#include "harness/cell_store.hpp"
#include "harness/progress.hpp"
#include "harness/run/cells.hpp"
#include "harness/run/provenance.hpp"
#include "harness/run/record_fields.hpp"
#include "harness/run/scene_store.hpp"
#include "harness/run/tables.hpp"
#include "harness/truth_cache.hpp"
#include "harness/work_queue.hpp"
#include "strategies/registry.hpp"

#include <tbb/parallel_for.h>
#include <unistd.h>

#include <algorithm>
#include <exception>
#include <iostream>
#include <list>
#include <memory>
#include <optional>
#include <thread>

namespace ccd::harness {

using nlohmann::json;

namespace {

/// Makes each OpenCL strategy of the run on a thread of its own and readies its devices (Strategy::prepare): the
/// context it leaves is the one the first cell on that device takes. A GPU's first context was a rank's longest start
/// of a cell (0.3-0.4 s on an H200 with four ranks making theirs at once); made while rank 0 plans, it costs no cell's
/// time. An MPI rank asks for work meanwhile (a cell that comes first makes a context of its own, or waits for the
/// program the warm-up is building: a small run's cells are not all left to rank 0); a process alone readies its
/// devices before its first cell (wait), so that the cell's start is the cell's own. The thread is joined when the run
/// ends at the latest. An error is left to the cell that meets it again, which reports it with its scene.
class DeviceWarmUp {
 public:
  explicit DeviceWarmUp(const std::vector<strategies::StrategySpec>& specs)
      : thread_([&specs] {
          for (const strategies::StrategySpec& spec : specs) {
            const auto backend = spec.own.find("backend");
            if (backend == spec.own.end() || backend->second != "opencl") continue;
            try {
              strategies::make_strategy(spec)->prepare();
            } catch (...) {  // (see above)
            }
          }
        }) {}
  ~DeviceWarmUp() { wait(); }
  void wait() {
    if (thread_.joinable()) thread_.join();
  }
  DeviceWarmUp(const DeviceWarmUp&) = delete;
  DeviceWarmUp& operator=(const DeviceWarmUp&) = delete;

 private:
  std::thread thread_;
};

/// Where a finished cell goes: its place in the output, its file and key.
struct PlannedCell {
  std::size_t slot = 0;
  std::filesystem::path file;
  CellKey key;
};

/// What rank 0 knows of a work item beside its payload: for whom it prints progress and where its cells go (one, or
/// with --interleave every pending cell of a scene at one δ; none for a truth step).
struct PlannedItem {
  std::string label;
  std::size_t step = 0, steps = 0;
  std::vector<PlannedCell> cells;
};

std::string on_rank(int rank) { return rank_info().size > 1 ? " (rank " + std::to_string(rank) + ")" : std::string(); }

/// A run as rank 0 plans it and every rank works on it: the scenes this rank holds, the cells kept or finished,
/// the work items of the scene being planned, and the progress shown.
class Benchmark {
 public:
  explicit Benchmark(const RunOptions& options)
      : options_(options),
        planner_(rank_info().rank == 0),
        truth_cache_(datasets::procedural_cache_root() / "truth"),
        variants_(scene_variants(options)),
        store_(options, variants_),
        cell_total_(variants_.size() * options.strategies.size()) {
    // Rank 0's view of the run: cells done of every cell planned (a bar on a terminal, plain lines in a log).
    if (planner_) progress_.emplace("run: cells", cell_total_);
  }

  WorkFunction work() {
    return [this](const std::string& payload) { return work_on(payload); };
  }

  /// Plans and runs every cell: one process scene by scene (each scene loaded once, when its turn comes), MPI ranks
  /// every scene at once.
  void run_all();

  /// The cells in the order of --strategy (kept or computed), each summary with the spec as given and its speed-up,
  /// and the cells left out: moved out, once the run has ended.
  RunResult take_result();

 private:
  void say(const std::string& text) {
    if (progress_) {
      progress_->line(text);
    } else {
      std::cerr << text << "\n";
    }
  }

  /// A cell in progress on rank 0: its steps move the estimate; a log gets a line per pass.
  void cell_moved(int pass, std::size_t step, const std::string& strategy);
  /// A work item (harness/work_queue.hpp): {"truth", scene, step} computes or reads one step's truth into the cache
  /// (and this rank's memory); {"cell", scene, spec, file} runs a cell. Steps of a cell are never split: strategies
  /// keep state from step to step.
  std::string work_on(const std::string& payload);
  /// Plans scene variant s, loaded as `data` with `content` its content digest: its kept cells go into cells_, its
  /// truth steps and pending cells become work items.
  void plan_scene(std::size_t s, const SceneData& data, const std::string& content);
  /// Plans every scene variant at once (MPI's rank 0, before any rank starts), their loading side by side.
  void plan_every_scene();
  void say_loading(std::size_t s) {
    say("run: loading " + variants_[s].source->label + (variants_[s].thickness ? " at δ " + significant(*variants_[s].thickness, 6) : std::string()));
  }
  /// The cell of `spec` on scene s, kept from an earlier run (true) or to run; false when the strategy refuses the
  /// scene at one of several δ (left out and said so).
  struct Pending {
    const strategies::StrategySpec* spec;
    std::filesystem::path file;
    CellKey key;
    std::size_t slot;  // cells keep the order of --strategy, kept or computed
  };
  std::optional<Pending> plan_cell(std::size_t s, const SceneData& data, const strategies::StrategySpec& spec, const std::string& content);
  /// Why a kept cell of `spec` may not stand for a fresh one in this run (docs/DESIGN.md §10 "Kept cells"), or "".
  std::string why_not_kept(const std::string& spec, const CellSummary& summary) const;
  /// The run's spec whose text is `text` (a work item names its cell's spec by it).
  const strategies::StrategySpec& spec_named(const std::string& text) const;
  void item_done(std::size_t index, const std::string& text, int rank);

  const RunOptions& options_;
  const bool planner_;
  const TruthCache truth_cache_;
  const std::vector<SceneVariant> variants_;
  SceneStore store_;
  std::size_t cell_total_, cells_finished_ = 0, cell_count_ = 0, cells_done_ = 0;
  /// This run's id (rank 0's start time and process): what the interleaved cells of one of its scenes share.
  const std::string run_id_ = utc_now() + "-" + std::to_string(::getpid());
  std::optional<Progress> progress_;
  /// OUT/results.jsonl, each cell added as it finishes (rank 0 alone writing).
  ResultsLog results_log_{options_.out};
  std::vector<std::optional<CellRecord>> cells_;
  std::vector<std::string> cell_specs_;  // each cell's spec as --strategy gave it (the table's short name)
  std::vector<WorkItem> items_;
  std::vector<PlannedItem> planned_;
  /// Cells a strategy refused (several δ only).
  std::vector<LeftOut> left_out_;
};

void Benchmark::cell_moved(int pass, std::size_t step, const std::string& strategy) {
  if (!progress_) return;
  const SceneData* data = store_.last();
  const std::size_t steps = data ? data->steps : 1;
  const double passes = std::max(1, options_.repeats);
  const double fraction = (pass + static_cast<double>(step + 1) / static_cast<double>(steps)) / passes;
  const std::string label = data ? data->label : "";
  progress_->update(static_cast<double>(cells_finished_) + fraction, cell_total_,
                    label + " / " + strategies::short_label(strategy) + ": pass " + std::to_string(pass + 1) + ", step " + std::to_string(step) +
                        " of steps 0-" + std::to_string(steps - 1));
  if (!progress_->terminal() && step + 1 == steps) {
    say("run: " + label + " / " + strategies::short_label(strategy) + ": pass " + std::to_string(pass + 1) + " of " +
        std::to_string(options_.repeats) + " done");
  }
}

std::string Benchmark::work_on(const std::string& payload) {
  const json task = json::parse(payload);
  // A cell's key (and file name, chosen by rank 0) holds rank 0's thread count: a rank with another would write
  // cells that no rerun can find.
  if (task.at("threads").get<std::size_t>() != worker_threads()) {
    throw std::invalid_argument("rank " + std::to_string(rank_info().rank) + " has " + std::to_string(worker_threads()) +
                                " worker threads and rank 0 " + task.at("threads").dump() +
                                ": give --threads so that every rank has the same (timings, and so cell keys, depend on it)");
  }
  SceneData& data = store_.get(task.at("scene").get<std::size_t>());
  const Scene& scene = data.sequence.scene();
  auto load_truth = [&](std::size_t k) {
    bool computed = false;
    data.truth[k] = truth_cache_.truth(scene, data.frames[k], data.frames[k + 1], computed, options_.toi);
    data.has_truth[k] = true;
    return computed;
  };
  if (task.at("kind") == "truth") return json{{"computed", load_truth(task.at("step"))}}.dump();
  if (options_.verify) {
    // Truth steps computed on other ranks are in the cache by now (they finished before this cell was handed out).
    for (std::size_t k = 0; k < data.steps; ++k) {
      if (!data.has_truth[k]) load_truth(k);
    }
  }
  const CellProgress moved = [this](int pass, std::size_t step, const std::string& strategy) { cell_moved(pass, step, strategy); };
  const CellProgress progress = planner_ ? moved : CellProgress{};
  // Sent to rank 0 as the cell file holds it (the records' one serializer, run/records.hpp).
  if (task.at("kind") == "cell") {
    return json(run_cell(data, spec_named(task.at("spec")), options_, data.steps, task.at("file"), progress, task.at("strategy"))).dump();
  }
  std::vector<CellToRun> cells;
  for (const json& cell : task.at("cells")) cells.push_back({&spec_named(cell.at("spec")), cell.at("file"), cell.at("strategy")});
  return json(run_cells_interleaved(data, cells, options_, data.steps, progress, task.at("group"))).dump();
}

std::string Benchmark::why_not_kept(const std::string& spec, const CellSummary& summary) const {
  // What a plugin's answers depend on is unbounded (its environment, files it reads, libraries it opens itself or
  // that LD_PRELOAD puts before its own): no key covers it, so its answers stand for this run's only when asked.
  if (strategies::runs_plugin(spec) && !options_.resume) {
    return "a plugin's answers can depend on what no digest covers (its environment, files it reads, libraries it opens itself, "
           "LD_PRELOAD); --resume reuses its kept cell, marked resumed, which check refuses unless --allow-resumed";
  }
  // Its passes did not run in turn with this run's cells: compare could not test it pair by pair.
  if (options_.interleave) return "--interleave times a scene's cells in turn, which a kept cell's passes were not";
  // A kept cell holds its answers' digests, not the answers: the files asked for need them.
  if (options_.write_answers) return "--write-answers needs its answers, which a kept cell does not hold";
  if (options_.misses && summary.verdict && summary.verdict->missed != 0) return "--misses needs its missed pairs, which a kept cell does not hold";
  return {};
}

const strategies::StrategySpec& Benchmark::spec_named(const std::string& text) const {
  for (const strategies::StrategySpec& spec : options_.strategies) {
    if (spec.text == text) return spec;
  }
  throw std::logic_error("a work item names a strategy the run was not given: " + text);
}

std::optional<Benchmark::Pending> Benchmark::plan_cell(std::size_t s, const SceneData& data, const strategies::StrategySpec& spec,
                                                       const std::string& content) {
  const SceneSource& source = *variants_[s].source;
  const Scene& scene = data.sequence.scene();
  if (options_.thicknesses.size() > 1) {
    try {
      strategies::check_scene(spec, scene);
    } catch (const std::invalid_argument& refusal) {
      auto it = std::find_if(left_out_.begin(), left_out_.end(), [&](const LeftOut& entry) { return entry.spec == spec.text; });
      if (it == left_out_.end()) it = left_out_.insert(left_out_.end(), {spec.text, {}, refusal.what()});
      it->scenes.push_back(source.label + " at δ " + significant(scene.thickness(), 3));
      --cell_total_;
      return std::nullopt;
    }
  }
  // Planned by the name the strategy will have, without making it (made only where the cell runs).
  CellKey key{source.label,    content,      data.steps,       scene.thickness(), data.thickness_from, strategies::resolved_name(spec),
              options_.verify, options_.toi, options_.repeats, worker_threads(),  executable_digest()};
  const auto file = options_.out / "cells" / cell_file_name(key);
  std::optional<CellRecord> kept;
  if (!options_.fresh && !strategies::runs_host_method(spec.text)) {
    try {
      if (const std::optional<json> cell = read_cell(file, key)) kept = read_cell_record(*cell, file);
    } catch (const InputError& corrupt) {
      throw InputError(corrupt.file(), corrupt.where(), corrupt.reason() + " (remove the file, or rerun with --fresh)");
    }
  }
  if (kept) {
    if (const std::string why = why_not_kept(spec.text, kept->summary); !why.empty()) {
      say("run: " + source.label + " / " + strategies::short_label(spec.text) + ": computed again, not kept from an earlier run: " + why);
      kept.reset();
    }
  }
  cell_specs_.push_back(spec.text);
  if (!kept) {
    cells_.emplace_back();
    return Pending{&spec, file, std::move(key), cells_.size() - 1};
  }
  // The cell is kept under its resolved name; the strategy as given is this run's: results.jsonl names it so
  // (compare and check match cells by it), rank 0 alone writing.
  if (kept->summary.spec != spec.text) {
    kept->summary.spec = spec.text;
    const json document = *kept;
    write_cell(file, document);
    results_log_.add(file, document, std::cerr);
  }
  kept->summary.resumed = true;
  say("run: " + source.label + " / " + key.strategy +
      ": kept from an earlier run with the same inputs, strategy, steps, δ, repeats, threads and executable (--fresh reruns it)");
  ++cells_finished_;
  cells_.push_back(std::move(*kept));
  return std::nullopt;
}

void Benchmark::plan_scene(std::size_t s, const SceneData& data, const std::string& content) {
  const SceneSource& source = *variants_[s].source;
  const std::size_t steps = data.steps;
  const Scene& scene = data.sequence.scene();
  std::vector<Pending> pending;
  for (const strategies::StrategySpec& spec : options_.strategies) {
    if (std::optional<Pending> cell = plan_cell(s, data, spec, content)) pending.push_back(std::move(*cell));
  }
  if (pending.empty()) return;
  // A strategy that refuses this scene (fcl at δ > 0) says so before any truth or timing is spent.
  for (const Pending& cell : pending) strategies::check_scene(*cell.spec, scene);
  // Under MPI the largest cells go first (WorkItem::cost): a cell's work grows with its triangles and steps. A truth
  // step is given its scene's cell's cost: the cells wait for it, so a large scene's truth must not be left for last.
  const double cell_cost = static_cast<double>(scene.topology().num_faces()) * static_cast<double>(steps);
  // A scene's items at every δ are one group: a rank that holds its frames takes the next of them (SceneStore shares
  // the frames between its δ).
  const std::size_t group = static_cast<std::size_t>(variants_[s].source - options_.scenes.data());
  std::vector<std::size_t> truth_items;
  if (options_.verify) {
    for (std::size_t k = 0; k < steps; ++k) {
      truth_items.push_back(items_.size());
      items_.push_back({json{{"kind", "truth"}, {"scene", s}, {"step", k}, {"threads", worker_threads()}}.dump(), {}, cell_cost, group});
      planned_.push_back({source.label, k, steps, {}});
    }
  }
  auto cell_task = [](const Pending& cell) {
    return json{{"spec", cell.spec->text}, {"strategy", cell.key.strategy}, {"file", cell.file.filename().string()}};
  };
  if (options_.interleave && pending.size() > 1) {
    // One work item: the cells' passes run in turn on one rank. The group's id is this run's alone (a kept cell of
    // an earlier run has another), so compare pairs only passes that ran in turn.
    json task = {
        {"kind", "cells"}, {"scene", s}, {"cells", json::array()}, {"threads", worker_threads()}, {"group", run_id_ + "/" + std::to_string(s)}};
    PlannedItem item{source.label, 0, steps, {}};
    for (Pending& cell : pending) {
      task["cells"].push_back(cell_task(cell));
      item.cells.push_back({cell.slot, std::move(cell.file), std::move(cell.key)});
    }
    items_.push_back({task.dump(), truth_items, cell_cost * static_cast<double>(pending.size()), group});
    planned_.push_back(std::move(item));
    return;
  }
  for (Pending& cell : pending) {
    json task = cell_task(cell);
    task.update({{"kind", "cell"}, {"scene", s}, {"threads", worker_threads()}});
    items_.push_back({task.dump(), truth_items, cell_cost, group});
    planned_.push_back({source.label, 0, steps, {{cell.slot, std::move(cell.file), std::move(cell.key)}}});
  }
}

void Benchmark::item_done(std::size_t index, const std::string& text, int rank) {
  PlannedItem& item = planned_.at(index);
  json result = json::parse(text);
  if (item.cells.empty()) {
    const std::string truth = item.label + ": truth of step " + std::to_string(item.step) + " of steps 0-" + std::to_string(item.steps - 1) +
                              (result.at("computed").get<bool>() ? " computed" : " cached") + on_rank(rank);
    // In a log only computed truth gets a line (read from the cache it is quick); the bar shows either.
    if (progress_->terminal()) {
      progress_->update(static_cast<double>(cells_finished_), cell_total_, truth);
    } else if (result.at("computed").get<bool>()) {
      say("run: " + truth);
    }
    return;
  }
  if (!result.is_array()) result = json::array({std::move(result)});
  for (std::size_t c = 0; c < item.cells.size(); ++c) {
    PlannedCell& planned = item.cells[c];
    CellRecord cell = result.at(c).get<CellRecord>();
    cell.summary.key = planned.key.to_json();
    const json document = cell;
    write_cell(planned.file, document);
    results_log_.add(planned.file, document, std::cerr);
    ++cells_done_;
    ++cells_finished_;
    progress_->update(static_cast<double>(cells_finished_), cell_total_,
                      item.label + " / " + strategies::short_label(planned.key.strategy) + " done");
    if (rank_info().size > 1) {
      say("run: " + item.label + " / " + planned.key.strategy + ": cell " + std::to_string(cells_done_) + " of " + std::to_string(cell_count_) +
          " done" + on_rank(rank));
    }
    cells_[planned.slot] = std::move(cell);
  }
}

void Benchmark::run_all() {
  const DoneFunction done = [this](std::size_t index, const std::string& text, int rank) { item_done(index, text, rank); };
  if (rank_info().size == 1) {
    // A process alone readies its devices before its first cell to run, and waits: planning a scene is shorter than
    // a GPU's first context (the cell would make one of its own), and a run whose cells are all kept makes none.
    std::optional<DeviceWarmUp> warm_up;
    try {
      for (std::size_t s = 0; s < variants_.size(); ++s) {
        items_.clear();
        planned_.clear();
        say_loading(s);
        const SceneData& data = store_.get(s);
        plan_scene(s, data, scene_content_digest(data.sequence.scene(), data.frames));
        if (!items_.empty() && !warm_up) {
          warm_up.emplace(options_.strategies);
          warm_up->wait();
        }
        distribute(items_, work(), done);
      }
    } catch (...) {
      // A run that stops on an error still leaves the log as the cell files hold it (a cell computed again once).
      try {
        results_log_.finish(std::cerr);
      } catch (const std::exception& error) {
        std::cerr << "ccdbench: warning: results.jsonl was not rebuilt: " << error.what() << "\n";
      }
      throw;
    }
    results_log_.finish(std::cerr);
    return;
  }
  const DeviceWarmUp warm_up(options_.strategies);  // while rank 0 plans every scene
  plan_every_scene();
  cell_count_ = 0;
  for (const PlannedItem& item : planned_) cell_count_ += item.cells.size();
  say_on_termination("run: stopped before every cell finished (a rank died, or the run was interrupted): finished cells are kept in " +
                     (options_.out / "cells").string() + "; the same command again, with any number of ranks, runs only the rest\n");
  distribute(items_, work(), done);
  say_on_termination({});
  results_log_.finish(std::cerr);
}

void Benchmark::plan_every_scene() {
  // Every rank waits for this: rank 0 loads kScenesLoadedAtOnce scenes side by side (their frames read and hashed,
  // most of the planning: one after another, the 12 variants of issue 66's sweep took 0.4-0.7 s on a GPU node), then
  // plans their variants in order. A scene's variants load in turn, each taking the frames of the one before; each
  // keeps only its digest, which is all planning needs of the frames (a cell loads its scene where it runs). An error
  // is reported as planning them one by one would: the first variant's.
  constexpr std::size_t kScenesLoadedAtOnce = 4;  // (each scene's frames held until its digest is taken)
  struct Loaded {
    std::unique_ptr<SceneData> data;
    std::string content;
    std::exception_ptr error;
  };
  std::vector<std::size_t> firsts;  // each scene's first variant (variants are scene by scene)
  for (std::size_t s = 0; s < variants_.size(); ++s) {
    if (s == 0 || variants_[s].source != variants_[s - 1].source) firsts.push_back(s);
  }
  firsts.push_back(variants_.size());
  for (std::size_t window = 0; window + 1 < firsts.size(); window += kScenesLoadedAtOnce) {
    const std::size_t scenes = std::min(kScenesLoadedAtOnce, firsts.size() - 1 - window);
    const std::size_t first = firsts[window], end = firsts[window + scenes];
    std::vector<Loaded> loaded(end - first);
    tbb::parallel_for(std::size_t{0}, scenes, [&](std::size_t k) {
      SceneData* sibling = nullptr;
      for (std::size_t s = firsts[window + k]; s < firsts[window + k + 1]; ++s) {
        Loaded& into = loaded[s - first];
        try {
          into.data = store_.load(s, sibling, true);
          into.content = scene_content_digest(into.data->sequence.scene(), into.data->frames);
        } catch (...) {
          into.error = std::current_exception();
          break;
        }
        if (sibling != nullptr) std::vector<std::vector<Vec3>>().swap(sibling->frames);  // (what a move left)
        sibling = into.data.get();
      }
      if (sibling != nullptr) std::vector<std::vector<Vec3>>().swap(sibling->frames);
    });
    for (std::size_t s = first; s < end; ++s) {
      say_loading(s);
      if (loaded[s - first].error) std::rethrow_exception(loaded[s - first].error);
      plan_scene(s, *loaded[s - first].data, loaded[s - first].content);
    }
  }
}

RunResult Benchmark::take_result() {
  RunResult result;
  for (std::size_t c = 0; c < cells_.size(); ++c) {
    result.cells.push_back(std::move(*cells_[c]));
    result.cells.back().summary.spec = cell_specs_[c];
  }
  cells_.clear();
  attach_speedups(result.cells);
  result.left_out = std::move(left_out_);
  return result;
}

}  // namespace

void complete_run_request(RunOptions& options, const std::vector<std::string>& specs) {
  for (const std::string& text : specs) {
    try {
      options.strategies.push_back(strategies::parse_strategy_spec(text));
      strategies::validate(options.strategies.back());
    } catch (const std::invalid_argument& error) {
      throw RunRequestRefused("strategy " + text, error.what());
    }
  }
  if (options.toi && !options.verify)
    throw RunRequestRefused("toi", "TOIs are compared with the exact truth: they need verification (--verify exact; the C++ API's verify)");
}

void prepare_run_outputs(const RunOptions& options) {
  if (rank_info().rank != 0) return;  // only rank 0 writes them
  datasets::require_writable_directory(options.out);
  datasets::require_writable_directory(options.out / "cells");
  if (options.json) datasets::require_writable_file(*options.json);
  if (options.report) datasets::require_writable_directory(*options.report);
  if (options.misses) datasets::require_writable_directory(*options.misses);
  if (options.faults) datasets::require_writable_directory(*options.faults);
  if (options.write_answers) datasets::require_writable_directory(*options.write_answers);
  // What the run writes when it ends goes now: a run that stops before (a crash, kill -9, a refusal) leaves no
  // earlier run's results where this run's are expected, for check or a script to take as this run's.
  std::error_code ignored;
  if (options.json) std::filesystem::remove(*options.json, ignored);
  if (options.report) {
    for (const char* file : {kReportPage, kReportSummaries, kReportSteps}) std::filesystem::remove(*options.report / file, ignored);
  }
}

RunResult run_benchmark(const RunOptions& options) {
  // Every output is checked before any work (a run must not compute for an hour and then fail to write). The specs
  // were validated where they were parsed (the command line, the C++ API).
  prepare_run_outputs(options);
  Benchmark benchmark(options);
  if (rank_info().rank != 0) {
    const DeviceWarmUp warm_up(options.strategies);  // while rank 0 plans
    distribute({}, benchmark.work(), {});
    return {};
  }
  benchmark.run_all();
  return benchmark.take_result();
}

}  // namespace ccd::harness
