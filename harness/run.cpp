#include "harness/run.hpp"

#include "core/error.hpp"
#include "datasets/atomic_file.hpp"
#include "datasets/procedural_scenes.hpp"
#include "harness/cell_store.hpp"
#include "harness/progress.hpp"
#include "harness/run/cells.hpp"
#include "harness/run/provenance.hpp"
#include "harness/run/tables.hpp"
#include "harness/truth_cache.hpp"
#include "harness/work_queue.hpp"
#include "strategies/registry.hpp"

#include <algorithm>
#include <iostream>
#include <list>
#include <memory>

namespace ccd::harness {

using nlohmann::json;

namespace {

/// A scene at one of the run's thicknesses (nullopt: its own).
struct SceneVariant {
  const SceneSource* source;
  std::optional<double> thickness;
};

/// Every scene at every thickness, scene by scene.
std::vector<SceneVariant> scene_variants(const RunOptions& options) {
  const std::vector<std::optional<double>> thicknesses =
      options.thicknesses.empty() ? std::vector<std::optional<double>>{std::nullopt} : options.thicknesses;
  std::vector<SceneVariant> variants;
  for (const SceneSource& source : options.scenes) {
    for (const std::optional<double>& thickness : thicknesses) variants.push_back({&source, thickness});
  }
  return variants;
}

/// The scenes this rank has loaded, by index in the run's variants: loaded when a work item first needs one, and
/// at most kKept at once (a rank may alternate between scenes when the work queue hands out cells of several).
class SceneStore {
 public:
  SceneStore(const RunOptions& options, const std::vector<SceneVariant>& variants) : options_(options), variants_(variants) {}

  SceneData& get(std::size_t index) {
    for (auto it = loaded_.begin(); it != loaded_.end(); ++it) {
      if (it->first != index) continue;
      loaded_.splice(loaded_.begin(), loaded_, it);
      return *loaded_.front().second;
    }
    const SceneVariant& variant = variants_.at(index);
    const SceneSource& source = *variant.source;
    auto data = std::make_unique<SceneData>(SceneData{source.label, source.load(), {}, {}, {}, 0, variant.thickness ? "command line" : "scene"});
    if (variant.thickness) data->sequence.set_thickness(*variant.thickness);
    data->steps = data->sequence.num_steps();
    if (options_.max_steps > 0) data->steps = std::min(data->steps, options_.max_steps);
    if (data->steps == 0) throw InputError(source.label, {}, "the scene has no steps (one frame)");
    for (std::size_t k = 0; k <= data->steps; ++k) data->frames.push_back(data->sequence.frame(k));
    data->truth.resize(data->steps);
    data->has_truth.assign(data->steps, false);
    loaded_.emplace_front(index, std::move(data));
    if (loaded_.size() > kKept) loaded_.pop_back();
    return *loaded_.front().second;
  }

 private:
  static constexpr std::size_t kKept = 2;
  const RunOptions& options_;
  const std::vector<SceneVariant>& variants_;
  std::list<std::pair<std::size_t, std::unique_ptr<SceneData>>> loaded_;

