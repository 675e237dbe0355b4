#include "datasets/frame_cache.hpp"

#include "core/error.hpp"
#include "datasets/atomic_file.hpp"
#include "datasets/content_hash.hpp"
#include "datasets/input_file.hpp"

#include <bit>
#include <cmath>
#include <cstring>
#include <fstream>
#include <vector>

namespace ccd::datasets {
namespace {

static_assert(std::endian::native == std::endian::little,
              "the frame cache stores little-endian values and is read with memcpy; add byte swapping to port it");

constexpr char kMagic[8] = {'C', 'C', 'D', 'B', 'F', 'R', 'M', '1'};
/// Version 2 ends with a checksum: the hex ContentHash of the header (without the frame count), the faces and the
/// frames, then the frame count.
constexpr std::uint32_t kVersion = 2;
constexpr std::size_t kDigestBytes = 32;

template <class T>
void put(std::ostream& out, T value) {
  out.write(reinterpret_cast<const char*>(&value), sizeof value);
}

template <class T>
bool get(std::istream& in, T& value) {
  return static_cast<bool>(in.read(reinterpret_cast<char*>(&value), sizeof value));
}

struct CacheHeader {
  std::string key;
  std::uint64_t num_vertices = 0;
  std::uint64_t num_faces = 0;
  std::uint64_t num_frames = 0;
  std::uint64_t frame_count_offset = 0;
  std::uint64_t faces_offset = 0;
  std::uint64_t frames_offset = 0;
};

/// Reads the whole file once and compares its checksum (a cache is verified before it is used, docs/DESIGN.md §6).
void verify_checksum(const std::filesystem::path& path, const CacheHeader& header, std::uint64_t size) {
  std::ifstream in = open_input_file(path, "frame cache", std::ios::in | std::ios::binary);
  ContentHash hash;
  std::vector<char> buffer(1 << 20);
  auto hash_range = [&](std::uint64_t from, std::uint64_t to) {
    in.seekg(static_cast<std::streamoff>(from));
    for (std::uint64_t left = to - from; left > 0;) {
      const auto chunk = static_cast<std::streamsize>(std::min<std::uint64_t>(left, buffer.size()));
      if (!in.read(buffer.data(), chunk)) throw InputError(path, "checksum", "cannot read the cache");
      hash.bytes(buffer.data(), static_cast<std::size_t>(chunk));
      left -= static_cast<std::uint64_t>(chunk);
    }
  };
  hash_range(0, header.frame_count_offset);
  hash_range(header.frame_count_offset + 8, size - kDigestBytes);
  hash.value(header.num_frames);
  std::string stored(kDigestBytes, '\0');
  in.seekg(static_cast<std::streamoff>(size - kDigestBytes));
  if (!in.read(stored.data(), static_cast<std::streamsize>(kDigestBytes)) || stored != hash.hex()) {
    throw InputError(path, "checksum", "does not match the content (the frame cache is corrupt)");
  }
}

CacheHeader read_header(const std::filesystem::path& path, std::istream& in) {
  char magic[8];
  std::uint32_t version = 0, reserved = 0;
  std::uint64_t key_length = 0;
  if (!in.read(magic, 8) || std::memcmp(magic, kMagic, 8) != 0) {
    throw InputError(path, "header", "not a ccdbench frame cache (bad magic)");
  }
  if (!get(in, version) || !get(in, reserved) || version != kVersion) {
    throw InputError(path, "header", "unsupported frame cache version " + std::to_string(version));
  }
  if (!get(in, key_length) || key_length > (1u << 20)) throw InputError(path, "header", "corrupt key length");
  CacheHeader header;
  header.key.resize(key_length);
  if (!in.read(header.key.data(), static_cast<std::streamsize>(key_length))) {
    throw InputError(path, "header", "truncated frame cache (inside the key)");
  }
  header.frame_count_offset = 8 + 4 + 4 + 8 + key_length + 8 + 8;
  if (!get(in, header.num_vertices) || !get(in, header.num_faces) || !get(in, header.num_frames)) {
    throw InputError(path, "header", "truncated frame cache (inside the counts)");
  }
  header.faces_offset = header.frame_count_offset + 8;
  const std::uint64_t actual = input_file_size(path);
  // Counts are checked against the file's bytes before any product of them is formed or allocated: a corrupt
  // count must not wrap around 2^64 into a small "expected" size.
  constexpr std::uint64_t kFaceBytes = 3 * sizeof(std::uint32_t), kVertexBytes = 3 * sizeof(double);
  if (header.num_vertices == 0) throw InputError(path, "header", "a frame cache with no vertices");
  if (header.num_faces > actual / kFaceBytes || header.num_vertices > actual / kVertexBytes ||
      header.num_frames > actual / (header.num_vertices * kVertexBytes)) {
    throw InputError(path, "header",
                     "corrupt counts: " + std::to_string(header.num_vertices) + " vertices, " + std::to_string(header.num_faces) + " faces, " +
                         std::to_string(header.num_frames) + " frames do not fit in " + std::to_string(actual) + " bytes");
  }
  if (header.num_frames == 0) throw InputError(path, "header", "a frame cache with no frames");
  header.frames_offset = header.faces_offset + header.num_faces * kFaceBytes;
  const std::uint64_t expected = header.frames_offset + header.num_frames * header.num_vertices * kVertexBytes + kDigestBytes;
  if (actual < expected) {
    const std::uint64_t frame_bytes = std::max<std::uint64_t>(1, header.num_vertices * 3 * sizeof(double));
    const std::uint64_t complete = actual < header.frames_offset ? 0 : (actual - header.frames_offset) / frame_bytes;
    throw InputError(path, "frame " + std::to_string(complete),
                     "truncated frame cache: " + std::to_string(actual) + " bytes, " + std::to_string(expected) + " expected for " +
                         std::to_string(header.num_frames) + " frames");
  }
  if (actual > expected) throw InputError(path, "end", "frame cache has trailing bytes");
  verify_checksum(path, header, actual);
  return header;
}

class CachedFrameSource final : public FrameSource {
 public:
  CachedFrameSource(std::filesystem::path path, CacheHeader header, std::vector<Face> faces)
      : path_(std::move(path)), header_(std::move(header)), faces_(std::move(faces)) {}

