#pragma once
/// @file
/// What the tests of the plugin boundary share (docs/DESIGN.md §10): the plugins built with the project, a scene
/// with contact, copies of plugins a test may change, and runs of ccdbench as a user types them.

#include "tests/support/cli.hpp"
#include "tests/support/test_support.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <optional>
#include <string>
#include <utility>

namespace ccd::testing {

/// A plugin built with the project (tests/plugins/, examples/).
inline std::filesystem::path plugin(const std::string& name) { return std::filesystem::path(CCDBENCH_PLUGIN_DIR) / ("lib" + name + ".so"); }

/// ASAN_OPTIONS with handle_segv=0 added, for tests whose plugins crash on purpose: a child then dies by its signal,
/// as in Release, instead of a sanitizer report (the sanitizer still watches everything else).
inline std::string without_segv_reports() {
  const char* before = std::getenv("ASAN_OPTIONS");
  return before == nullptr || *before == '\0' ? std::string("handle_segv=0") : std::string(before) + ":handle_segv=0";
}

inline std::string text_of(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

/// A test of plugins run as a user runs them: its own folder and truth cache, the scene, copies of plugins.
class PluginRuns : public ::testing::Test {
 protected:
  void SetUp() override { cache_.emplace("CCDBENCH_CACHE_DIR", (dir_ / "cache").string()); }

  /// The kinematic fold at resolution 8 (106 triangles, contact at both δ), generated once per test.
  std::filesystem::path fold() { return small_fold(dir_ / "fold8"); }

  /// A copy of a built plugin in a folder of the test's own (a test that changes a plugin's file changes its copy).
  std::filesystem::path copy_of(const std::string& name, const std::string& as = {}) {
    const std::filesystem::path folder = dir_ / "plugins";
    std::filesystem::create_directories(folder);
    const std::filesystem::path target = folder / (as.empty() ? "lib" + name + ".so" : as);
    std::filesystem::copy_file(plugin(name), target, std::filesystem::copy_options::overwrite_existing);
    return target;
  }

  /// Replaces `target` with a copy of `source`, as a build does (a new file renamed over the old one).
  static void replace(const std::filesystem::path& target, const std::filesystem::path& source) {
    const std::filesystem::path fresh = target.string() + ".new";
    std::filesystem::copy_file(source, fresh, std::filesystem::copy_options::overwrite_existing);
    std::filesystem::rename(fresh, target);
  }

  /// The wrapper plugin beside a build of the library it links (answer 1: finds every contact; 0: finds none).
  std::filesystem::path wrapper(int answer) {
    const std::filesystem::path wrapper = copy_of("broken_wrapper");
    replace(wrapper.parent_path() / "libbroken_dependency.so", plugin("broken_dependency_" + std::to_string(answer)));
    return wrapper;
  }

  /// `ccdbench ARGUMENTS --json FILE`: exit status, output and the JSON it wrote (null when none).
  std::pair<CommandResult, nlohmann::json> with_json(const std::string& arguments, const std::filesystem::path& directory = {}) {
    const std::filesystem::path json = dir_ / "out.json";
    std::filesystem::remove(json);
    CommandResult result = run_ccdbench(arguments + " --json " + quoted(json), directory);
    return {result, std::filesystem::exists(json) ? read_json(json) : nlohmann::json()};
  }

  TempDir dir_;
  std::optional<ScopedVariable> cache_;
};

}  // namespace ccd::testing
