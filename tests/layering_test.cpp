// The include structure the design states (docs/DESIGN.md §2), read from the sources themselves on every test run:
// which folders a folder may see, the declared order of the layers inside datasets/, reference/ and strategies/, and
// no include cycle between the units of any folder (a unit is a file's path without its extension: foo.hpp, foo.cpp
// and foo.h are one unit). Written here, not as a CMake script: a cycle search wants a graph and a depth-first walk.

#include "ccd/config.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <regex>
#include <set>
#include <string>
#include <vector>

namespace ccd {
namespace {

const std::vector<std::string> kTopFolders = {"core", "datasets", "reference", "strategies", "harness"};

/// unit -> the units it includes ("#include \"folder/...\"" of the project's own folders).
using Graph = std::map<std::string, std::set<std::string>>;

std::string unit_of(const std::string& path) { return std::filesystem::path(path).replace_extension().generic_string(); }

Graph include_graph() {
  const std::filesystem::path root(CCDBENCH_SOURCE_DIR);
  static const std::regex include_line("^\\s*#\\s*include\\s*\"([^\"]+)\"");
  static const std::set<std::string> extensions = {".cpp", ".hpp", ".h", ".c", ".cl", ".inc"};
  Graph graph;
  for (const std::string& top : kTopFolders) {
    for (const auto& entry : std::filesystem::recursive_directory_iterator(root / top)) {
      if (!entry.is_regular_file() || extensions.count(entry.path().extension().string()) == 0) continue;
      const std::string file = std::filesystem::relative(entry.path(), root).generic_string();
      const std::string unit = unit_of(file);
      graph[unit];
      std::ifstream in(entry.path());
      for (std::string line; std::getline(in, line);) {
        std::smatch match;
        if (!std::regex_search(line, match, include_line)) continue;
        const std::string included = match[1].str();
        const std::string folder = included.substr(0, included.find('/'));
        if (std::find(kTopFolders.begin(), kTopFolders.end(), folder) == kTopFolders.end()) continue;
        if (unit_of(included) != unit) graph[unit].insert(unit_of(included));
      }
    }
  }
  return graph;
}

std::string top_of(const std::string& unit) { return unit.substr(0, unit.find('/')); }

/// Whether a layer's `pattern` is a folder's, "folder/**".
bool is_folder(const std::string& pattern) { return pattern.size() > 3 && pattern.compare(pattern.size() - 3, 3, "/**") == 0; }

/// Whether `unit` matches `pattern`: "folder/**" is everything under the folder, anything else one unit.
bool matches(const std::string& unit, const std::string& pattern) {
  if (is_folder(pattern)) return unit.rfind(pattern.substr(0, pattern.size() - 2), 0) == 0;
  return unit == pattern;
}

// The layers of each folder, lowest first: a unit may include units of its own layer or of a lower one, and every
// unit of the folder must be in one.
const std::map<std::string, std::vector<std::vector<std::string>>> kLayers = {
    {"reference",
     {{"reference/exact_pair", "reference/rational_polynomial", "reference/sign_conditions"},  // the pair and exact arithmetic
      {"reference/certified_filter", "reference/exact_decision", "reference/unit_scale"},      // the two ways to decide; the pair at unit size
      {"reference/elementary_pair"},                                                           // deciding: filter, then exact
      {"reference/face_shape", "reference/step_truth"}}},                                      // whole steps
    {"datasets",
     {{"datasets/atomic_file", "datasets/content_hash", "datasets/data_dir", "datasets/input_file", "datasets/rational", "datasets/mesh_frame",
       "datasets/mesh_frame_validate", "datasets/shapes", "datasets/shape_json", "datasets/scene_parameters", "datasets/cloth_simulator",
       "datasets/query_file", "datasets/extremes_suite"},      // files, meshes in memory, queries, simulation
      {"datasets/ply", "datasets/obj", "datasets/mesh_file"},  // mesh formats
      {"datasets/frame_source", "datasets/frame_cache", "datasets/sample_step", "datasets/scene_sequence"},  // frames of a scene
      {"datasets/procedural/**", "datasets/procedural_scenes"},                                              // built-in scenes
      {"datasets/scene_file"}}},                                                                             // scene files
    {"strategies",
     {{"strategies/narrowphase/**"},  // narrow phases and the C text both backends compile (their registry: above plugins)
      {"strategies/bvh/**"},
      {"strategies/strategy", "strategies/strategy_entry", "strategies/backend", "strategies/object_hierarchies", "strategies/face_shape",
       "strategies/separation_filter", "strategies/elementary_tests"},  // what a strategy is and shares
      {"strategies/plugin/**"},                                         // code under audit, as a narrow phase or a strategy
      {"strategies/narrowphase_registry"},                              // every narrow phase, plugins' included
      {"strategies/opencl/**", "strategies/apccd/**", "strategies/full_traversal/**", "strategies/fcl/**"},  // the strategies
      {"strategies/registry"}}}};                                                                            // every strategy

/// The layer of `unit` in its folder's declaration, or -1: the layer that names it, else the first whose
/// "folder/**" holds it (a unit named apart from its folder's layer sits where it is named).
int layer_of(const std::string& unit) {
  const auto folder = kLayers.find(top_of(unit));
  if (folder == kLayers.end()) return -1;
  const auto& layers = folder->second;
  for (std::size_t layer = 0; layer < layers.size(); ++layer) {
    if (std::find(layers[layer].begin(), layers[layer].end(), unit) != layers[layer].end()) return static_cast<int>(layer);
  }
  for (std::size_t layer = 0; layer < layers.size(); ++layer) {
    for (const std::string& pattern : layers[layer]) {
      if (matches(unit, pattern)) return static_cast<int>(layer);
    }
  }
  return -1;
}

TEST(Layering, EachFolderIncludesOnlyWhatItMaySee) {
  // core/ sees only core/; datasets/ core/ and itself; the reference never includes strategies/, nor strategies/
  // the reference; nothing below harness/ includes it.
  const std::map<std::string, std::set<std::string>> forbidden = {{"core", {"datasets", "reference", "strategies", "harness"}},
                                                                  {"datasets", {"reference", "strategies", "harness"}},
                                                                  {"reference", {"strategies", "harness"}},
                                                                  {"strategies", {"reference", "harness"}}};
  std::vector<std::string> violations;
  for (const auto& [unit, included] : include_graph()) {
    const auto rule = forbidden.find(top_of(unit));
    if (rule == forbidden.end()) continue;
    for (const std::string& other : included) {
      if (rule->second.count(top_of(other))) violations.push_back(unit + " includes " + other);
    }
  }
  EXPECT_TRUE(violations.empty()) << ::testing::PrintToString(violations);
}

TEST(Layering, EveryUnitIncludesOnlyItsLayerAndTheLayersBelow) {
  std::vector<std::string> violations;
  std::size_t checked = 0;
  for (const auto& [unit, included] : include_graph()) {
    if (kLayers.count(top_of(unit)) == 0) continue;
    const int own = layer_of(unit);
    if (own < 0) {
      violations.push_back(unit + " is in no declared layer (tests/layering_test.cpp)");
      continue;
    }
    for (const std::string& other : included) {
      if (top_of(other) != top_of(unit)) continue;
      ++checked;
      if (layer_of(other) > own)
        violations.push_back(unit + " (layer " + std::to_string(own) + ") includes " + other + " (layer " + std::to_string(layer_of(other)) + ")");
    }
  }
  EXPECT_GT(checked, 100u);  // the graph was read
  EXPECT_TRUE(violations.empty()) << ::testing::PrintToString(violations);
}

TEST(Layering, NoUnitIsNamedApartFromItsFoldersLayer) {
  // A unit named on its own in a layer other than the one its folder ("folder/**") sits in would be an exception to
  // that folder's place (as the narrow-phase registry inside narrowphase/ once was): a folder is one layer, whole.
  std::vector<std::string> exceptions;
  for (const auto& [top, layers] : kLayers) {
    for (std::size_t named_layer = 0; named_layer < layers.size(); ++named_layer) {
      for (const std::string& named : layers[named_layer]) {
        if (is_folder(named)) continue;
        for (std::size_t layer = 0; layer < layers.size(); ++layer) {
          for (const std::string& pattern : layers[layer]) {
            if (layer != named_layer && is_folder(pattern) && matches(named, pattern))
              exceptions.push_back(named + " (layer " + std::to_string(named_layer) + ") is inside " + pattern + " (layer " + std::to_string(layer) +
                                   ")");
          }
        }
      }
    }
  }
  EXPECT_TRUE(exceptions.empty()) << ::testing::PrintToString(exceptions);
}

TEST(Layering, NoIncludeCycleBetweenUnits) {
  const Graph graph = include_graph();
  // Depth-first, colouring units: a unit met again while on the path closes a cycle.
  std::map<std::string, int> state;  // 0 new, 1 on the path, 2 done
  std::vector<std::string> path, cycles;
  std::function<void(const std::string&)> visit = [&](const std::string& unit) {
    state[unit] = 1;
    path.push_back(unit);
    if (const auto it = graph.find(unit); it != graph.end()) {
      for (const std::string& next : it->second) {
        if (state[next] == 1) {
          std::string cycle;
          for (auto at = std::find(path.begin(), path.end(), next); at != path.end(); ++at) cycle += *at + " -> ";
          cycles.push_back(cycle + next);
        } else if (state[next] == 0) {
          visit(next);
        }
      }
    }
    path.pop_back();
    state[unit] = 2;
  };
  for (const auto& [unit, included] : graph) {
    if (state[unit] == 0) visit(unit);
  }
  EXPECT_TRUE(cycles.empty()) << ::testing::PrintToString(cycles);
}

}  // namespace
}  // namespace ccd