 public:
  /// The scene a work item used last (the one a cell in progress runs on), or nullptr.
  const SceneData* last() const { return loaded_.empty() ? nullptr : loaded_.front().second.get(); }
};

/// What rank 0 knows of a work item beside its payload: for whom it prints progress and where a cell goes.
struct PlannedItem {
  std::string label;
  std::size_t step = 0, steps = 0;
  bool cell = false;
  std::size_t slot = 0;  // the cell's place in the output
  std::filesystem::path file;
  CellKey key;
};

std::string on_rank(int rank) { return rank_info().size > 1 ? " (rank " + std::to_string(rank) + ")" : std::string(); }

}  // namespace

void check_run_outputs(const RunOptions& options) {
  if (rank_info().rank != 0) return;  // only rank 0 writes them
  datasets::require_writable_directory(options.out);
  datasets::require_writable_directory(options.out / "cells");
  if (options.json) datasets::require_writable_file(*options.json);
  if (options.report) datasets::require_writable_directory(*options.report);
  if (options.misses) datasets::require_writable_directory(*options.misses);
  if (options.faults) datasets::require_writable_directory(*options.faults);
  if (options.write_answers) datasets::require_writable_directory(*options.write_answers);
}

std::vector<json> run_benchmark(const RunOptions& options, std::ostream& out) {
  // Every output is checked before any work (a run must not compute for an hour and then fail to write), and before
  // any plugin is loaded; then unknown names fail.
  check_run_outputs(options);
  for (const std::string& spec : options.strategies) strategies::make_strategy(spec);
  const bool planner = rank_info().rank == 0;
  const TruthCache truth_cache(datasets::procedural_cache_root() / "truth");
  const std::vector<SceneVariant> variants = scene_variants(options);
  SceneStore store(options, variants);
  // Rank 0's view of the run: cells done of every cell planned (a bar on a terminal, plain lines in a log).
  std::size_t cell_total = variants.size() * options.strategies.size(), cells_finished = 0;
  std::optional<Progress> progress;
  if (planner) progress.emplace("run: cells", cell_total);
  auto say = [&](const std::string& text) {
    if (progress) {
      progress->line(text);
    } else {
      std::cerr << text << "\n";
    }
  };
  // A cell in progress on rank 0: its steps move the estimate; a log gets a line per pass, as before.
  const CellProgress cell_progress = [&](int pass, std::size_t step, const std::string& strategy) {
    if (!progress) return;
    const SceneData* data = store.last();
    const std::size_t steps = data ? data->steps : 1;
    const double passes = std::max(1, options.repeats);
    const double fraction = (pass + static_cast<double>(step + 1) / static_cast<double>(steps)) / passes;
    const std::string label = data ? data->label : "";
    progress->update(static_cast<double>(cells_finished) + fraction, cell_total,
                     label + " / " + strategies::short_label(strategy) + ": pass " + std::to_string(pass + 1) + ", step " + std::to_string(step + 1) +
                         "/" + std::to_string(steps));
    if (!progress->terminal() && step + 1 == steps) {
      say("run: " + label + " / " + strategies::short_label(strategy) + ": pass " + std::to_string(pass + 1) + " of " +
          std::to_string(options.repeats) + " done");
    }
  };

  // Work items (harness/work_queue.hpp): {"truth", scene, step} computes or reads one step's truth into the cache
  // (and this rank's memory); {"cell", scene, spec, file} runs a cell. Steps of a cell are never split: strategies
  // keep state from step to step.
  const WorkFunction work = [&](const std::string& payload) -> std::string {
    const json task = json::parse(payload);
    // A cell's key (and file name, chosen by rank 0) holds rank 0's thread count: a rank with another would write
    // cells that no rerun can find.
    if (task.at("threads").get<std::size_t>() != worker_threads()) {
      throw std::invalid_argument("rank " + std::to_string(rank_info().rank) + " has " + std::to_string(worker_threads()) +
                                  " worker threads and rank 0 " + task.at("threads").dump() +
                                  ": give --threads so that every rank has the same (timings, and so cell keys, depend on it)");
    }
    SceneData& data = store.get(task.at("scene").get<std::size_t>());
    const Scene& scene = data.sequence.scene();
    auto load_truth = [&](std::size_t k) {
      bool computed = false;
      data.truth[k] = truth_cache.truth(scene, data.frames[k], data.frames[k + 1], computed, options.toi);
      data.has_truth[k] = true;
      return computed;
    };
    if (task.at("kind") == "truth") {
      const std::size_t k = task.at("step");
      const bool computed = load_truth(k);
      return json{{"computed", computed}}.dump();
    }
    if (options.verify) {
      // Truth steps computed on other ranks are in the cache by now (they finished before this cell was handed out).
      for (std::size_t k = 0; k < data.steps; ++k) {
        if (!data.has_truth[k]) load_truth(k);
      }
    }
    json result =
        run_cell(data, task.at("spec"), options, data.steps, task.at("file"), planner ? cell_progress : CellProgress{}, task.at("strategy"));
    return result.dump();
  };
  if (!planner) {
    distribute({}, work, {});
    return {};
  }

  std::vector<std::optional<json>> cells;
  std::vector<std::string> cell_specs;  // each cell's spec as --strategy gave it (the table's short name)
  std::vector<WorkItem> items;
  std::vector<PlannedItem> planned;
  // Plans scene s: its kept cells go into `cells`, its truth steps and pending cells become work items.
  // Cells a strategy refused (several δ only): per spec, the scenes and δ, and the first refusal's reason.
  std::vector<std::pair<std::string, std::pair<std::vector<std::string>, std::string>>> left_out;
  auto plan_scene = [&](std::size_t s) {
    const SceneSource& source = *variants[s].source;
    say("run: loading " + source.label + (variants[s].thickness ? " at δ " + significant(*variants[s].thickness, 6) : std::string()));
    const SceneData& data = store.get(s);
    const std::size_t steps = data.steps;
    const Scene& scene = data.sequence.scene();
    const std::string content = scene_content_digest(scene, data.frames);
    struct Pending {
      std::string spec;
      std::filesystem::path file;
      CellKey key;
      std::size_t slot;  // cells keep the order of --strategy, kept or computed
    };
    std::vector<Pending> pending;
    for (const std::string& spec : options.strategies) {
      const auto strategy = strategies::make_strategy(spec);
      if (options.thicknesses.size() > 1) {
        try {
          strategy->check_scene(scene);
        } catch (const std::invalid_argument& refusal) {
          auto it = std::find_if(left_out.begin(), left_out.end(), [&](const auto& entry) { return entry.first == spec; });
          if (it == left_out.end()) it = left_out.insert(left_out.end(), {spec, {{}, refusal.what()}});
          it->second.first.push_back(source.label + " at δ " + significant(scene.thickness(), 3));
          --cell_total;
          continue;
        }
      }
      CellKey key{source.label,   content,     steps,           scene.thickness(), data.thickness_from, strategy->name(),
                  options.verify, options.toi, options.repeats, worker_threads(),  executable_digest()};
      const auto file = options.out / "cells" / cell_file_name(key);
      std::optional<json> kept;
      if (!options.fresh) {
        try {
          kept = read_cell(file, key);
        } catch (const InputError& corrupt) {
          throw InputError(corrupt.file(), corrupt.where(), corrupt.reason() + " (remove the file, or rerun with --fresh)");
        }
      }
      if (kept) {
        // The cell is kept under its resolved name; the strategy as given is this run's: results.jsonl names it so
        // (compare and check match cells by it), rank 0 alone writing.
        if (rank_info().rank == 0 && (*kept)["summary"].value("spec", json()) != json(spec)) {
          (*kept)["summary"]["spec"] = spec;
          write_cell(file, *kept);
          rebuild_results_log(options.out, std::cerr);
        }
        (*kept)["summary"]["resumed"] = true;
        say("run: " + source.label + " / " + key.strategy +
            ": kept from an earlier run with the same inputs, strategy, steps, δ, "
            "repeats, threads and executable (--fresh reruns it)" +
            (options.misses ? "; its misses are not written to --misses again" : ""));
        ++cells_finished;
        cells.push_back(std::move(*kept));
        cell_specs.push_back(spec);
      } else {
        pending.push_back({spec, file, std::move(key), cells.size()});
        cells.emplace_back();
        cell_specs.push_back(spec);
      }
    }
    if (pending.empty()) return;
    // A strategy that refuses this scene (fcl at δ > 0) says so before any truth or timing is spent.
    for (const Pending& cell : pending) strategies::make_strategy(cell.spec)->check_scene(scene);
    std::vector<std::size_t> truth_items;
    if (options.verify) {
      for (std::size_t k = 0; k < steps; ++k) {
        truth_items.push_back(items.size());
        items.push_back({json{{"kind", "truth"}, {"scene", s}, {"step", k}, {"threads", worker_threads()}}.dump(), {}});
        planned.push_back({source.label, k, steps, false, 0, {}, {}});
      }
    }
    for (Pending& cell : pending) {
      const std::string file = cell.file.filename().string();
      items.push_back(
          {json{{"kind", "cell"}, {"scene", s}, {"spec", cell.spec}, {"strategy", cell.key.strategy}, {"file", file}, {"threads", worker_threads()}}
               .dump(),
           truth_items});
      planned.push_back({source.label, 0, steps, true, cell.slot, std::move(cell.file), std::move(cell.key)});
    }
  };
  std::size_t cell_count = 0, cells_done = 0;
  const DoneFunction done = [&](std::size_t index, const std::string& text, int rank) {
    PlannedItem& item = planned.at(index);
    json result = json::parse(text);
    if (!item.cell) {
      const std::string truth = item.label + ": truth of step " + std::to_string(item.step + 1) + "/" + std::to_string(item.steps) +
                                (result.at("computed").get<bool>() ? " computed" : " cached") + on_rank(rank);
      // In a log only computed truth gets a line (read from the cache it is quick); the bar shows either.
      if (progress->terminal()) {
        progress->update(static_cast<double>(cells_finished), cell_total, truth);
      } else if (result.at("computed").get<bool>()) {
        say("run: " + truth);
      }
      return;
    }
    result["key"] = item.key.to_json();
    result["summary"]["key"] = result["key"];
    write_cell(item.file, result);
    rebuild_results_log(options.out, std::cerr);
    ++cells_done;
    ++cells_finished;
    progress->update(static_cast<double>(cells_finished), cell_total, item.label + " / " + strategies::short_label(item.key.strategy) + " done");
    if (rank_info().size > 1) {
      say("run: " + item.label + " / " + item.key.strategy + ": cell " + std::to_string(cells_done) + " of " + std::to_string(cell_count) + " done" +
          on_rank(rank));
    }
    cells[item.slot] = std::move(result);
  };
  if (rank_info().size == 1) {
    // One process: scene by scene, as before MPI (each scene loaded once, when its turn comes).
    for (std::size_t s = 0; s < variants.size(); ++s) {
      items.clear();
      planned.clear();
      plan_scene(s);
      distribute(items, work, done);
    }
  } else {
    for (std::size_t s = 0; s < variants.size(); ++s) plan_scene(s);
    cell_count = static_cast<std::size_t>(std::count_if(planned.begin(), planned.end(), [](const PlannedItem& p) { return p.cell; }));
    say_on_termination(
        "run: stopped before every cell finished (a rank died, or the run was interrupted): finished "
        "cells are kept in " +
        (options.out / "cells").string() + "; the same command again, with any number of ranks, runs only the rest\n");
    distribute(items, work, done);
    say_on_termination({});
  }

  std::vector<json> summaries;
  for (std::size_t c = 0; c < cells.size(); ++c) {
    summaries.push_back(cells[c]->at("summary"));
    summaries.back()["spec"] = cell_specs[c];
  }
  attach_speedups(summaries);
  const Table table = summary_table(summaries);
  table.print(out);
  out << summary_notes(table) << resolved_names(summaries);
  for (const json& s : summaries) {
    if (s.value("errors", 0) == 0) continue;
    out << "errors: " << s["scene"].get<std::string>() << " / " << s.value("spec", s["strategy"].get<std::string>()) << ": " << s["errors"]
        << " answers could not be taken (counted apart, and as the plugin's errors= key says); written to "
        << s.value("errors_written", std::string("(kept from an earlier run)")) << "/FAULTS.txt\n";
  }
  for (const auto& [spec, refused] : left_out) {
    out << "left out: " << spec << " on " << refused.first.size() << " scene" << (refused.first.size() == 1 ? "" : "s") << " (";
    for (std::size_t i = 0; i < refused.first.size(); ++i) out << (i ? ", " : "") << refused.first[i];
    out << "), which it refuses; the first said: " << refused.second << "\n";
  }
  if (options.json) datasets::write_json_file(*options.json, summaries);
  if (options.report) {
    std::vector<json> finished;
    for (const std::optional<json>& cell : cells) finished.push_back(*cell);
    write_report(*options.report, table, summaries, finished, options.command_line);
    out << "report: " << (*options.report / "README.md").string() << "\n";
  }
  out << "results: " << (options.out / "results.jsonl").string() << " (every finished cell of every run into " << options.out.string() << ")\n";
  return summaries;
}

}  // namespace ccd::harness
