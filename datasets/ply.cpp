#include "datasets/ply.hpp"

#include "core/error.hpp"
#include "datasets/atomic_file.hpp"
#include "datasets/input_file.hpp"
#include "datasets/mesh_frame_validate.hpp"

#include <bit>
#include <charconv>
#include <cstring>
#include <fstream>
#include <iomanip>
#include <optional>
#include <sstream>

namespace ccd::datasets {
namespace {

enum class PlyType { int8, uint8, int16, uint16, int32, uint32, float32, float64 };

std::optional<PlyType> parse_ply_type(std::string_view name) {
  struct Entry {
    std::string_view name;
    PlyType type;
  };
  static constexpr Entry kTypes[] = {
      {"char", PlyType::int8},     {"int8", PlyType::int8},       {"uchar", PlyType::uint8},    {"uint8", PlyType::uint8},
      {"short", PlyType::int16},   {"int16", PlyType::int16},     {"ushort", PlyType::uint16},  {"uint16", PlyType::uint16},
      {"int", PlyType::int32},     {"int32", PlyType::int32},     {"uint", PlyType::uint32},    {"uint32", PlyType::uint32},
      {"float", PlyType::float32}, {"float32", PlyType::float32}, {"double", PlyType::float64}, {"float64", PlyType::float64}};
  for (const Entry& entry : kTypes) {
    if (entry.name == name) return entry.type;
  }
  return std::nullopt;
}

std::size_t type_size(PlyType type) {
  switch (type) {
    case PlyType::int8:
    case PlyType::uint8: return 1;
    case PlyType::int16:
    case PlyType::uint16: return 2;
    case PlyType::int32:
    case PlyType::uint32:
    case PlyType::float32: return 4;
    case PlyType::float64: return 8;
  }
  return 0;
}

bool is_integer(PlyType type) { return type != PlyType::float32 && type != PlyType::float64; }

struct PlyProperty {
  std::string name;
  PlyType type = PlyType::float64;
  bool is_list = false;
  PlyType count_type = PlyType::uint8;
};

struct PlyElement {
  std::string name;
  std::size_t count = 0;
  std::vector<PlyProperty> properties;
};

struct PlyHeader {
  PlyEncoding encoding = PlyEncoding::ascii;
  std::vector<PlyElement> elements;
  std::size_t body_offset = 0;      // bytes
  std::size_t body_first_line = 0;  // 1-based line number of the first body line (ASCII)
};

std::vector<std::string> split_words(const std::string& line) {
  std::istringstream in(line);
  std::vector<std::string> words;
  for (std::string word; in >> word;) words.push_back(word);
  return words;
}

PlyHeader parse_header(const std::filesystem::path& path, std::istream& in) {
  PlyHeader header;
  std::string line;
  std::size_t line_number = 0;
  bool saw_format = false;
  auto next_line = [&]() -> bool {
    if (!std::getline(in, line)) return false;
    ++line_number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    return true;
  };
  if (!next_line() || line != "ply") throw InputError(path, line_at(1), "not a PLY file (first line is not 'ply')");
  while (true) {
    if (!next_line()) throw InputError(path, line_at(line_number), "header ends without 'end_header'");
    const auto words = split_words(line);
    if (words.empty() || words[0] == "comment" || words[0] == "obj_info") continue;
    if (words[0] == "end_header") break;
    if (words[0] == "format") {
      if (words.size() != 3) throw InputError(path, line_at(line_number), "malformed format line");
      if (words[1] == "ascii")
        header.encoding = PlyEncoding::ascii;
      else if (words[1] == "binary_little_endian")
        header.encoding = PlyEncoding::binary_little_endian;
      else if (words[1] == "binary_big_endian")
        header.encoding = PlyEncoding::binary_big_endian;
      else
        throw InputError(path, line_at(line_number), "unknown PLY format '" + words[1] + "'");
      saw_format = true;
    } else if (words[0] == "element") {
      std::size_t count = 0;
      const bool whole_number = words.size() == 3 && [&] {
        const auto parsed = std::from_chars(words[2].data(), words[2].data() + words[2].size(), count);
        return parsed.ec == std::errc{} && parsed.ptr == words[2].data() + words[2].size();
      }();
      if (!whole_number) {
        throw InputError(path, line_at(line_number), "malformed element line: '" + line + "'");
      }
      header.elements.push_back({words[1], count, {}});
    } else if (words[0] == "property") {
      if (header.elements.empty()) throw InputError(path, line_at(line_number), "property before any element");
      PlyProperty property;
      if (words.size() == 5 && words[1] == "list") {
        const auto count_type = parse_ply_type(words[2]);
        const auto item_type = parse_ply_type(words[3]);
        if (!count_type || !item_type || !is_integer(*count_type)) {
          throw InputError(path, line_at(line_number), "malformed list property: '" + line + "'");
        }
        property = {words[4], *item_type, true, *count_type};
      } else if (words.size() == 3) {
        const auto type = parse_ply_type(words[1]);
        if (!type) throw InputError(path, line_at(line_number), "unknown property type '" + words[1] + "'");
        property = {words[2], *type, false, PlyType::uint8};
      } else {
        throw InputError(path, line_at(line_number), "malformed property line: '" + line + "'");
      }
      header.elements.back().properties.push_back(property);
    } else {
      throw InputError(path, line_at(line_number), "unexpected header line: '" + line + "'");
    }
  }
  if (!saw_format) throw InputError(path, line_at(line_number), "header has no format line");
  header.body_offset = static_cast<std::size_t>(in.tellg());
  header.body_first_line = line_number + 1;
  return header;
}

/// Where in the element list the mesh lives.
struct MeshLayout {
  std::size_t vertex_element = 0;
  std::size_t face_element = 0;
  int axis_property[3] = {-1, -1, -1};
  int index_property = -1;
};

MeshLayout find_mesh_layout(const std::filesystem::path& path, const PlyHeader& header) {
  MeshLayout layout;
  std::optional<std::size_t> vertex, face;
  for (std::size_t e = 0; e < header.elements.size(); ++e) {
    if (header.elements[e].name == "vertex") vertex = e;
    if (header.elements[e].name == "face") face = e;
  }
  if (!vertex) throw InputError(path, "header", "no 'vertex' element");
  layout.vertex_element = *vertex;
  const auto& vertex_properties = header.elements[*vertex].properties;
  static constexpr const char* kAxis[3] = {"x", "y", "z"};
  for (int k = 0; k < 3; ++k) {
    for (std::size_t p = 0; p < vertex_properties.size(); ++p) {
      if (vertex_properties[p].name == kAxis[k] && !vertex_properties[p].is_list) layout.axis_property[k] = static_cast<int>(p);
    }
    if (layout.axis_property[k] < 0) {
      throw InputError(path, "header", std::string("vertex element has no '") + kAxis[k] + "' property");
    }
  }
  if (!face) throw InputError(path, "header", "no 'face' element (ccdbench reads triangle meshes)");
  layout.face_element = *face;
  const auto& face_properties = header.elements[*face].properties;
  for (std::size_t p = 0; p < face_properties.size(); ++p) {
    const auto& property = face_properties[p];
    if (property.is_list && (property.name == "vertex_indices" || property.name == "vertex_index")) {
      if (!is_integer(property.type)) throw InputError(path, "header", "face indices must be integers");
      layout.index_property = static_cast<int>(p);
    }
  }
  if (layout.index_property < 0) throw InputError(path, "header", "face element has no 'vertex_indices' list");
  return layout;
}

/// Reads typed values from the binary body; every read checks the remaining length.
class BinaryCursor {
 public:
  BinaryCursor(const std::vector<char>& bytes, bool big_endian) : bytes_(bytes), big_endian_(big_endian) {}

