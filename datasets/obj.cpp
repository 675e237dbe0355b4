#include "datasets/obj.hpp"

#include "core/error.hpp"
#include "datasets/atomic_file.hpp"
#include "datasets/input_file.hpp"
#include "datasets/mesh_frame_validate.hpp"

#include <charconv>
#include <fstream>
#include <iomanip>
#include <sstream>

namespace ccd::datasets {
namespace {

double parse_coordinate(const std::filesystem::path& path, std::size_t line, const std::string& token) {
  double value = 0.0;
  const auto result = std::from_chars(token.data(), token.data() + token.size(), value);
  if (result.ec != std::errc{} || result.ptr != token.data() + token.size()) {
    throw InputError(path, line_at(line), "malformed coordinate '" + token + "'");
  }
  return value;
}

/// OBJ indices are 1-based, or negative: relative to the vertices read so far (-1 is the last one).
VertexId parse_index(const std::filesystem::path& path, std::size_t line, const std::string& token, std::size_t vertices_so_far) {
  const std::string index_text = token.substr(0, token.find('/'));
  long long index = 0;
  const auto result = std::from_chars(index_text.data(), index_text.data() + index_text.size(), index);
  if (result.ec != std::errc{} || result.ptr != index_text.data() + index_text.size()) {
    throw InputError(path, line_at(line), "malformed face index '" + token + "'");
  }
  const long long zero_based = index > 0 ? index - 1 : static_cast<long long>(vertices_so_far) + index;
  if (index == 0 || zero_based < 0 || zero_based >= static_cast<long long>(vertices_so_far)) {
    throw InputError(path, line_at(line),
                     "face index " + std::to_string(index) + " out of range (" + std::to_string(vertices_so_far) + " vertices so far)");
  }
  return static_cast<VertexId>(zero_based);
}

}  // namespace

MeshFrame read_obj(const std::filesystem::path& path) {
  std::ifstream in = open_input_file(path, "OBJ file");
  MeshFrame frame;
  frame.format = "OBJ";
  std::vector<std::size_t> vertex_lines, face_lines;
  std::string line;
  for (std::size_t line_number = 1; std::getline(in, line); ++line_number) {
    std::istringstream words(line);
    std::string keyword;
    if (!(words >> keyword) || keyword[0] == '#') continue;
    std::vector<std::string> args;
    for (std::string word; words >> word;) args.push_back(word);
    if (keyword == "v") {
      if (args.size() < 3 || args.size() > 4) {
        throw InputError(path, line_at(line_number), "a vertex needs 3 coordinates (or 4 with w)");
      }
      frame.positions.emplace_back(parse_coordinate(path, line_number, args[0]), parse_coordinate(path, line_number, args[1]),
                                   parse_coordinate(path, line_number, args[2]));
      vertex_lines.push_back(line_number);
    } else if (keyword == "f") {
      if (args.size() != 3) {
        throw InputError(path, line_at(line_number),
                         "face has " + std::to_string(args.size()) +
                             " corners; ccdbench reads triangle meshes only "
                             "(triangulate it first)");
      }
      Face face{};
      for (int k = 0; k < 3; ++k) face[k] = parse_index(path, line_number, args[k], frame.positions.size());
      frame.faces.push_back(face);
      face_lines.push_back(line_number);
    }
  }
  validate_mesh_frame(
      path, frame, [&](std::size_t i) { return line_at(vertex_lines[i]); }, [&](std::size_t i) { return line_at(face_lines[i]); });
  return frame;
}

void write_obj(const std::filesystem::path& path, const MeshFrame& frame) {
  AtomicFile file(path, std::ios::out);
  std::ofstream& out = file.stream();
  out << "# written by ccdbench\n" << std::setprecision(17);
  for (const Vec3& p : frame.positions) out << "v " << p.x() << ' ' << p.y() << ' ' << p.z() << '\n';
  for (const Face& f : frame.faces) out << "f " << f[0] + 1 << ' ' << f[1] + 1 << ' ' << f[2] + 1 << '\n';
  file.commit();
}

}  // namespace ccd::datasets
