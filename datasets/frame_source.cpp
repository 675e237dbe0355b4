#include "datasets/frame_source.hpp"
#include "datasets/mesh_file.hpp"

#include "core/error.hpp"
#include "datasets/mesh_frame.hpp"

#include <algorithm>
#include <cctype>
#include <map>
#include <optional>

namespace ccd::datasets {
namespace {

class FileFrameSource final : public FrameSource {
 public:
  explicit FileFrameSource(std::vector<std::filesystem::path> files) : files_(std::move(files)) {
    if (files_.empty()) throw InputError({}, "frames", "a frame sequence needs at least one file");
    MeshFrame first = read_mesh(files_.front());
    num_vertices_ = first.positions.size();
    faces_ = std::move(first.faces);
  }

  std::size_t num_vertices() const override { return num_vertices_; }
  const std::vector<Face>& faces() const override { return faces_; }
  std::size_t num_frames() const override { return files_.size(); }

  std::vector<Vec3> frame(std::size_t k) const override {
    MeshFrame mesh = read_mesh(files_.at(k));
    if (mesh.positions.size() != num_vertices_) {
      throw InputError(files_[k], "vertex count",
                       "topology changed between frames: " + std::to_string(mesh.positions.size()) + " vertices here, " +
                           std::to_string(num_vertices_) + " in " + files_.front().string());
    }
    if (mesh.faces.size() != faces_.size()) {
      throw InputError(files_[k], "face count",
                       "topology changed between frames: " + std::to_string(mesh.faces.size()) + " faces here, " + std::to_string(faces_.size()) +
                           " in " + files_.front().string());
    }
    const auto differs = std::mismatch(mesh.faces.begin(), mesh.faces.end(), faces_.begin());
    if (differs.first != mesh.faces.end()) {
      const auto f = static_cast<std::size_t>(differs.first - mesh.faces.begin());
      throw InputError(files_[k], "face " + std::to_string(f),
                       "topology changed between frames: this face's corners differ from those in " + files_.front().string());
    }
    return std::move(mesh.positions);
  }

  std::string describe() const override {
    if (files_.size() == 1) return "1 file " + files_.front().string();
    return std::to_string(files_.size()) + " files " + files_.front().string() + " .. " + files_.back().string();
  }

 private:
  std::vector<std::filesystem::path> files_;
  std::size_t num_vertices_ = 0;
  std::vector<Face> faces_;
};

bool is_mesh_extension(const std::filesystem::path& path) {
  std::string extension = path.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return extension == ".ply" || extension == ".obj";
}

/// The frame number at the end of `stem` ("frame_0007" -> 7), or nullopt when it ends in no digits or in more
/// digits than any frame count needs.
std::optional<unsigned long long> trailing_number(const std::string& stem, std::size_t& digits_begin) {
  digits_begin = stem.size();
  while (digits_begin > 0 && std::isdigit(static_cast<unsigned char>(stem[digits_begin - 1]))) --digits_begin;
  const std::size_t digits = stem.size() - digits_begin;
  if (digits == 0 || digits > 18) return std::nullopt;
  return std::stoull(stem.substr(digits_begin));
}

/// Adds `path` as frame `number`, refusing a second file with the same number ("frame_0001" and "frame_01").
void add_numbered_frame(const std::filesystem::path& where, std::map<unsigned long long, std::filesystem::path>& numbered, unsigned long long number,
                        const std::filesystem::path& path) {
  const auto [it, inserted] = numbered.emplace(number, path);
  if (!inserted) {
    throw InputError(
        where, {},
        "two files for frame " + std::to_string(number) + ": '" + it->second.filename().string() + "' and '" + path.filename().string() + "'");
  }
}

std::vector<std::filesystem::path> list_frame_directory(const std::filesystem::path& directory) {
  std::map<unsigned long long, std::filesystem::path> numbered;
  std::string prefix_and_extension;
  for (const auto& entry : std::filesystem::directory_iterator(directory)) {
    const std::filesystem::path& path = entry.path();
    if (!is_mesh_extension(path)) continue;
    const std::string stem = path.stem().string();
    std::size_t digits = 0;
    const auto number = trailing_number(stem, digits);
    if (!number) continue;  // no frame number
    if (!entry.is_regular_file()) {
      throw InputError(path, {}, "is named like a frame file but is not a regular file (a folder?)");
    }
    const std::string shape = stem.substr(0, digits) + "#" + path.extension().string();
    if (prefix_and_extension.empty()) prefix_and_extension = shape;
    if (shape != prefix_and_extension) {
      throw InputError(directory, {},
                       "frame files with different names or formats: '" + path.filename().string() + "' does not match " + prefix_and_extension +
                           " (# = frame number)");
    }
    add_numbered_frame(directory, numbered, *number, path);
  }
  if (numbered.empty()) throw InputError(directory, {}, "no numbered .ply or .obj frame files in this directory");
  std::vector<std::filesystem::path> files;
  unsigned long long expected = numbered.begin()->first;
  for (const auto& [number, path] : numbered) {
    if (number != expected) {
      throw InputError(directory, {}, "frame numbers have a gap: frame " + std::to_string(expected) + " is missing");
    }
    files.push_back(path);
    ++expected;
  }
  return files;
}

/// A printf-style frame pattern split at its one integer conversion: "dir/frame_%04d.ply" is
/// {"dir/frame_", 4, zero-padded, ".ply"}. Parsed by hand so a user's pattern never reaches printf.
struct FramePattern {
  std::string prefix;
  std::size_t width = 0;
  bool zero_pad = false;
  std::string suffix;