  bool read(PlyType type, double& value) {
    const std::size_t size = type_size(type);
    if (offset_ + size > bytes_.size()) return false;
    unsigned char raw[8];
    std::memcpy(raw, bytes_.data() + offset_, size);
    offset_ += size;
    if (big_endian_ != (std::endian::native == std::endian::big)) std::reverse(raw, raw + size);
    switch (type) {
      case PlyType::int8: value = static_cast<std::int8_t>(raw[0]); break;
      case PlyType::uint8: value = raw[0]; break;
      case PlyType::int16: value = load<std::int16_t>(raw); break;
      case PlyType::uint16: value = load<std::uint16_t>(raw); break;
      case PlyType::int32: value = load<std::int32_t>(raw); break;
      case PlyType::uint32: value = load<std::uint32_t>(raw); break;
      case PlyType::float32: value = static_cast<double>(load<float>(raw)); break;
      case PlyType::float64: value = load<double>(raw); break;
    }
    return true;
  }
  std::size_t remaining() const { return bytes_.size() - offset_; }

 private:
  template <class T>
  static T load(const unsigned char* raw) {
    T value;
    std::memcpy(&value, raw, sizeof(T));
    return value;
  }
  const std::vector<char>& bytes_;
  bool big_endian_;
  std::size_t offset_ = 0;
};

/// Reads the value tokens of ASCII body lines, one element per line (blank lines are skipped).
class AsciiCursor {
 public:
  AsciiCursor(const std::filesystem::path& path, std::istream& in, std::size_t first_line) : path_(path), in_(in), line_number_(first_line - 1) {}

