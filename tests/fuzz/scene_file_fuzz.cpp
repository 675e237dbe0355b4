// Fuzz target: the scene-file reader. Built-in generators are replaced by a stub that checks their parameters as
// the real ones do and generates nothing: a fuzzed {"generator": ...} must not simulate for minutes or
// fill the cache. The scene file lives in an empty temporary folder, so relative frame paths find nothing.
#include "datasets/procedural_scenes.hpp"
#include "datasets/scene_file.hpp"
#include "tests/fuzz/fuzz_input.hpp"

#include <nlohmann/json.hpp>

#include <cstdlib>
#include <fstream>

namespace {

ccd::datasets::SceneSequence stub_generator(const std::string& name, const nlohmann::json& block, const std::filesystem::path& file) {
  ccd::datasets::SceneParameters parameters;
  for (const auto& item : block.items()) {
    if (!item.value().is_number()) throw ccd::InputError(file, "generator." + item.key(), "must be a number");
    parameters[item.key()] = item.value().get<double>();
  }
  try {
    ccd::datasets::resolve_scene_parameters(name, parameters);
  } catch (const std::invalid_argument& error) {
    throw ccd::InputError(file, "generator", error.what());
  }
  throw ccd::InputError(file, "generator", "accepted (the fuzz stub generates nothing)");
}

const std::filesystem::path& folder() {
  static const std::filesystem::path path = [] {
    std::string pattern = (std::filesystem::temp_directory_path() / "ccdbench-fuzz-XXXXXX").string();
    if (::mkdtemp(pattern.data()) == nullptr) std::abort();
    for (const std::string& name : ccd::datasets::scene_generator_names()) {
      ccd::datasets::register_scene_generator(
          name, [name](const nlohmann::json& block, const std::filesystem::path& file) { return stub_generator(name, block, file); });
    }
    return std::filesystem::path(pattern);
  }();
  return path;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::filesystem::path file = folder() / "scene.json";
  std::ofstream(file, std::ios::binary | std::ios::trunc).write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  try {
    ccd::datasets::load_scene_file(file);
  } catch (const ccd::InputError&) {
  }
  return 0;
}
