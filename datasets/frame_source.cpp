#include "datasets/frame_source.hpp"

#include "core/error.hpp"
#include "datasets/mesh_frame.hpp"

#include <algorithm>
#include <cctype>
#include <map>

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
                       "topology changed between frames: " + std::to_string(mesh.positions.size()) +
                           " vertices here, " + std::to_string(num_vertices_) + " in " + files_.front().string());
    }
    if (mesh.faces.size() != faces_.size()) {
      throw InputError(files_[k], "face count",
                       "topology changed between frames: " + std::to_string(mesh.faces.size()) + " faces here, " +
                           std::to_string(faces_.size()) + " in " + files_.front().string());
    }
    const auto differs = std::mismatch(mesh.faces.begin(), mesh.faces.end(), faces_.begin());
    if (differs.first != mesh.faces.end()) {
      const auto f = static_cast<std::size_t>(differs.first - mesh.faces.begin());
      throw InputError(files_[k], "face " + std::to_string(f),
                       "topology changed between frames: this face's corners differ from those in " +
                           files_.front().string());
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
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return extension == ".ply" || extension == ".obj";
}

std::vector<std::filesystem::path> list_frame_directory(const std::filesystem::path& directory) {
  std::map<unsigned long long, std::filesystem::path> numbered;
  std::string prefix_and_extension;
  for (const auto& entry : std::filesystem::directory_iterator(directory)) {
    const std::filesystem::path& path = entry.path();
    if (!entry.is_regular_file() || !is_mesh_extension(path)) continue;
    const std::string stem = path.stem().string();
    std::size_t digits = stem.size();
    while (digits > 0 && std::isdigit(static_cast<unsigned char>(stem[digits - 1]))) --digits;
    if (digits == stem.size()) continue;  // no frame number
    const std::string shape = stem.substr(0, digits) + "#" + path.extension().string();
    if (prefix_and_extension.empty()) prefix_and_extension = shape;
    if (shape != prefix_and_extension) {
      throw InputError(directory, {}, "frame files with different names or formats: '" + path.filename().string() +
                                          "' does not match " + prefix_and_extension + " (# = frame number)");
    }
    numbered[std::stoull(stem.substr(digits))] = path;
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

std::unique_ptr<FrameSource> make_file_frame_source(std::vector<std::filesystem::path> files) {
  return std::make_unique<FileFrameSource>(std::move(files));
}

std::vector<std::filesystem::path> expand_frame_files(const std::filesystem::path& directory_or_pattern) {
  if (std::filesystem::is_directory(directory_or_pattern)) return list_frame_directory(directory_or_pattern);
  const FramePattern pattern = parse_frame_pattern(directory_or_pattern);
  unsigned long long number = std::filesystem::exists(pattern.format(0)) ? 0 : 1;
  std::vector<std::filesystem::path> files;
  for (std::filesystem::path path; std::filesystem::exists(path = pattern.format(number)); ++number) {
    files.push_back(path);
  }
  if (files.empty()) throw InputError(directory_or_pattern, {}, "no frame file matches this pattern (tried 0 and 1)");
  return files;
}

}  // namespace ccd::datasets