  /// Moves to the next non-blank line; false at the end of the file.
  bool next_line() {
    while (std::getline(in_, line_)) {
      ++line_number_;
      position_ = 0;
      if (line_.find_first_not_of(" \t\r") != std::string::npos) return true;
    }
    return false;
  }
  std::size_t line_number() const { return line_number_; }

  double read(PlyType type) {
    const std::size_t begin = line_.find_first_not_of(" \t\r", position_);
    if (begin == std::string::npos) throw InputError(path_, line_at(line_number_), "too few values on the line");
    std::size_t end = line_.find_first_of(" \t\r", begin);
    if (end == std::string::npos) end = line_.size();
    position_ = end;
    const char* first = line_.data() + begin;
    const char* last = line_.data() + end;
    double value = 0.0;
    std::from_chars_result result{};
    if (type == PlyType::float32) {
      float single = 0.0f;
      result = std::from_chars(first, last, single);
      value = static_cast<double>(single);
    } else if (type == PlyType::float64) {
      result = std::from_chars(first, last, value);
    } else {
      long long integer = 0;
      result = std::from_chars(first, last, integer);
      value = static_cast<double>(integer);
    }
    if (result.ec == std::errc::result_out_of_range) {
      throw InputError(path_, line_at(line_number_), "value '" + std::string(first, last) + "' is out of range");
    }
    if (result.ec != std::errc{} || result.ptr != last) {
      // from_chars rejects "nan"/"inf" spelled in some ways; report those as what they are.
      const std::string token(first, last);
      throw InputError(path_, line_at(line_number_), "malformed number '" + token + "'");
    }
    return value;
  }
  void expect_line_end() {
    if (line_.find_first_not_of(" \t\r", position_) != std::string::npos) {
      throw InputError(path_, line_at(line_number_), "too many values on the line");
    }
  }

