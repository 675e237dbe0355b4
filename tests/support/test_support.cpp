#include "tests/support/test_support.hpp"

#include "datasets/procedural_scenes.hpp"

#include <cstdlib>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string_view>

namespace ccd::testing {

TempDir::TempDir() {
  std::string pattern = (std::filesystem::temp_directory_path() / "ccdbench-test-XXXXXX").string();
  if (::mkdtemp(pattern.data()) == nullptr) throw std::runtime_error("mkdtemp failed");
  path_ = pattern;
}

TempDir::~TempDir() {
  std::error_code ignored;
  std::filesystem::remove_all(path_, ignored);
}

void write_text(const std::filesystem::path& path, const std::string& text) {
  std::filesystem::create_directories(path.parent_path());
  std::ofstream out(path, std::ios::binary);
  out << text;
}

std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

std::filesystem::path small_fold(const std::filesystem::path& folder, std::size_t frames) {
  if (!std::filesystem::exists(folder)) {
    datasets::SceneParameters parameters;
    parameters["resolution"] = 8;
    parameters["frames"] = static_cast<double>(frames);
    datasets::generate_procedural_scene({"fold", parameters, folder, {}, {}});
  }
  return folder;
}

std::vector<Face> grid_faces(std::size_t n) {
  std::vector<Face> faces;
  for (std::size_t i = 0; i + 1 < n; ++i) {
    for (std::size_t j = 0; j + 1 < n; ++j) {
      const auto a = static_cast<VertexId>(i * n + j);
      const auto b = static_cast<VertexId>(a + 1);
      const auto c = static_cast<VertexId>(a + n);
      const auto d = static_cast<VertexId>(c + 1);
      faces.push_back({a, b, d});
      faces.push_back({a, d, c});
    }
  }
  return faces;
}

std::vector<Vec3> grid_positions(std::size_t n, double z) {
  std::vector<Vec3> positions;
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t j = 0; j < n; ++j) positions.emplace_back(static_cast<double>(j), static_cast<double>(i), z);
  }
  return positions;
}

std::vector<Face> tetrahedron_faces() { return {{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {0, 3, 2}}; }

bool external_data_required() {
  const char* value = std::getenv("CCDBENCH_REQUIRE_DATA");
  return value != nullptr && std::string_view(value) == "1";
}

std::optional<std::filesystem::path> external_data_or_reason(std::string& reason) {
  const auto dir = datasets::external_data_dir();
  if (!dir) {
    reason = "needs the public data (docs/DATA.md), not found: run scripts/fetch-data.sh, or set CCDBENCH_DATA_DIR to a copy";
    return std::nullopt;
  }
  if (!std::filesystem::is_directory(*dir / "sample-queries") || !std::filesystem::is_directory(*dir / "scalable-ccd-sample")) {
    reason = "needs the public data (docs/DATA.md): " + dir->string() +
             " lacks sample-queries/ or scalable-ccd-sample/; run scripts/fetch-data.sh, or set CCDBENCH_DATA_DIR to a copy";
    return std::nullopt;
  }
  return dir;
}

}  // namespace ccd::testing
