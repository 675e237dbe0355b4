#pragma once
/// @file
/// Helpers shared by the test suites: temporary folders, small meshes, and the rule for tests that need the
/// public data (skip with a reason, or fail when CCDBENCH_REQUIRE_DATA=1).

#include "core/topology.hpp"
#include "core/vec.hpp"
#include "datasets/data_dir.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cctype>
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace ccd::testing {

/// An environment variable set for the scope (the ccdbench processes the test starts inherit it).
class ScopedVariable {
 public:
  ScopedVariable(const char* name, const std::string& value) : name_(name) {
    if (const char* before = std::getenv(name)) before_ = before;
    ::setenv(name, value.c_str(), 1);
  }
  ~ScopedVariable() { before_ ? (void)::setenv(name_, before_->c_str(), 1) : (void)::unsetenv(name_); }
  ScopedVariable(const ScopedVariable&) = delete;
  ScopedVariable& operator=(const ScopedVariable&) = delete;

 private:
  const char* name_;
  std::optional<std::string> before_;
};

/// One of `count` parts of a test's inputs: item i belongs to part i % count. A test of many inputs that is too long
/// for the sanitizer run (CI's second, on two cores, where the reference's exact path runs several times slower) is
/// instantiated once per part: every build runs every part, and the ASan test preset leaves out parts 2.. by name
/// (CMakePresets.json), so each test checks the same thing in every build type and the sanitizer run still goes
/// through the same code.
struct Part {
  std::size_t index = 0;
  std::size_t count = 1;
  bool holds(std::size_t item) const { return item % count == index; }
  /// "part1of4".
  std::string name() const { return "part" + std::to_string(index + 1) + "of" + std::to_string(count); }
};

/// Prints a part as its name (in ctest's list of test names).
inline void PrintTo(const Part& part, std::ostream* out) { *out << part.name(); }

/// The parts 1..count of a test's inputs.
inline std::vector<Part> parts(std::size_t count) {
  std::vector<Part> all;
  for (std::size_t i = 0; i < count; ++i) all.push_back({i, count});
  return all;
}

/// Names an instance of a test parametrized over parts: "part1of4".
inline std::string part_name(const ::testing::TestParamInfo<Part>& param) { return param.param.name(); }

/// A fresh folder under the system temporary directory, removed with its contents on destruction.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path operator/(const std::string& name) const { return path_ / name; }

 private:
  std::filesystem::path path_;
};

/// Writes `text` to `path` as it is (no newline added).
void write_text(const std::filesystem::path& path, const std::string& text);

/// A file's bytes as they are ("" when it cannot be read).
std::string read_text(const std::filesystem::path& path);

/// The kinematic fold at resolution 8 (106 triangles, contact at both δ) with `frames` frames, generated into
/// `folder` unless it is there already: the scene the plugin, audit and regression tests run.
std::filesystem::path small_fold(const std::filesystem::path& folder, std::size_t frames = 8);

/// An n x n vertex grid in the z = 0 plane, spacing 1, two triangles per cell: 2(n-1)^2 faces.
std::vector<Face> grid_faces(std::size_t n);
std::vector<Vec3> grid_positions(std::size_t n, double z = 0.0);
/// A closed tetrahedron (4 vertices, 4 faces, 6 edges).
std::vector<Face> tetrahedron_faces();

/// The message of the `Exception` that `call` throws; fails the test (and returns "") when it throws none.
template <class Exception, class Call>
std::string error_message(Call&& call) {
  try {
    call();
  } catch (const Exception& error) {
    return error.what();
  }
  ADD_FAILURE() << "expected an exception";
  return "";
}

/// The positive thickness the data tests use for a query: 1e-3 of the diagonal of the box around its 8 rows.
inline double small_thickness_for(const std::array<Vec3, 8>& rows) {
  Vec3 lower = rows[0], upper = lower;
  for (const Vec3& r : rows) {
    lower = lower.cwiseMin(r);
    upper = upper.cwiseMax(r);
  }
  return 1e-3 * (upper - lower).norm();
}

/// Names an instance of a test parametrized over strings by its parameter (test names allow letters, digits and
/// '_' only: "spinning-ball" becomes spinning_ball).
inline std::string param_name(const ::testing::TestParamInfo<std::string>& param) {
  std::string name = param.param;
  for (char& c : name) c = std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
  return name;
}

/// Whether CCDBENCH_REQUIRE_DATA=1: a test that would skip for lack of data fails instead (CI sets it).
bool external_data_required();

/// The external data folder, when present with the expected content; otherwise nullopt and the reason.
std::optional<std::filesystem::path> external_data_or_reason(std::string& reason);

/// How many queries the public data holds under `folder` (docs/DATA.md): data tests assert it, so that
/// a data folder that exists but is empty or partial fails instead of passing over nothing.
inline std::size_t shared_query_count(const std::string& folder) {
  if (folder == "sample-queries") return 250 + 74;
  if (folder == "scalable-ccd-sample/cloth-funnel") return 92 + 263;
  if (folder == "scalable-ccd-sample/rod-twist") return 801 + 4370;
  if (folder == "scalable-ccd-sample") return 92 + 263 + 801 + 4370;
  ADD_FAILURE() << "no expected count for " << folder;
  return 0;
}

}  // namespace ccd::testing

/// Binds `dir` to the public data folder, or skips the test saying why (fails instead under
/// CCDBENCH_REQUIRE_DATA=1, as CI sets it).
#define CCD_REQUIRE_EXTERNAL_DATA(dir)                                            \
  std::filesystem::path dir;                                                      \
  {                                                                               \
    std::string ccd_reason_;                                                      \
    const auto ccd_found_ = ::ccd::testing::external_data_or_reason(ccd_reason_); \
    if (!ccd_found_) {                                                            \
      if (::ccd::testing::external_data_required()) FAIL() << ccd_reason_;        \
      GTEST_SKIP() << ccd_reason_;                                                \
    }                                                                             \
    dir = *ccd_found_;                                                            \
  }
