#include "harness/inspect.hpp"

#include "core/error.hpp"
#include "core/step.hpp"
#include "datasets/frame_cache.hpp"
#include "datasets/mesh_file.hpp"
#include "datasets/mesh_frame.hpp"
#include "datasets/query_file.hpp"
#include "datasets/sample_step.hpp"
#include "datasets/scene_file.hpp"
#include "datasets/shape_json.hpp"
#include "harness/progress.hpp"

#include <fstream>
#include <iomanip>
#include <ostream>

namespace ccd::harness {
namespace {

using nlohmann::json;
namespace fs = std::filesystem;

json topology_counts(const MeshTopology& topology) {
  return {{"vertices", topology.num_vertices()},
          {"unused_vertices", topology.num_unused_vertices()},
          {"faces", topology.num_faces()},
          {"edges", topology.num_edges()},
          {"boundary_edges", topology.num_boundary_edges()}};
}

/// Reads frames in order and records the largest vertex displacement of every step.
json sequence_displacements(const datasets::SceneSequence& sequence) {
  json displacements = json::array();
  Progress progress("inspect: frames", sequence.num_frames());
  std::vector<Vec3> previous = sequence.frame(0);
  for (std::size_t k = 1; k < sequence.num_frames(); ++k) {
    std::vector<Vec3> current = sequence.frame(k);
    displacements.push_back(max_displacement(previous, current));
    previous = std::move(current);
    progress.update(k + 1);
  }
  return displacements;
}

json describe_sequence(const fs::path& path, const std::string& type, const datasets::SceneSequence& sequence) {
  const Scene& scene = sequence.scene();
  json description = {{"path", path.string()}, {"type", type}, {"thickness", scene.thickness()}};
  description.update(topology_counts(scene.topology()));
  json objects = json::array();
  for (ObjectId id = 0; id < scene.objects().size(); ++id) {
    const SceneObject& object = scene.object(id);
    objects.push_back({{"name", object.name},
                       {"kind", to_string(object.kind)},
                       {"self_collision", object.self_collision},
                       {"vertices", object.num_vertices},
                       {"faces", object.num_faces},
                       {"frames", sequence.source(id).num_frames()},
                       {"source", sequence.source(id).describe()}});
    if (object.shape) datasets::put_shape_keys(objects.back(), *object.shape);
  }
  description["objects"] = objects;
  // A shape's centre is a vertex no face uses: not a stray vertex of a mesh.
  description["shape_centres"] = scene.shape_objects().size();
  json collidable = json::array();
  for (const auto& [a, b] : scene.collidable_pairs()) collidable.push_back({scene.object(a).name, scene.object(b).name});
  description["collidable"] = collidable;
  description["frames"] = sequence.num_frames();
  description["steps"] = sequence.num_steps();
  description["max_displacement"] = sequence_displacements(sequence);
  return description;
}

json describe_queries(const datasets::QueryFile& file) {
  json description = {{"path", file.path.string()},
                      {"type", "queries"},
                      {"kind", datasets::to_string(file.kind)},
                      {"queries", file.queries.size()},
                      {"not_exactly_double", file.not_exactly_double()}};
  if (file.has_truth() && !file.queries.empty()) {
    description["positives"] = file.positives();
    description["truth_source"] = file.truth_file ? file.truth_file->string() : "column 7";
  } else {
    description["positives"] = nullptr;
    description["truth_source"] = nullptr;
  }
  return description;
}

json describe_query_directory(const fs::path& path, const std::vector<fs::path>& files) {
  json entries = json::array();
  std::size_t queries = 0, positives = 0;
  bool all_have_truth = true;
  for (const fs::path& file : files) {
    const datasets::QueryFile query_file = datasets::read_query_file(file);
    entries.push_back(describe_queries(query_file));
    queries += query_file.queries.size();
    positives += query_file.positives();
    all_have_truth = all_have_truth && query_file.has_truth();
  }
  json description = {{"path", path.string()}, {"type", "query_directory"}, {"files", entries}, {"queries", queries}};
  description["positives"] = all_have_truth ? json(positives) : json(nullptr);
  return description;
}

json describe_sample_step(const fs::path& path) {
  const datasets::SampleStep step = datasets::load_sample_step(path);
  json description = {{"path", path.string()},
                      {"type", "sample_step"},
                      {"step", step.step},
                      {"frames", {step.frame0_file.string(), step.frame1_file.string()}},
                      {"steps", 1}};
  description.update(topology_counts(step.topology));
  description["vf_candidates"] = step.vertex_face_candidates.size();
  description["ee_candidates"] = step.edge_edge_candidates.size();
  description["vf_queries"] = describe_queries(step.vertex_face_queries);
  description["ee_queries"] = describe_queries(step.edge_edge_queries);
  description["max_displacement"] = json::array({max_displacement(step.x0, step.x1)});
  return description;
}

bool looks_like_frame_cache(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  char magic[8] = {};
  return in.read(magic, 8) && std::string(magic, 8) == "CCDBFRM1";
}

bool has_csv_files(const fs::path& directory) {
  for (const auto& entry : fs::recursive_directory_iterator(directory)) {
    if (entry.is_regular_file() && entry.path().extension() == ".csv") return true;
  }
  return false;
}

}  // namespace

json inspect_path(const fs::path& path) {
  if (fs::is_directory(path)) {
    if (fs::exists(path / "scene.json")) return describe_sequence(path, "scene", datasets::load_scene_file(path));
    if (datasets::is_sample_step_directory(path)) return describe_sample_step(path);
    if (has_csv_files(path)) return describe_query_directory(path, datasets::discover_query_files({path}));
    return describe_sequence(path, "frames", datasets::scene_from_frame_files(datasets::expand_frame_files(path), 0.0));
  }
  const std::string text = path.string();
  if (!fs::exists(path)) {
    if (text.find('%') != std::string::npos) {
      return describe_sequence(path, "frames", datasets::scene_from_frame_files(datasets::expand_frame_files(path), 0.0));
    }
    throw InputError(path, {}, "no such file or directory");
  }
  const std::string extension = path.extension().string();
  const std::string name = path.filename().string();
  if (extension == ".ply" || extension == ".obj" || extension == ".PLY" || extension == ".OBJ") {
    const datasets::MeshFrame frame = datasets::read_mesh(path);
    json description = {{"path", text}, {"type", "mesh"}, {"format", frame.format}};
    description.update(topology_counts(MeshTopology(frame.positions.size(), frame.faces)));
    return description;
  }
  if (extension == ".csv") return describe_queries(datasets::read_query_file(path));
  if (extension == ".json") {
    if (path.parent_path().filename() == "mma_bool" || name.ends_with("_mma_bool.json")) {
      const std::vector<bool> truth = datasets::read_truth_file(path);
      return {{"path", text},
              {"type", "truth"},
              {"entries", truth.size()},
              {"positives", static_cast<std::size_t>(std::count(truth.begin(), truth.end(), true))}};
    }
    if (path.parent_path().filename() == "boxes") {
      const auto pairs = datasets::read_candidate_pairs(path);
      const bool vertex_face = name.ends_with("vf.json");
      return {{"path", text},
              {"type", "candidates"},
              {"kind", vertex_face                 ? "vertex-face"
                       : name.ends_with("ee.json") ? "edge-edge"
                                                   : "unknown"},
              {"pairs", pairs.size()}};
    }
    return describe_sequence(path, "scene", datasets::load_scene_file(path));
  }
  if (looks_like_frame_cache(path)) {
    const auto source = datasets::open_frame_cache(path);
    json description = {{"path", text}, {"type", "frame_cache"}, {"key", datasets::frame_cache_key(path)}, {"frames", source->num_frames()}};
    description.update(topology_counts(MeshTopology(source->num_vertices(), source->faces())));
    return description;
  }
  throw InputError(path, {},
                   "not a ccdbench input (expected a mesh, query, truth, candidate, scene or frame-cache "
                   "file, or a directory of those)");
}

namespace {

void print_topology(const json& d, std::ostream& out, const std::string& indent) {
  const std::size_t centres = d.value("shape_centres", std::size_t{0});
  out << indent << "vertices " << d["vertices"] << " (unused " << d["unused_vertices"].get<std::size_t>() - centres;
  if (centres > 0) out << ", and " << centres << " shape centre" << (centres == 1 ? "" : "s");
  out << "), faces " << d["faces"] << ", edges " << d["edges"] << " (boundary " << d["boundary_edges"] << ")\n";
}

void print_queries(const json& d, std::ostream& out, const std::string& indent) {
  out << indent << d["path"].get<std::string>() << ": " << d["kind"].get<std::string>() << ", queries " << d["queries"];
  if (d["positives"].is_null()) {
    out << ", truth: none";
  } else {
    out << ", positives " << d["positives"] << " (truth: " << d["truth_source"].get<std::string>() << ")";
  }
  out << ", not exactly double " << d["not_exactly_double"] << "\n";
}

void print_displacements(const json& d, std::ostream& out, const std::string& indent) {
  const json& steps = d["max_displacement"];
  out << indent << "largest displacement per step:";
  const std::size_t shown = std::min<std::size_t>(steps.size(), 20);
  for (std::size_t k = 0; k < shown; ++k) out << ' ' << std::setprecision(6) << steps[k].get<double>();
  if (shown < steps.size()) out << " ... (" << steps.size() << " steps; --json lists all)";
  out << "\n";
}

}  // namespace

void print_inspection(const json& d, std::ostream& out) {
  const std::string type = d["type"];
  if (type == "queries") return print_queries(d, out, "");
  out << d["path"].get<std::string>() << ": " << type << "\n";
  if (type == "mesh") {
    out << "  format " << d["format"].get<std::string>() << "\n";
    print_topology(d, out, "  ");
  } else if (type == "frames" || type == "scene") {
    print_topology(d, out, "  ");
    out << "  frames " << d["frames"] << ", steps " << d["steps"] << ", thickness " << d["thickness"] << "\n";
    for (const json& object : d["objects"]) {
      out << "  object " << object["name"].get<std::string>() << ": " << object["kind"].get<std::string>();
      if (object.contains("shape")) {
        out << " (" << object["shape"].get<std::string>();
        if (object.contains("radius")) out << ", radius " << object["radius"];
        if (object.contains("half_extents")) out << ", half extents " << object["half_extents"].dump();
        out << "), centre per frame";
      } else {
        out << ", self-collision " << (object["self_collision"].get<bool>() ? "on" : "off") << ", vertices " << object["vertices"] << ", faces "
            << object["faces"];
      }
      out << ", frames " << object["frames"] << " (" << object["source"].get<std::string>() << ")\n";
    }
    for (const json& pair : d["collidable"]) {
      out << "  collidable " << pair[0].get<std::string>() << " <-> " << pair[1].get<std::string>() << "\n";
    }
    print_displacements(d, out, "  ");
  } else if (type == "sample_step") {
    out << "  step " << d["step"].get<std::string>() << ": " << d["frames"][0].get<std::string>() << " -> " << d["frames"][1].get<std::string>()
        << "\n";
    print_topology(d, out, "  ");
    out << "  candidates: vertex-face " << d["vf_candidates"] << ", edge-edge " << d["ee_candidates"] << "\n";
    print_queries(d["vf_queries"], out, "  ");
    print_queries(d["ee_queries"], out, "  ");
    print_displacements(d, out, "  ");
  } else if (type == "query_directory") {
    for (const json& file : d["files"]) print_queries(file, out, "  ");
    out << "  total: queries " << d["queries"] << ", positives " << d["positives"] << "\n";
  } else if (type == "truth") {
    out << "  entries " << d["entries"] << ", positives " << d["positives"] << "\n";
  } else if (type == "candidates") {
    out << "  " << d["kind"].get<std::string>() << " candidate pairs " << d["pairs"] << "\n";
  } else if (type == "frame_cache") {
    out << "  key " << d["key"].get<std::string>() << "\n  frames " << d["frames"] << "\n";
    print_topology(d, out, "  ");
  }
}

}  // namespace ccd::harness
