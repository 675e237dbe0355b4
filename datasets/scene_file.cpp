#include "datasets/scene_file.hpp"

#include "core/error.hpp"
#include "datasets/frame_cache.hpp"
#include "datasets/input_file.hpp"
#include "datasets/procedural_scenes.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <map>
#include <mutex>
#include <set>

namespace ccd::datasets {
namespace {

using nlohmann::json;

std::map<std::string, SceneGeneratorFunction>& generator_registry() {
  static std::map<std::string, SceneGeneratorFunction> registry;
  return registry;
}

std::mutex& generator_registry_mutex() {
  static std::mutex mutex;
  return mutex;
}

/// The built-in procedural scenes as generators: a block's parameters (numbers, or a parameter's named choices) to the
/// scene generated into the cache (procedural_scenes.hpp), read back as a scene file.
void register_builtin_generators() {
  std::lock_guard lock(generator_registry_mutex());
  for (const ProceduralSceneInfo& info : procedural_scenes()) {
    const std::string name = info.name;
    generator_registry()[name] = [name](const nlohmann::json& block, const std::filesystem::path& file) {
      SceneParameters parameters;
      for (const auto& item : block.items()) {
        if (item.value().is_string()) {
          const auto choice = scene_parameter_choice(name, item.key(), item.value().get<std::string>());
          if (!choice) throw InputError(file, "generator." + item.key(), "must be a number or one of the parameter's choices");
          parameters[item.key()] = *choice;
          continue;
        }
        if (!item.value().is_number()) throw InputError(file, "generator." + item.key(), "must be a number");
        parameters[item.key()] = item.value().get<double>();
      }
      GenerateResult generated;
      try {
        generated = generate_cached_scene(name, parameters);
      } catch (const std::invalid_argument& error) {
        throw InputError(file, "generator", error.what());
      }
      return load_scene_file(generated.scene_file);
    };
  }
}

/// The built-in procedural scenes join the registry the first time anyone looks into it.
void ensure_builtin_generators() {
  static std::once_flag once;
  std::call_once(once, register_builtin_generators);
}

/// Reports keys outside `allowed` in object `value` found at `where`.
void reject_unknown_keys(const std::filesystem::path& file, const std::string& where, const json& value,
                         std::initializer_list<std::string_view> allowed) {
  for (const auto& item : value.items()) {
    if (std::find(allowed.begin(), allowed.end(), item.key()) == allowed.end()) {
      std::string list;
      for (std::string_view key : allowed) list += (list.empty() ? "" : ", ") + std::string(key);
      throw InputError(file, where, "unknown key '" + item.key() + "' (allowed: " + list + ")");
    }
  }
}

const json& require(const std::filesystem::path& file, const std::string& where, const json& value, const char* key, json::value_t type,
                    const char* type_name) {
  if (!value.contains(key)) throw InputError(file, where, std::string("missing key '") + key + "'");
  const json& member = value.at(key);
  const bool ok = member.type() == type || (type == json::value_t::number_float && member.is_number());
  if (!ok) throw InputError(file, where + "." + key, std::string("must be ") + type_name);
  return member;
}

std::filesystem::path resolve(const std::filesystem::path& base, const std::string& text) {
  const std::filesystem::path path(text);
  return path.is_absolute() ? path : base / path;
}

std::unique_ptr<FrameSource> frame_source_from_json(const json& frames, const std::filesystem::path& base, const std::filesystem::path& file,
                                                    const std::string& where) {
  if (!frames.is_object() || frames.size() != 1) {
    throw InputError(file, where, "must be an object with exactly one of: files, pattern, directory, cache");
  }
  reject_unknown_keys(file, where, frames, {"files", "pattern", "directory", "cache"});
  const std::string key = frames.begin().key();
  const json& value = frames.begin().value();
  if (key == "files") {
    if (!value.is_array() || value.empty()) throw InputError(file, where + ".files", "must be a non-empty array");
    std::vector<std::filesystem::path> files;
    for (const json& entry : value) {
      if (!entry.is_string()) throw InputError(file, where + ".files", "entries must be strings");
      files.push_back(resolve(base, entry.get<std::string>()));
    }
    return make_file_frame_source(std::move(files));
  }
  if (!value.is_string()) throw InputError(file, where + "." + key, "must be a string");
  const std::filesystem::path path = resolve(base, value.get<std::string>());
  if (key == "cache") return open_frame_cache(path);
  return make_file_frame_source(expand_frame_files(path));
}

/// An array of three finite numbers at `where`.
Vec3 vec3_from_json(const json& value, const std::filesystem::path& file, const std::string& where) {
  if (!value.is_array() || value.size() != 3) throw InputError(file, where, "must be an array of three numbers");
  Vec3 v;
  for (int k = 0; k < 3; ++k) {
    if (!value[k].is_number()) throw InputError(file, where, "must be an array of three numbers");
    v[k] = value[k].get<double>();
    if (!std::isfinite(v[k])) throw InputError(file, where, "must be finite");
  }
  return v;
}

/// {"shape": "sphere", "radius": R} or {"shape": "box", "half_extents": [X, Y, Z]} of a shape object.
Shape shape_from_json(const json& object, const std::filesystem::path& file, const std::string& where) {
  const std::string kind = require(file, where, object, "shape", json::value_t::string, "a string").get<std::string>();
  Shape shape;
  if (kind == "sphere") {
    if (object.contains("half_extents")) throw InputError(file, where + ".half_extents", "a sphere has a radius, not half extents");
    shape.kind = ShapeKind::sphere;
    shape.radius = require(file, where, object, "radius", json::value_t::number_float, "a number").get<double>();
  } else if (kind == "box") {
    if (object.contains("radius")) throw InputError(file, where + ".radius", "a box has half extents, not a radius");
    shape.kind = ShapeKind::box;
    if (!object.contains("half_extents")) throw InputError(file, where, "missing key 'half_extents'");
    shape.half_extents = vec3_from_json(object.at("half_extents"), file, where + ".half_extents");
  } else {
    throw InputError(file, where + ".shape", "unknown shape '" + kind + "' (sphere, box)");
  }
  if (auto problem = find_shape_problem(shape)) throw InputError(file, where, *problem);
  return shape;
}

/// A shape's motion track: {"centres": [[x, y, z], ...]} (one centre: it stays still) or {"cache": "file.frames"}
/// (a frame cache of one vertex and no faces).
std::unique_ptr<FrameSource> track_from_json(const json& track, const std::filesystem::path& base, const std::filesystem::path& file,
                                             const std::string& where) {
  if (!track.is_object() || track.size() != 1) throw InputError(file, where, "must be an object with exactly one of: centres, cache");
  reject_unknown_keys(file, where, track, {"centres", "cache"});
  if (track.contains("cache")) {
    const json& value = track.at("cache");
    if (!value.is_string()) throw InputError(file, where + ".cache", "must be a string");
    return open_frame_cache(resolve(base, value.get<std::string>()));
  }
  const json& centres = track.at("centres");
  if (!centres.is_array() || centres.empty()) throw InputError(file, where + ".centres", "must be a non-empty array of [x, y, z]");
  std::vector<Vec3> points;
  for (std::size_t i = 0; i < centres.size(); ++i) {
    points.push_back(vec3_from_json(centres[i], file, where + ".centres[" + std::to_string(i) + "]"));
  }
  return make_track_frame_source(std::move(points), file.string() + ":" + where + " (" + std::to_string(points.size()) + " centres)");
}

SceneSequence scene_from_generator(const json& block, const std::filesystem::path& file) {
  if (!block.is_object()) throw InputError(file, "generator", "must be an object with a 'name'");
  const std::string name = require(file, "generator", block, "name", json::value_t::string, "a string").get<std::string>();
  ensure_builtin_generators();
  SceneGeneratorFunction generator;
  {
    std::lock_guard lock(generator_registry_mutex());
    const auto it = generator_registry().find(name);
    if (it != generator_registry().end()) generator = it->second;
  }
  if (!generator) {
    std::string known;
    for (const std::string& n : scene_generator_names()) known += (known.empty() ? "" : ", ") + n;
    throw InputError(file, "generator.name", "unknown scene generator '" + name + "' (known: " + (known.empty() ? "none" : known) + ")");
  }
  json parameters = block;
  parameters.erase("name");
  return generator(parameters, file);
}

}  // namespace

void register_scene_generator(const std::string& name, SceneGeneratorFunction generator) {
  std::lock_guard lock(generator_registry_mutex());
  generator_registry()[name] = std::move(generator);
}

std::vector<std::string> scene_generator_names() {
  ensure_builtin_generators();
  std::lock_guard lock(generator_registry_mutex());
  std::vector<std::string> names;
  for (const auto& entry : generator_registry()) names.push_back(entry.first);
  return names;
}

SceneSequence scene_from_json(const json& document, const std::filesystem::path& base, const std::filesystem::path& file) {
  if (!document.is_object()) throw InputError(file, {}, "a scene file must hold a JSON object");
  reject_unknown_keys(file, {}, document, {"name", "thickness", "objects", "collidable", "generator"});
  double thickness = 0.0;
  if (document.contains("thickness")) {
    thickness = require(file, {}, document, "thickness", json::value_t::number_float, "a number").get<double>();
  }
  if (document.contains("generator")) {
    if (document.contains("objects") || document.contains("collidable")) {
      throw InputError(file, "generator", "a generated scene declares no 'objects' or 'collidable' of its own");
    }
    SceneSequence sequence = scene_from_generator(document.at("generator"), file);
    if (document.contains("thickness")) sequence.set_thickness(thickness);
    return sequence;
  }
  const json& objects = require(file, {}, document, "objects", json::value_t::array, "an array");
  if (objects.empty()) throw InputError(file, "objects", "a scene needs at least one object");

  std::vector<ObjectDescription> descriptions;
  std::vector<std::unique_ptr<FrameSource>> sources;
  for (std::size_t i = 0; i < objects.size(); ++i) {
    const std::string where = "objects[" + std::to_string(i) + "]";
    const json& object = objects[i];
    if (!object.is_object()) throw InputError(file, where, "must be an object");
    ObjectDescription description;
    description.name = require(file, where, object, "name", json::value_t::string, "a string").get<std::string>();
    if (object.contains("kind")) {
      const std::string kind = require(file, where, object, "kind", json::value_t::string, "a string").get<std::string>();
      const auto parsed = parse_object_kind(kind);
      if (!parsed) throw InputError(file, where + ".kind", "unknown kind '" + kind + "' (deformable, rigid, static, shape)");
      description.kind = *parsed;
    }
    if (description.kind == ObjectKind::shape) {
      reject_unknown_keys(file, where, object, {"name", "kind", "shape", "radius", "half_extents", "track"});
      description.shape = shape_from_json(object, file, where);
      description.self_collision = false;
      if (!object.contains("track")) throw InputError(file, where, "missing key 'track'");
      auto source = track_from_json(object.at("track"), base, file, where + ".track");
      if (source->num_vertices() != 1 || !source->faces().empty()) {
        throw InputError(file, where + ".track", "a shape's track holds one vertex (its centre) and no faces");
      }
      description.num_vertices = 1;
      descriptions.push_back(std::move(description));
      sources.push_back(std::move(source));
      continue;
    }
    reject_unknown_keys(file, where, object, {"name", "kind", "self_collision", "frames"});
    description.self_collision = description.kind == ObjectKind::deformable;
    if (object.contains("self_collision")) {
      description.self_collision = require(file, where, object, "self_collision", json::value_t::boolean, "true or false").get<bool>();
    }
    if (!object.contains("frames")) throw InputError(file, where, "missing key 'frames'");
    auto source = frame_source_from_json(object.at("frames"), base, file, where + ".frames");
    description.num_vertices = source->num_vertices();
    description.faces = source->faces();
    descriptions.push_back(std::move(description));
    sources.push_back(std::move(source));
  }

  std::vector<std::pair<ObjectId, ObjectId>> collidable;
  auto object_index = [&](const json& name, const std::string& where) {
    if (!name.is_string()) throw InputError(file, where, "object names must be strings");
    for (ObjectId id = 0; id < descriptions.size(); ++id) {
      if (descriptions[id].name == name.get<std::string>()) return id;
    }
    throw InputError(file, where, "no object named '" + name.get<std::string>() + "'");
  };
  if (!document.contains("collidable")) {
    for (ObjectId a = 0; a < descriptions.size(); ++a) {
      for (ObjectId b = a + 1; b < descriptions.size(); ++b) collidable.emplace_back(a, b);
    }
  } else {
    const json& pairs = require(file, {}, document, "collidable", json::value_t::array, "an array of [a, b] pairs");
    for (std::size_t i = 0; i < pairs.size(); ++i) {
      const std::string where = "collidable[" + std::to_string(i) + "]";
      if (!pairs[i].is_array() || pairs[i].size() != 2) throw InputError(file, where, "must be a pair [a, b]");
      collidable.emplace_back(object_index(pairs[i][0], where), object_index(pairs[i][1], where));
    }
  }
  try {
    return SceneSequence(Scene(std::move(descriptions), std::move(collidable), thickness), std::move(sources));
  } catch (const InputError& error) {
    if (!error.file().empty()) throw;
    throw error.in_file(file);
  }
}

SceneSequence load_scene_file(const std::filesystem::path& path) {
  const std::filesystem::path file = std::filesystem::is_directory(path) ? path / "scene.json" : path;
  return scene_from_json(read_json_file(file, "scene file"), file.parent_path(), file);
}

}  // namespace ccd::datasets