 private:
  const std::filesystem::path& path_;
  std::istream& in_;
  std::string line_;
  std::size_t line_number_;
  std::size_t position_ = 0;
};

std::string element_where(const PlyElement& element, std::size_t index) { return element.name + " " + std::to_string(index); }

/// `where()` names the element for a message: made only when one is thrown (a frame of a large mesh has millions of
/// elements, and making each one's name was most of the time a binary PLY took to read).
template <class Where>
void check_face_count(const std::filesystem::path& path, const Where& where, double count, std::size_t face) {
  if (count != 3.0) {
    throw InputError(path, where(),
                     "face " + std::to_string(face) + " has " + std::to_string(static_cast<long long>(count)) +
                         " corners; ccdbench reads triangle meshes only (triangulate it first)");
  }
}

template <class Where>
VertexId to_vertex_index(const std::filesystem::path& path, const Where& where, double value) {
  // Negative or huge indices become an out-of-range index that validation reports with its value.
  if (value < 0.0 || value > 4294967295.0) {
    throw InputError(path, where(), "vertex index " + std::to_string(static_cast<long long>(value)) + " out of range");
  }
  return static_cast<VertexId>(value);
}

/// Refuses elements that have entries but no properties: nothing in the body would bound their count.
void check_elements_have_properties(const std::filesystem::path& path, const PlyHeader& header) {
  for (const PlyElement& element : header.elements) {
    if (element.count > 0 && element.properties.empty()) {
      throw InputError(path, "header", "element '" + element.name + "' has " + std::to_string(element.count) + " entries but no properties");
    }
  }
}

/// One entry (number i) of element `e`, its values read through `read(type)`: a vertex's coordinates or a face's
/// corner indices go into `frame`, appended as the body delivers them (never allocated from the header's counts: a
/// header may declare 300000000 faces in a 200-byte file); other properties are read past.
template <class Where, class Read>
void read_entry(const std::filesystem::path& path, const MeshLayout& layout, const PlyElement& element, std::size_t e, std::size_t i,
                const Where& where, Read&& read, MeshFrame& frame) {
  if (e == layout.vertex_element) frame.positions.emplace_back(0.0, 0.0, 0.0);
  if (e == layout.face_element) frame.faces.push_back(Face{});
  for (std::size_t p = 0; p < element.properties.size(); ++p) {
    const PlyProperty& property = element.properties[p];
    if (!property.is_list) {
      const double value = read(property.type);
      if (e == layout.vertex_element) {
        for (int k = 0; k < 3; ++k) {
          if (static_cast<int>(p) == layout.axis_property[k]) frame.positions[i][k] = value;
        }
      }
      continue;
    }
    const double count = read(property.count_type);
    const bool is_index = e == layout.face_element && static_cast<int>(p) == layout.index_property;
    if (is_index) check_face_count(path, where, count, i);
    if (count < 0.0) throw InputError(path, where(), "negative list length");
    for (std::size_t k = 0; k < static_cast<std::size_t>(count); ++k) {
      const double value = read(property.type);
      if (is_index) frame.faces[i][k] = to_vertex_index(path, where, value);
    }
  }
}

MeshFrame read_ascii_body(const std::filesystem::path& path, std::ifstream& in, const PlyHeader& header, const MeshLayout& layout) {
  MeshFrame frame;
  frame.format = "PLY ascii";
  std::vector<std::size_t> vertex_lines, face_lines;  // where each element was, for messages
  AsciiCursor cursor(path, in, header.body_first_line);
  for (std::size_t e = 0; e < header.elements.size(); ++e) {
    const PlyElement& element = header.elements[e];
    for (std::size_t i = 0; i < element.count; ++i) {
      if (!cursor.next_line()) {
        throw InputError(path, line_at(cursor.line_number()), "file ends at " + element_where(element, i) + " of " + std::to_string(element.count));
      }
      read_entry(
          path, layout, element, e, i, [&] { return line_at(cursor.line_number()); }, [&](PlyType type) { return cursor.read(type); }, frame);
      cursor.expect_line_end();
      if (e == layout.vertex_element) vertex_lines.push_back(cursor.line_number());
      if (e == layout.face_element) face_lines.push_back(cursor.line_number());
    }
  }
  if (cursor.next_line()) {
    throw InputError(path, line_at(cursor.line_number()),
                     "more lines than the header declares (" + std::to_string(header.elements[layout.vertex_element].count) + " vertices, " +
                         std::to_string(header.elements[layout.face_element].count) + " faces, " + std::to_string(header.elements.size()) +
                         " elements in all)");
  }
  validate_mesh_frame(
      path, frame, [&](std::size_t i) { return line_at(vertex_lines[i]); }, [&](std::size_t i) { return line_at(face_lines[i]); });
  return frame;
}

MeshFrame read_binary_body(const std::filesystem::path& path, std::ifstream& in, const PlyHeader& header, const MeshLayout& layout) {
  MeshFrame frame;
  const bool big_endian = header.encoding == PlyEncoding::binary_big_endian;
  frame.format = big_endian ? "PLY binary_big_endian" : "PLY binary_little_endian";
  // The body as the file holds it (its size is the file's bytes, not a count the header claims), read at once.
  const std::uintmax_t size = input_file_size(path);
  std::vector<char> body(size > header.body_offset ? static_cast<std::size_t>(size - header.body_offset) : 0);
  in.seekg(static_cast<std::streamoff>(header.body_offset));
  if (!body.empty() && !in.read(body.data(), static_cast<std::streamsize>(body.size()))) {
    throw InputError(path, "body", "cannot read the body (file changed while it was read?)");
  }
  BinaryCursor cursor(body, big_endian);
  for (std::size_t e = 0; e < header.elements.size(); ++e) {
    const PlyElement& element = header.elements[e];
    for (std::size_t i = 0; i < element.count; ++i) {
      const auto where = [&] { return element_where(element, i); };
      auto read = [&](PlyType type) {
        double value = 0.0;
        if (!cursor.read(type, value)) {
          throw InputError(
              path, where(),
              "truncated binary PLY: file ends inside " + where() + " of " + std::to_string(element.count) + " " + element.name + " elements");
        }
        return value;
      };
      read_entry(path, layout, element, e, i, where, read, frame);
    }
  }
  if (cursor.remaining() != 0) {
    throw InputError(path, "end of body", std::to_string(cursor.remaining()) + " bytes after the last element");
  }
  const PlyElement& vertex_element = header.elements[layout.vertex_element];
  frame.format += vertex_element.properties[static_cast<std::size_t>(layout.axis_property[0])].type == PlyType::float32 ? " (float)" : " (double)";
  validate_mesh_frame(
      path, frame, [](std::size_t i) { return "vertex " + std::to_string(i); }, [](std::size_t i) { return "face " + std::to_string(i); });
  return frame;
}

}  // namespace

MeshFrame read_ply(const std::filesystem::path& path) {
  std::ifstream in = open_input_file(path, "PLY file", std::ios::in | std::ios::binary);
  const PlyHeader header = parse_header(path, in);
  const MeshLayout layout = find_mesh_layout(path, header);
  check_elements_have_properties(path, header);
  return header.encoding == PlyEncoding::ascii ? read_ascii_body(path, in, header, layout) : read_binary_body(path, in, header, layout);
}

void write_ply(const std::filesystem::path& path, const MeshFrame& frame, PlyEncoding encoding) {
  AtomicFile file(path);
  std::ofstream& out = file.stream();
  out << "ply\nformat "
      << (encoding == PlyEncoding::ascii                  ? "ascii"
          : encoding == PlyEncoding::binary_little_endian ? "binary_little_endian"
                                                          : "binary_big_endian")
      << " 1.0\ncomment written by ccdbench\n"
      << "element vertex " << frame.positions.size() << "\nproperty double x\nproperty double y\nproperty double z\n"
      << "element face " << frame.faces.size() << "\nproperty list uchar int vertex_indices\nend_header\n";
  if (encoding == PlyEncoding::ascii) {
    out << std::setprecision(17);  // 17 significant digits identify every double exactly
    for (const Vec3& p : frame.positions) out << p.x() << ' ' << p.y() << ' ' << p.z() << '\n';
    for (const Face& f : frame.faces) out << "3 " << f[0] << ' ' << f[1] << ' ' << f[2] << '\n';
  } else {
    const bool swap = (encoding == PlyEncoding::binary_big_endian) != (std::endian::native == std::endian::big);
    auto put = [&](const void* data, std::size_t size) {
      char raw[8];
      std::memcpy(raw, data, size);
      if (swap) std::reverse(raw, raw + size);
      out.write(raw, static_cast<std::streamsize>(size));
    };
    for (const Vec3& p : frame.positions) {
      for (int k = 0; k < 3; ++k) put(&p[k], sizeof(double));
    }
    for (const Face& f : frame.faces) {
      const unsigned char three = 3;
      out.put(static_cast<char>(three));
      for (VertexId v : f) {
        const auto index = static_cast<std::int32_t>(v);
        put(&index, sizeof index);
      }
    }
  }
  file.commit();
}

}  // namespace ccd::datasets
