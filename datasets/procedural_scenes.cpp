#include "datasets/procedural_scenes.hpp"

#include "core/error.hpp"
#include "core/scene.hpp"
#include "datasets/atomic_file.hpp"
#include "datasets/cloth_simulator.hpp"
#include "datasets/frame_cache.hpp"
#include "datasets/ply.hpp"
#include "datasets/procedural/scene_setup.hpp"
#include "datasets/shape_json.hpp"

#include <nlohmann/json.hpp>

#include <unistd.h>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <iomanip>
#include <iostream>
#include <random>
#include <sstream>
#include <stdexcept>
#include <system_error>

namespace ccd::datasets {
namespace {

using procedural::CommonParameters;
using procedural::OutputObject;
using procedural::SceneDefinition;
using procedural::Setup;

/// Bumped whenever the simulator or a scene changes what it generates, so old caches are not reused.
constexpr int kGeneratorVersion = 3;

const std::vector<SceneDefinition>& definitions() { return procedural::scene_definitions(); }

const SceneDefinition& find_definition(const std::string& name) {
  for (const SceneDefinition& d : definitions()) {
    if (d.info.name == name) return d;
  }
  std::string known;
  for (const SceneDefinition& d : definitions()) known += (known.empty() ? "" : ", ") + d.info.name;
  throw std::invalid_argument("unknown scene '" + name + "' (built-in: " + known + ")");
}

SceneParameters resolve_parameters(const ProceduralSceneInfo& info, const SceneParameters& given) {
  SceneParameters resolved;
  for (const SceneParameter& parameter : info.parameters) resolved[parameter.name] = parameter.default_value;
  for (const auto& [name, value] : given) {
    if (!resolved.count(name)) {
      std::string known;
      for (const SceneParameter& parameter : info.parameters) known += (known.empty() ? "" : ", ") + parameter.name;
      throw std::invalid_argument("scene '" + info.name + "' has no parameter '" + name + "' (it has: " + known + ")");
    }
    if (!std::isfinite(value)) throw std::invalid_argument("parameter '" + name + "' must be finite");
    resolved[name] = value;
  }
  auto require_integer = [&](const char* name, double low, double high) {
    const double value = resolved.at(name);
    if (value != std::floor(value) || value < low || value > high) {
      std::ostringstream message;
      message << "parameter '" << name << "' must be an integer in [" << low << ", " << high << "], got " << value;
      throw std::invalid_argument(message.str());
    }
  };
  require_integer("resolution", 3, 4096);
  require_integer("frames", 2, 100000);
  require_integer("seed", 0, 9007199254740992.0);
  require_integer("steps_per_frame", 1, 64);
  require_integer("first_frame", 0, resolved.at("frames") - 2);
  for (const SceneParameter& parameter : info.parameters) {
    if (!parameter.choices.empty()) require_integer(parameter.name.c_str(), 0, static_cast<double>(parameter.choices.size() - 1));
  }
  if (resolved.count("count")) require_integer("count", 1, 64);
  return resolved;
}

/// "wind=1e+06 (default 8), frames=400 (default 30)": the parameters a user changed, for messages.
std::string changed_parameters(const ProceduralSceneInfo& info, const SceneParameters& parameters) {
  std::ostringstream text;
  for (const SceneParameter& parameter : info.parameters) {
    const double value = parameters.at(parameter.name);
    if (value == parameter.default_value) continue;
    text << (text.tellp() > 0 ? ", " : "") << parameter.name << "=" << value << " (default " << parameter.default_value << ")";
  }
  return text.tellp() > 0 ? text.str() : "every parameter at its default";
}

/// Refuses, before anything is allocated, a scene whose simulation would not fit this machine's memory or whose
/// frames would not fit the output's disk (resolution 4096 with 64 cloths would otherwise end in std::bad_alloc).
/// The simulator keeps about kSimulatorBytesPerVertex per cloth vertex (positions, velocities, constraints and
/// their colour groups, repulsion cells); each frame is written twice (cache and PLY), 24 bytes per vertex each.
void check_scene_fits(const ProceduralSceneInfo& info, const SceneParameters& parameters, const std::filesystem::path& out) {
  constexpr double kSimulatorBytesPerVertex = 1024;
  constexpr double kFrameBytesPerVertex = 2 * 3 * sizeof(double);
  const double n = parameters.at("resolution");
  const double cloths = parameters.count("count") ? parameters.at("count") : 1.0;
  const double vertices = n * n * cloths;
  const double memory = static_cast<double>(::sysconf(_SC_PHYS_PAGES)) * static_cast<double>(::sysconf(_SC_PAGESIZE));
  constexpr double kGiB = 1024.0 * 1024.0 * 1024.0;
  std::ostringstream message;
  message << std::setprecision(3);
  if (memory > 0 && vertices * kSimulatorBytesPerVertex > memory) {
    message << "scene '" << info.name << "' with " << changed_parameters(info, parameters) << " needs about "
            << vertices * kSimulatorBytesPerVertex / kGiB << " GiB to simulate; this machine has " << memory / kGiB << " GiB";
    throw std::invalid_argument(message.str());
  }
  std::error_code error;
  std::filesystem::path existing = out;
  while (!existing.empty() && !std::filesystem::exists(existing, error)) existing = existing.parent_path();
  const auto space = std::filesystem::space(existing.empty() ? std::filesystem::path(".") : existing, error);
  const double frame_bytes = vertices * kFrameBytesPerVertex * parameters.at("frames");
  if (!error && frame_bytes > static_cast<double>(space.available)) {
    message << "scene '" << info.name << "' with " << changed_parameters(info, parameters) << " needs about " << frame_bytes / kGiB
            << " GiB for its frames; " << out.string() << " has " << static_cast<double>(space.available) / kGiB << " GiB free";
    throw std::invalid_argument(message.str());
  }
}

std::string cache_key(const std::string& name, const SceneParameters& parameters) {
  std::ostringstream key;
  key << "ccdbench procedural v" << kGeneratorVersion << ' ' << name << std::setprecision(17);
  for (const auto& [parameter, value] : parameters) {
    // steps_per_frame=1 (the default) is left out, so that the scenes generated before it existed keep their key.
    if (parameter == "steps_per_frame" && value == 1) continue;
    if (parameter == "first_frame" && value == 0) continue;  // likewise first_frame=0
    if (parameter == "obstacles" && value == 0) continue;    // likewise obstacles=mesh
    key << ' ' << parameter << '=' << value;
  }
  return key.str();
}

std::filesystem::path frame_file(const std::filesystem::path& out, const std::string& object, std::size_t frame) {
  std::ostringstream name;
  name << "frame_" << std::setw(4) << std::setfill('0') << frame << ".ply";
  return out / object / name.str();
}

std::size_t frames_of(const OutputObject& object, std::size_t frames) {
  return object.kind == ObjectKind::static_object || object.still ? 1 : frames;
}

void write_scene_json(const std::filesystem::path& out, const std::string& name, const Setup& setup) {
  nlohmann::json objects = nlohmann::json::array();
  for (const OutputObject& object : setup.objects) {
    if (object.shape) {
      nlohmann::json entry = {{"name", object.name}, {"kind", "shape"}, {"track", {{"cache", "cache/" + object.name + ".frames"}}}};
      put_shape_keys(entry, *object.shape);
      objects.push_back(entry);
      continue;
    }
    nlohmann::json frames = object.kind == ObjectKind::static_object ? nlohmann::json{{"files", {object.name + "/frame_0000.ply"}}}
                                                                     : nlohmann::json{{"pattern", object.name + "/frame_%04d.ply"}};
    objects.push_back(
        {{"name", object.name}, {"kind", std::string(to_string(object.kind))}, {"self_collision", object.self_collision}, {"frames", frames}});
  }
  nlohmann::json collidable = nlohmann::json::array();
  for (const auto& [a, b] : setup.collidable) collidable.push_back({a, b});
  const nlohmann::json document = {{"name", name}, {"thickness", setup.thickness}, {"objects", objects}, {"collidable", collidable}};
  write_json_file(out / "scene.json", document);
}

/// Whether `out` holds this generation whole: caches with the key, every PLY, and scene.json (written last). The
/// caches it opened (each verified whole) go into `opened`, in the objects' order.
bool complete_in(const std::filesystem::path& out, const Setup& setup, const std::string& key, std::size_t frames,
                 std::vector<std::unique_ptr<FrameSource>>& opened) {
  if (!std::filesystem::exists(out / "scene.json")) return false;
  for (const OutputObject& object : setup.objects) {
    try {
      std::optional<std::unique_ptr<FrameSource>> cache = open_frame_cache(out / "cache" / (object.name + ".frames"), key);
      if (!cache) return false;
      opened.push_back(std::move(*cache));
    } catch (const InputError& corrupt) {
      // A corrupt or old cache is never used: the scene is generated again over it.
      std::cerr << "ccdbench: warning: " << corrupt.what() << "; the scene is generated again\n";
      return false;
    }
    const std::size_t count = frames_of(object, frames);
    if (object.shape) continue;  // a shape's track is its cache; it has no PLY frames
    if (!std::filesystem::exists(frame_file(out, object.name, count - 1)) || std::filesystem::exists(frame_file(out, object.name, count))) {
      return false;
    }
  }
  return true;
}

}  // namespace

const std::vector<ProceduralSceneInfo>& procedural_scenes() {
  static const std::vector<ProceduralSceneInfo> infos = [] {
    std::vector<ProceduralSceneInfo> result;
    for (const SceneDefinition& d : definitions()) result.push_back(d.info);
    return result;
  }();
  return infos;
}

std::optional<double> scene_parameter_choice(const std::string& scene, const std::string& parameter, const std::string& text) {
  for (const SceneParameter& p : find_definition(scene).info.parameters) {
    if (p.name != parameter) continue;
    for (std::size_t i = 0; i < p.choices.size(); ++i) {
      if (p.choices[i] == text) return static_cast<double>(i);
    }
  }
  return std::nullopt;
}

SceneParameters resolve_scene_parameters(const std::string& name, const SceneParameters& given) {
  return resolve_parameters(find_definition(name).info, given);
}

GenerateResult generate_procedural_scene(const GenerateRequest& request) {
  const auto start = std::chrono::steady_clock::now();
  const SceneDefinition& definition = find_definition(request.name);
  const SceneParameters parameters = resolve_parameters(definition.info, request.parameters);
  check_scene_fits(definition.info, parameters, request.out);
  CommonParameters common{static_cast<std::size_t>(parameters.at("resolution")), static_cast<std::size_t>(parameters.at("frames")),
                          std::mt19937_64(static_cast<std::uint64_t>(parameters.at("seed"))),
                          static_cast<std::size_t>(parameters.at("steps_per_frame"))};
  Setup setup = definition.build(common, parameters);
  const std::string key = cache_key(request.name, parameters);
  // Every CCD step is 1/steps_per_frame of a simulated frame; the emitted frames are the simulator's states at
  // those times.
  const std::size_t parts = common.steps_per_frame;
  const std::size_t emitted = (common.frames - 1) * parts + 1;
  // Frames before first_frame are simulated but not written; the written ones are numbered from 0.
  const std::size_t first_written = static_cast<std::size_t>(parameters.at("first_frame")) * parts;
  const std::size_t written = emitted - first_written;
  const double frame_seconds = SimulatorSettings{}.frame_seconds;
  auto time_of = [&](std::size_t frame) { return static_cast<double>(frame) * frame_seconds / static_cast<double>(parts); };
  // One process generates a folder at a time; another one waits, then finds it complete.
  std::filesystem::create_directories(request.out);
  const FileLock lock(request.out / ".generate.lock");

  GenerateResult result;
  result.scene_file = request.out / "scene.json";
  result.frames = written;
  result.thickness = setup.thickness;
  result.cloth_triangles = 0;
  for (const OutputObject& object : setup.objects) {
    result.triangles += object.faces.size();
    if (object.kind == ObjectKind::deformable) result.cloth_triangles += object.faces.size();
  }
  std::vector<std::unique_ptr<FrameSource>> caches;
  result.from_cache = complete_in(request.out, setup, key, written, caches);
  if (!result.from_cache) {
    caches.clear();
    std::filesystem::remove(request.out / "scene.json");
    std::vector<std::unique_ptr<FrameCacheWriter>> writers;
    for (const OutputObject& object : setup.objects) {
      writers.push_back(
          std::make_unique<FrameCacheWriter>(request.out / "cache" / (object.name + ".frames"), key, object.num_vertices, object.faces));
    }
    for (std::size_t frame = 0; frame < emitted; ++frame) {
      if (frame > 0) setup.simulator->step_fraction(static_cast<int>(parts));
      const double time = time_of(frame);
      std::vector<std::vector<Vec3>> positions;
      for (std::size_t k = 0; k < setup.objects.size(); ++k) {
        positions.push_back(setup.objects[k].positions(*setup.simulator, time));
        for (const Vec3& v : positions.back()) {
          if (!v.allFinite()) {
            throw std::invalid_argument("the simulation of '" + request.name + "' diverged at frame " + std::to_string(frame) +
                                        " (non-finite positions of object '" + setup.objects[k].name + "') with " +
                                        changed_parameters(definition.info, parameters) +
                                        ": a parameter is outside the range where the simulator is stable");
          }
        }
        if (frame >= first_written && frame - first_written < frames_of(setup.objects[k], written)) writers[k]->append(positions.back());
      }
      if (request.report && frame >= first_written) request.report({frame - first_written, setup.report(frame - first_written, time, positions)});
      if (request.progress) request.progress(frame + 1, emitted);
    }
    for (auto& writer : writers) writer->finish();
    // The caches just written, read back and verified as any reader of them would.
    for (const OutputObject& object : setup.objects) caches.push_back(open_frame_cache(request.out / "cache" / (object.name + ".frames")));
  }
  if (result.from_cache && request.report) {
    for (std::size_t frame = 0; frame < written; ++frame) {
      std::vector<std::vector<Vec3>> positions;
      for (const auto& cache : caches) positions.push_back(cache->frame(std::min(frame, cache->num_frames() - 1)));
      request.report({frame, setup.report(frame, time_of(frame + first_written), positions)});
    }
  }
  if (!result.from_cache) {
    for (std::size_t k = 0; k < setup.objects.size(); ++k) {
      const OutputObject& object = setup.objects[k];
      std::filesystem::remove_all(request.out / object.name);  // no stale frames beyond this count
      if (object.shape) continue;
      for (std::size_t frame = 0; frame < caches[k]->num_frames(); ++frame) {
        write_ply(frame_file(request.out, object.name, frame), {caches[k]->frame(frame), object.faces, ""});
      }
    }
    write_scene_json(request.out, request.name, setup);
  }
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

std::filesystem::path procedural_cache_root() {
  if (const char* dir = std::getenv("CCDBENCH_CACHE_DIR"); dir && *dir) return dir;
  if (const char* dir = std::getenv("XDG_CACHE_HOME"); dir && *dir) return std::filesystem::path(dir) / "ccdbench";
  if (const char* home = std::getenv("HOME"); home && *home) return std::filesystem::path(home) / ".cache" / "ccdbench";
  return std::filesystem::temp_directory_path() / "ccdbench-cache";
}

GenerateResult generate_cached_scene(const std::string& name, const SceneParameters& given) {
  const SceneParameters resolved = resolve_parameters(find_definition(name).info, given);
  // FNV-1a of the key names the folder: stable across runs and machines, unlike std::hash.
  std::uint64_t hash = 14695981039346656037ull;
  for (char ch : cache_key(name, resolved)) hash = (hash ^ static_cast<unsigned char>(ch)) * 1099511628211ull;
  std::ostringstream folder;
  folder << name << '-' << std::hex << std::setw(16) << std::setfill('0') << hash;
  return generate_procedural_scene({name, resolved, procedural_cache_root() / folder.str(), {}, {}});
}

}  // namespace ccd::datasets