  std::filesystem::path format(unsigned long long number) const {
    std::string digits = std::to_string(number);
    if (digits.size() < width) digits.insert(0, width - digits.size(), zero_pad ? '0' : ' ');
    return prefix + digits + suffix;
  }
};

/// Accepts exactly one conversion %d, %i or %u with an optional 0 flag and width; "%%" is a literal '%'.
FramePattern parse_frame_pattern(const std::filesystem::path& pattern_path) {
  const std::string pattern = pattern_path.string();
  FramePattern parsed;
  int conversions = 0;
  std::string* out = &parsed.prefix;
  for (std::size_t i = 0; i < pattern.size(); ++i) {
    if (pattern[i] != '%') {
      *out += pattern[i];
      continue;
    }
    if (i + 1 < pattern.size() && pattern[i + 1] == '%') {
      *out += '%';
      ++i;
      continue;
    }
    std::size_t j = i + 1;
    if (j < pattern.size() && pattern[j] == '0') {
      parsed.zero_pad = true;
      ++j;
    }
    while (j < pattern.size() && std::isdigit(static_cast<unsigned char>(pattern[j]))) {
      parsed.width = parsed.width * 10 + static_cast<std::size_t>(pattern[j] - '0');
      if (parsed.width > 32) throw InputError(pattern_path, {}, "frame pattern: a width above 32 digits");
      ++j;
    }
    if (j >= pattern.size() || (pattern[j] != 'd' && pattern[j] != 'u' && pattern[j] != 'i') || parsed.width > 32) {
      throw InputError(pattern_path, {}, "frame pattern: only integer conversions like %04d are allowed");
    }
    ++conversions;
    out = &parsed.suffix;
    i = j;
  }
  if (conversions != 1) throw InputError(pattern_path, {}, "frame pattern needs exactly one %d-style conversion");
  return parsed;
}

}  // namespace

namespace {

class TrackFrameSource final : public FrameSource {
 public:
  TrackFrameSource(std::vector<Vec3> centres, std::string description) : centres_(std::move(centres)), description_(std::move(description)) {}
  std::size_t num_vertices() const override { return 1; }
  const std::vector<Face>& faces() const override { return faces_; }
  std::size_t num_frames() const override { return centres_.size(); }
  std::vector<Vec3> frame(std::size_t k) const override { return {centres_.at(k)}; }
  std::string describe() const override { return description_; }

 private:
  std::vector<Vec3> centres_;
  std::vector<Face> faces_;
  std::string description_;
};

}  // namespace

std::unique_ptr<FrameSource> make_track_frame_source(std::vector<Vec3> centres, std::string description) {
  return std::make_unique<TrackFrameSource>(std::move(centres), std::move(description));
}

std::unique_ptr<FrameSource> make_file_frame_source(std::vector<std::filesystem::path> files) {
  return std::make_unique<FileFrameSource>(std::move(files));
}

std::vector<std::filesystem::path> expand_frame_files(const std::filesystem::path& directory_or_pattern) {
  if (std::filesystem::is_directory(directory_or_pattern)) return list_frame_directory(directory_or_pattern);
  const FramePattern pattern = parse_frame_pattern(directory_or_pattern);
  // Every file of the pattern's folder whose name is the pattern's with some number in place of the conversion,
  // however padded: the sequence must be exactly these, numbered without a gap and without two files per number.
  const std::filesystem::path folder = std::filesystem::path(pattern.prefix).parent_path();
  const std::string name_prefix = std::filesystem::path(pattern.prefix).filename().string();
  if (pattern.suffix.find('/') != std::string::npos) {
    throw InputError(directory_or_pattern, {}, "frame pattern: the number must be in the file name, not in a folder");
  }
  std::map<unsigned long long, std::filesystem::path> numbered;
  std::error_code error;
  const std::filesystem::path listed = folder.empty() ? std::filesystem::path(".") : folder;
  for (const auto& entry : std::filesystem::directory_iterator(listed, error)) {
    const std::string name = entry.path().filename().string();
    if (name.size() <= name_prefix.size() + pattern.suffix.size() || name.compare(0, name_prefix.size(), name_prefix) != 0 ||
        name.compare(name.size() - pattern.suffix.size(), pattern.suffix.size(), pattern.suffix) != 0) {
      continue;
    }
    std::string middle = name.substr(name_prefix.size(), name.size() - name_prefix.size() - pattern.suffix.size());
    if (!pattern.zero_pad) middle.erase(0, middle.find_first_not_of(' '));  // %4d pads with spaces
    std::size_t digits = 0;
    const auto number = trailing_number(middle, digits);
    if (!number || digits != 0) continue;
    if (!entry.is_regular_file()) {
      throw InputError(entry.path(), {}, "is named like a frame file but is not a regular file (a folder?)");
    }
    add_numbered_frame(directory_or_pattern, numbered, *number, folder / name);
  }
  if (error) throw InputError(listed, {}, "cannot list the frame pattern's folder: " + error.message());
  if (numbered.empty()) throw InputError(directory_or_pattern, {}, "no frame file matches this pattern");
  if (numbered.begin()->first > 1) {
    throw InputError(directory_or_pattern, {}, "frames start at " + std::to_string(numbered.begin()->first) + ": frame 0 or 1 must exist");
  }
  std::vector<std::filesystem::path> files;
  unsigned long long expected = numbered.begin()->first;
  for (const auto& [number, path] : numbered) {
    if (number != expected) {
      throw InputError(directory_or_pattern, {},
                       "frame numbers have a gap: frame " + std::to_string(expected) + " is missing but frame " + std::to_string(number) + " exists");
    }
    if (path != pattern.format(number)) {
      throw InputError(
          path, {},
          "frame " + std::to_string(number) + " is not padded as the pattern says (expected '" + pattern.format(number).filename().string() + "')");
    }
    files.push_back(path);
    ++expected;
  }
  return files;
}

}  // namespace ccd::datasets