  std::size_t num_vertices() const override { return header_.num_vertices; }
  const std::vector<Face>& faces() const override { return faces_; }
  std::size_t num_frames() const override { return header_.num_frames; }

  std::vector<Vec3> frame(std::size_t k) const override {
    if (k >= header_.num_frames) {
      throw InputError(path_, "frame " + std::to_string(k), "the cache has " + std::to_string(header_.num_frames) + " frames");
    }
    std::ifstream in(path_, std::ios::binary);
    const std::uint64_t frame_bytes = header_.num_vertices * 3 * sizeof(double);
    in.seekg(static_cast<std::streamoff>(header_.frames_offset + k * frame_bytes));
    std::vector<Vec3> positions(header_.num_vertices);
    static_assert(sizeof(Vec3) == 3 * sizeof(double), "Vec3 must be three packed doubles");
    if (!in.read(reinterpret_cast<char*>(positions.data()), static_cast<std::streamsize>(frame_bytes))) {
      throw InputError(path_, "frame " + std::to_string(k), "cannot read frame (file changed since it was opened?)");
    }
    for (std::size_t i = 0; i < positions.size(); ++i) {
      if (!positions[i].allFinite()) {
        throw InputError(path_, "frame " + std::to_string(k) + ", vertex " + std::to_string(i), "non-finite coordinate in frame cache");
      }
    }
    return positions;
  }

  std::string describe() const override { return "frame cache " + path_.string(); }

