#include "harness/commands.hpp"

#include "core/error.hpp"
#include "core/number_text.hpp"
#include "datasets/atomic_file.hpp"
#include "datasets/content_hash.hpp"
#include "datasets/procedural_scenes.hpp"
#include "datasets/sample_step.hpp"
#include "datasets/scene_file.hpp"
#include "harness/cell_store.hpp"
#include "harness/inspect.hpp"
#include "harness/progress.hpp"
#include "harness/queries/stress.hpp"
#include "harness/run/provenance.hpp"
#include "harness/sample_comparison.hpp"
#include "harness/table.hpp"
#include "harness/truth_cache.hpp"
#include "harness/work_queue.hpp"
#include "reference/step_truth.hpp"
#include "strategies/opencl/full_opencl.hpp"
#include "strategies/plugin/plugin_narrow_phase.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <iostream>
#include <map>

namespace ccd::harness {

int run_inspect(const InspectOptions& options, std::ostream& out) {
  for (const auto& path : options.paths) {
    const nlohmann::json description = inspect_path(path);
    if (options.json) {
      out << description.dump() << '\n';
    } else {
      print_inspection(description, out);
    }
  }
  return 0;
}

namespace {

struct LoadedStep {
  std::string name;
  Scene scene;
  std::vector<Vec3> x0, x1;
  std::optional<datasets::SampleStep> sample;
};

LoadedStep load_step(const TruthOptions& options) {
  const int sources = (options.frames.empty() ? 0 : 1) + (options.scene ? 1 : 0) + (options.sample ? 1 : 0);
  if (sources != 1) throw std::invalid_argument("give exactly one of --frames A B, --scene FILE --step K, --sample DIR");
  if (options.sample) {
    datasets::SampleStep step = datasets::load_sample_step(*options.sample);
    const std::size_t num_vertices = step.topology.num_vertices();
    Scene scene({{"mesh", ObjectKind::deformable, true, num_vertices, step.topology.faces()}}, {}, options.thickness.value_or(0.0));
    LoadedStep loaded{options.sample->string(), std::move(scene), step.x0, step.x1, std::nullopt};
    loaded.sample = std::move(step);
    return loaded;
  }
  if (!options.frames.empty()) {
    if (options.frames.size() != 2) throw std::invalid_argument("--frames takes exactly two files (the step's frames)");
    const datasets::SceneSequence sequence = datasets::scene_from_frame_files(options.frames, options.thickness.value_or(0.0));
    return {options.frames[0].string() + " -> " + options.frames[1].string(), sequence.scene(), sequence.frame(0), sequence.frame(1), std::nullopt};
  }
  datasets::SceneSequence sequence = datasets::load_scene_file(*options.scene);
  if (options.thickness) sequence.set_thickness(*options.thickness);
  if (options.step >= sequence.num_steps()) {
    throw InputError(*options.scene, "step " + std::to_string(options.step),
                     "the scene has " + std::to_string(sequence.num_steps()) + " steps (0.." +
                         std::to_string(sequence.num_steps() == 0 ? 0 : sequence.num_steps() - 1) + ")");
  }
  return {options.scene->string() + " step " + std::to_string(options.step), sequence.scene(), sequence.frame(options.step),
          sequence.frame(options.step + 1), std::nullopt};
}

}  // namespace

namespace {

/// A truth statistics record, as `truth --json` writes it.
nlohmann::json truth_record(const std::string& name, double thickness, const Scene& scene, const reference::StepTruth& truth) {
  const reference::TruthStatistics& s = truth.statistics;
  return {{"step", name},
          {"thickness", thickness},
          {"vertices", scene.topology().num_vertices()},
          {"faces", scene.topology().num_faces()},
          {"vf", truth.collisions.vertex_face().size()},
          {"ee", truth.collisions.edge_edge().size()},
          {"fs", truth.collisions.face_shape().size()},
          {"vf_pairs_enumerated", s.vertex_face_pairs},
          {"ee_pairs_enumerated", s.edge_edge_pairs},
          {"fs_pairs_enumerated", s.face_shape_pairs},
          {"time_slices", s.time_slices},
          {"decided_by_filter", s.decided_by_filter},
          {"decided_exactly", s.decided_exactly},
          {"enumeration_ms", s.enumeration_milliseconds},
          {"decision_ms", s.decision_milliseconds}};
}

/// `truth --scene S --step K --steps N`: one work item per step (harness/work_queue.hpp), each computed by the
/// reference and stored in the truth cache; a table of every step in order, then the totals.
int run_truth_steps(const TruthOptions& options, std::ostream& out) {
  if (!options.scene || !options.frames.empty() || options.sample) {
    throw std::invalid_argument("--steps takes --scene FILE --step K: a scene's steps");
  }
  const bool planner = rank_info().rank == 0;
  if (planner && options.json) datasets::require_writable_file(*options.json);
  std::optional<datasets::SceneSequence> sequence;
  auto load = [&]() -> datasets::SceneSequence& {
    if (!sequence) {
      sequence = datasets::load_scene_file(*options.scene);
      if (options.thickness) sequence->set_thickness(*options.thickness);
    }
    return *sequence;
  };
  const TruthCache cache(datasets::procedural_cache_root() / "truth");
  const WorkFunction work = [&](const std::string& payload) {
    const std::size_t k = std::stoull(payload);
    datasets::SceneSequence& scene = load();
    const std::vector<Vec3> x0 = scene.frame(k), x1 = scene.frame(k + 1);
    reference::TruthRequest request;
    request.thickness = scene.scene().thickness();
    request.with_toi = options.toi;
    const reference::StepTruth truth = reference::compute_step_truth(scene.scene(), x0, x1, request);
    // Never replaces a cached file that may hold exact TOIs with one that has none.
    const std::filesystem::path file = cache.file_for(scene.scene(), x0, x1);
    if (options.toi || !std::filesystem::exists(file)) write_truth_file(file, truth.collisions, options.toi);
    nlohmann::json record = truth_record(options.scene->string() + " step " + std::to_string(k), request.thickness, scene.scene(), truth);
    record["index"] = k;
    record["rank"] = rank_info().rank;
    return record.dump();
  };
  if (!planner) {
    distribute({}, work, {});
    return 0;
  }
  const std::size_t available = load().num_steps();
  if (options.step >= available) {
    throw InputError(*options.scene, "step " + std::to_string(options.step),
                     "the scene has " + std::to_string(available) + " steps (0.." + std::to_string(available == 0 ? 0 : available - 1) + ")");
  }
  const std::size_t last = options.steps == 0 ? available : std::min(available, options.step + options.steps);
  std::vector<WorkItem> items;
  for (std::size_t k = options.step; k < last; ++k) items.push_back({std::to_string(k), {}});
  std::vector<nlohmann::json> records(items.size());
  std::size_t finished = 0;
  distribute(items, work, [&](std::size_t index, const std::string& result, int rank) {
    records[index] = nlohmann::json::parse(result);
    std::cerr << "truth: step " << options.step + index << " done (" << ++finished << " of " << items.size() << ")"
              << (rank_info().size > 1 ? " on rank " + std::to_string(rank) : std::string()) << "\n";
  });
  out << "truth for " << options.scene->string() << " steps " << options.step << ".." << last - 1 << " (thickness "
      << records.front()["thickness"].get<double>() << "), stored in the truth cache\n";
  using Align = Table::Align;
  Table table({{"step", Align::right},
               {"vf", Align::right},
               {"ee", Align::right},
               {"vf enum.", Align::right},
               {"ee enum.", Align::right},
               {"slices", Align::right},
               {"filter", Align::right},
               {"exactly", Align::right},
               {"ms", Align::right}});
  std::size_t vf = 0, ee = 0;
  double ms = 0;
  for (const nlohmann::json& r : records) {
    const double step_ms = r["enumeration_ms"].get<double>() + r["decision_ms"].get<double>();
    std::vector<std::string> row;
    for (const char* field :
         {"index", "vf", "ee", "vf_pairs_enumerated", "ee_pairs_enumerated", "time_slices", "decided_by_filter", "decided_exactly"}) {
      row.push_back(std::to_string(r[field].get<std::size_t>()));
    }
    row.push_back(fixed(step_ms, 1));
    table.add_row(std::move(row));
    vf += r["vf"].get<std::size_t>();
    ee += r["ee"].get<std::size_t>();
    ms += step_ms;
  }
  table.print(out);
  out << "total: " << records.size() << " steps, colliding pairs vertex-face " << vf << ", edge-edge " << ee << std::fixed << std::setprecision(1)
      << ", " << ms << " ms of truth computation\n";
  out.unsetf(std::ios::fixed);
  if (options.json) datasets::write_json_file(*options.json, nlohmann::json(records));
  return 0;
}

}  // namespace

int run_truth(const TruthOptions& options, std::ostream& out) {
  if (options.steps != 1) return run_truth_steps(options, out);
  if (rank_info().rank != 0) return 0;  // one step under mpirun: rank 0 alone, the output of one process
  if (options.json) datasets::require_writable_file(*options.json);
  const LoadedStep step = load_step(options);
  reference::TruthRequest request;
  request.thickness = step.scene.thickness();
  request.with_toi = options.toi;
  Progress progress("truth: pairs decided", 0);
  request.progress = [&](std::size_t done, std::size_t total) { progress.update(done, total); };
  const reference::StepTruth truth = reference::compute_step_truth(step.scene, step.x0, step.x1, request);
  const reference::TruthStatistics& s = truth.statistics;

  nlohmann::json result = truth_record(step.name, request.thickness, step.scene, truth);
  out << "truth for " << step.name << " (thickness " << request.thickness << ")\n"
      << "  colliding pairs: vertex-face " << truth.collisions.vertex_face().size() << ", edge-edge " << truth.collisions.edge_edge().size()
      << ", face-shape " << truth.collisions.face_shape().size() << "\n"
      << "  pairs enumerated (overlapping swept boxes, " << s.time_slices << " time slice" << (s.time_slices == 1 ? "" : "s") << "): vertex-face "
      << s.vertex_face_pairs << ", edge-edge " << s.edge_edge_pairs << ", face-shape " << s.face_shape_pairs << "\n"
      << "  decided by the certified filter " << s.decided_by_filter << ", exactly " << s.decided_exactly << "\n"
      << std::fixed << std::setprecision(1) << "  time: enumeration " << s.enumeration_milliseconds << " ms, decisions " << s.decision_milliseconds
      << " ms\n";
  out.unsetf(std::ios::fixed);
  if (step.sample) {
    const SampleComparison comparison = compare_with_sample(*step.sample, truth.collisions);
    result["sample"] = to_json(comparison);
    out << "  sample's own truth: vertex-face " << comparison.vertex_face_found << " of " << comparison.vertex_face_positives << " found, edge-edge "
        << comparison.edge_edge_found << " of " << comparison.edge_edge_positives << " found\n"
        << "  colliding pairs outside the sample's candidate list: vertex-face " << comparison.vertex_face_outside_candidates << ", edge-edge "
        << comparison.edge_edge_outside_candidates << "\n";
    for (const std::string& missing : comparison.missing) out << "  MISSING " << missing << "\n";
  }
  if (options.json) datasets::write_json_file(*options.json, result);
  return 0;
}

int run_stress_command(const StressOptions& options, std::ostream& out) {
  if (options.json) datasets::require_writable_file(*options.json);
  if (options.write_queries) datasets::require_writable_directory(*options.write_queries);
  const std::vector<std::string> all_families = datasets::extremes_families();
  for (const std::string& family : options.families) {
    if (std::find(all_families.begin(), all_families.end(), family) == all_families.end()) {
      std::string known;
      for (const std::string& name : all_families) known += (known.empty() ? "" : ", ") + name;
      throw std::invalid_argument("--family " + family + ": the extremes suite has no such family (it has: " + known + ")");
    }
  }
  std::vector<datasets::ExtremeQuery> suite;
  for (datasets::ExtremeQuery& query : datasets::extremes_suite(options.seed)) {
    const bool chosen =
        options.families.empty() || std::find(options.families.begin(), options.families.end(), query.family) != options.families.end();
    if (chosen) suite.push_back(std::move(query));
  }
  out << "extremes suite: " << suite.size() << " queries in " << (options.families.empty() ? all_families.size() : options.families.size())
      << " families (seed " << options.seed << "), at δ = 0 and at each case's δ > 0; truth from the exact reference\n";
  const std::vector<StressRow> rows = run_stress(suite, options.methods);
  print_stress(rows, out);
  for (const StressRow& row : rows) {
    if (row.family == "(all)") continue;
    for (const std::string& missed : row.missed) out << "missed by " << row.method << " (δ " << row.thickness << "): " << missed << "\n";
  }
  if (options.json) {
    nlohmann::json document = nlohmann::json::array();
    const nlohmann::json made = environment();
    for (const StressRow& row : rows) {
      document.push_back(to_json(row));
      document.back().update(made);
    }
    datasets::write_json_file(*options.json, document);
  }
  if (options.write_queries) {
    write_extremes_queries(suite, *options.write_queries);
    out << "wrote the suite as query files under " << options.write_queries->string() << "\n";
  }
  return 0;
}

int run_devices(bool json, std::ostream& out) {
  std::vector<strategies::OpenClDeviceSummary> devices;
  try {
    devices = strategies::opencl_devices();
  } catch (const std::invalid_argument& unavailable) {
    std::cerr << "ccdbench: error: " << unavailable.what() << '\n';
    return 2;
  }
  if (devices.empty() && !json) {
    out << "no OpenCL device (is an ICD such as pocl-opencl-icd installed, or OCL_ICD_VENDORS set?)\n";
    return 0;
  }
  for (const auto& d : devices) {
    const std::string verdict = d.refused_because.empty() ? "usable" : d.refused_because;
    if (json) {
      const nlohmann::json line = {{"index", d.index},
                                   {"platform", d.platform},
                                   {"name", d.name},
                                   {"version", d.version},
                                   {"driver", d.driver},
                                   {"type", d.gpu ? "gpu" : "other"},
                                   {"compute_units", d.compute_units},
                                   {"global_memory_bytes", d.global_memory},
                                   {"fp64", d.fp64},
                                   {"fp64_denormals", d.fp64_denormals},
                                   {"int64_atomics", d.int64_atomics},
                                   {"usable", d.refused_because.empty()}};
      out << line.dump() << '\n';
    } else {
      out << d.index << ": " << d.name << " [" << d.platform << "; " << d.version << "; driver " << d.driver << "]\n"
          << "   " << (d.gpu ? "GPU" : "not a GPU") << ", " << d.compute_units << " compute units, " << d.global_memory / (1024 * 1024)
          << " MiB, fp64 " << (d.fp64 ? (d.fp64_denormals ? "yes (subnormals kept)" : "yes (subnormals flushed)") : "no") << ", 64-bit atomics "
          << (d.int64_atomics ? "yes" : "no (apccd:backend=opencl needs them)") << "\n   " << verdict << "\n";
    }
  }
  if (!json)
    out << "choose one with --strategy full:backend=opencl:device=INDEX or apccd:backend=opencl:device=INDEX (default: the first GPU, else device "
           "0)\n";
  return 0;
}

int run_scenes(std::ostream& out) {
  for (const datasets::ProceduralSceneInfo& scene : datasets::procedural_scenes()) {
    out << scene.name << ": " << scene.description << "\n";
    Table table({{"  parameter"}, {"default", Table::Align::right}, {"meaning"}});
    for (const datasets::SceneParameter& parameter : scene.parameters) {
      table.add_row(
          {"  " + parameter.name,
           parameter.choices.empty() ? significant(parameter.default_value, 6) : parameter.choices[static_cast<std::size_t>(parameter.default_value)],
           parameter.description});
    }
    table.print(out);
  }
  out << "Generate one with: ccdbench generate NAME [--resolution N] [--frames N] [--seed S] [--set NAME=VALUE] --out DIR\n"
      << "or name it in a scene file: {\"generator\": {\"name\": \"flag\", \"wind\": 12}}\n";
  return 0;
}

int run_generate(const GenerateOptions& options, std::ostream& out) {
  datasets::SceneParameters parameters;
  if (options.resolution) parameters["resolution"] = *options.resolution;
  if (options.frames) parameters["frames"] = *options.frames;
  if (options.seed) parameters["seed"] = *options.seed;
  if (options.first_frame) parameters["first_frame"] = *options.first_frame;
  for (const std::string& setting : options.settings) {
    const auto equals = setting.find('=');
    if (equals == std::string::npos) throw std::invalid_argument("--set takes NAME=VALUE, got '" + setting + "'");
    const std::string value = setting.substr(equals + 1);
    const std::optional<double> parsed = parse_double(value);
    double number = parsed.value_or(0.0);
    if (!parsed) {
      const std::string name = setting.substr(0, equals);
      const auto choice = datasets::scene_parameter_choice(options.name, name, value);
      if (!choice) {
        // An unknown scene or parameter: resolve_scene_parameters says so and names the scene's parameters.
        datasets::resolve_scene_parameters(options.name, {{name, 0.0}});
        std::string choices;
        for (const datasets::ProceduralSceneInfo& info : datasets::procedural_scenes()) {
          for (const datasets::SceneParameter& parameter : info.parameters) {
            if (info.name != options.name || parameter.name != name) continue;
            for (const std::string& c : parameter.choices) choices += (choices.empty() ? "" : ", ") + c;
          }
        }
        throw std::invalid_argument("--set " + setting + ": the value must be a number" + (choices.empty() ? "" : " or one of: " + choices));
      }
      number = *choice;
    }
    parameters[setting.substr(0, equals)] = number;
  }
  Progress progress("generate " + options.name + ": frames", 0);
  std::optional<Table> measurements;
  datasets::GenerateRequest request{
      options.name, parameters, options.out, [&](std::size_t done, std::size_t total) { progress.update(done, total); }, {}};
  if (options.report) {
    request.report = [&](const datasets::FrameReport& report) {
      if (!measurements) {
        std::vector<Table::Column> columns{{"frame", Table::Align::right}};
        for (const auto& [name, value] : report.metrics) columns.push_back({name, Table::Align::right});
        measurements.emplace(std::move(columns));
      }
      std::vector<std::string> row{std::to_string(report.frame)};
      for (const auto& [name, value] : report.metrics) row.push_back(significant(value, 5));
      measurements->add_row(std::move(row));
    };
  }
  const datasets::GenerateResult result = datasets::generate_procedural_scene(request);
  if (measurements) measurements->print(out);
  out << options.name << ": " << result.frames << " frames, " << result.cloth_triangles << " cloth triangles (" << result.triangles
      << " in all), thickness " << result.thickness << ", " << (result.from_cache ? "from the cache in " : "generated in ") << std::fixed
      << std::setprecision(2) << result.seconds << " s\n  scene file: " << result.scene_file.string() << "\n";
  out.unsetf(std::ios::fixed);
  return 0;
}

}  // namespace ccd::harness