 private:
  std::filesystem::path path_;
  CacheHeader header_;
  std::vector<Face> faces_;
};

std::unique_ptr<FrameSource> open_with_header(const std::filesystem::path& path, std::ifstream& in, CacheHeader header) {
  std::vector<Face> faces(header.num_faces);
  for (Face& face : faces) {
    for (VertexId& v : face) {
      if (!get(in, v)) throw InputError(path, "faces", "truncated frame cache");
    }
  }
  if (auto problem = find_face_list_problem(header.num_vertices, faces)) {
    throw InputError(path, "face " + std::to_string(problem->face), problem->reason);
  }
  return std::make_unique<CachedFrameSource>(path, std::move(header), std::move(faces));
}

}  // namespace

struct FrameCacheWriter::Impl {
  AtomicFile file;
  std::uint64_t frame_count_offset = 0;
  std::size_t num_vertices = 0;
  std::uint64_t frames = 0;
  bool finished = false;
  /// Of everything written but the frame count, in file order (the count is hashed last, at finish).
  ContentHash hash;

  void write(const void* data, std::size_t size, bool hashed = true) {
    file.stream().write(static_cast<const char*>(data), static_cast<std::streamsize>(size));
    if (hashed) hash.bytes(data, size);
  }
  template <class T>
  void put_value(T value, bool hashed = true) {
    write(&value, sizeof value, hashed);
  }
};

FrameCacheWriter::FrameCacheWriter(const std::filesystem::path& path, const std::string& key, std::size_t num_vertices,
                                   const std::vector<Face>& faces)
    : impl_(new Impl{AtomicFile(path), 0, num_vertices, 0, false, {}}) {
  Impl& w = *impl_;
  w.write(kMagic, 8);
  w.put_value(kVersion);
  w.put_value(std::uint32_t{0});
  w.put_value(std::uint64_t{key.size()});
  w.write(key.data(), key.size());
  w.put_value(std::uint64_t{num_vertices});
  w.put_value(std::uint64_t{faces.size()});
  w.frame_count_offset = static_cast<std::uint64_t>(w.file.stream().tellp());
  w.put_value(std::uint64_t{0}, false);
  for (const Face& face : faces) {
    for (VertexId v : face) w.put_value(v);
  }
}

FrameCacheWriter::~FrameCacheWriter() = default;

void FrameCacheWriter::append(std::span<const Vec3> positions) {
  if (positions.size() != impl_->num_vertices) throw std::invalid_argument("FrameCacheWriter: wrong vertex count");
  impl_->write(positions.data(), positions.size() * sizeof(Vec3));
  ++impl_->frames;
}

void FrameCacheWriter::finish() {
  std::ofstream& out = impl_->file.stream();
  impl_->hash.value(impl_->frames);
  const std::string digest = impl_->hash.hex();
  out.write(digest.data(), static_cast<std::streamsize>(digest.size()));
  out.seekp(static_cast<std::streamoff>(impl_->frame_count_offset));
  put(out, impl_->frames);
  impl_->file.commit();
}

std::optional<std::unique_ptr<FrameSource>> open_frame_cache(const std::filesystem::path& path, const std::string& expected_key) {
  if (!std::filesystem::exists(path)) return std::nullopt;
  std::ifstream in = open_input_file(path, "frame cache", std::ios::in | std::ios::binary);
  CacheHeader header = read_header(path, in);
  if (header.key != expected_key) return std::nullopt;
  return open_with_header(path, in, std::move(header));
}

std::unique_ptr<FrameSource> open_frame_cache(const std::filesystem::path& path) {
  std::ifstream in = open_input_file(path, "frame cache", std::ios::in | std::ios::binary);
  CacheHeader header = read_header(path, in);
  return open_with_header(path, in, std::move(header));
}

std::string frame_cache_key(const std::filesystem::path& path) {
  std::ifstream in = open_input_file(path, "frame cache", std::ios::in | std::ios::binary);
  return read_header(path, in).key;
}

}  // namespace ccd::datasets
