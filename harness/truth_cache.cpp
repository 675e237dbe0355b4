#include "harness/truth_cache.hpp"

#include "ccd/source_digest.hpp"
#include "core/error.hpp"
#include "datasets/atomic_file.hpp"
#include "datasets/content_hash.hpp"
#include "datasets/input_file.hpp"
#include "reference/step_truth.hpp"

#include <CGAL/version.h>

#include <algorithm>
#include <bit>
#include <cstring>
#include <iostream>
#include <limits>
#include <vector>

namespace ccd::harness {
namespace {

constexpr char kMagic[8] = {'C', 'C', 'D', 'T', 'R', 'U', 'T', '3'};
constexpr std::size_t kHeaderBytes = 8 + 8 + 8 + 8;  // magic, VF count, EE count, flags
constexpr std::uint64_t kWithToi = 1;
/// A face-shape count follows the header, and face-shape pairs (and their TOIs) follow the edge-edge ones. Files
/// without face-shape pairs do not set it and keep the layout they had before shapes existed.
constexpr std::uint64_t kWithFaceShape = 2;
constexpr std::size_t kFaceShapeBytes = 2 * sizeof(std::uint32_t);
constexpr std::size_t kToiBytes = sizeof(double);
constexpr std::size_t kChecksumBytes = 8;
constexpr std::size_t kVertexFaceBytes = 2 * sizeof(std::uint32_t);
constexpr std::size_t kEdgeEdgeBytes = 4 * sizeof(std::uint32_t);

void put_u32(std::vector<unsigned char>& out, std::uint32_t value) {
  for (int i = 0; i < 4; ++i) out.push_back(static_cast<unsigned char>(value >> (8 * i)));
}
void put_u64(std::vector<unsigned char>& out, std::uint64_t value) {
  for (int i = 0; i < 8; ++i) out.push_back(static_cast<unsigned char>(value >> (8 * i)));
}
std::uint32_t get_u32(const unsigned char* p) {
  std::uint32_t value = 0;
  for (int i = 3; i >= 0; --i) value = (value << 8) | p[i];
  return value;
}
std::uint64_t get_u64(const unsigned char* p) {
  std::uint64_t value = 0;
  for (int i = 7; i >= 0; --i) value = (value << 8) | p[i];
  return value;
}

std::string pair_where(const char* kind, std::uint64_t index) { return std::string(kind) + " pair " + std::to_string(index); }

void check_vertex_face(const std::filesystem::path& path, const Scene& scene, std::uint64_t index, const VertexFacePair& pair) {
  const MeshTopology& topology = scene.topology();
  const std::string where = pair_where("vertex-face", index);
  if (pair.v >= topology.num_vertices() || pair.f >= topology.num_faces()) {
    throw InputError(path, where,
                     "vertex " + std::to_string(pair.v) + " or face " + std::to_string(pair.f) + " out of range (" +
                         std::to_string(topology.num_vertices()) + " vertices, " + std::to_string(topology.num_faces()) + " faces)");
  }
  const Face& face = topology.face(pair.f);
  if (!topology.is_used(pair.v) || pair.v == face[0] || pair.v == face[1] || pair.v == face[2] ||
      !scene.may_collide(scene.object_of_vertex(pair.v), scene.object_of_face(pair.f))) {
    throw InputError(path, where, "not a vertex-face pair this scene can have");
  }
}

void check_edge(const std::filesystem::path& path, const MeshTopology& topology, const std::string& where, const Edge& e) {
  if (e.v0 >= e.v1 || e.v1 >= topology.num_vertices() || !topology.find_edge(e.v0, e.v1)) {
    throw InputError(path, where, "(" + std::to_string(e.v0) + ", " + std::to_string(e.v1) + ") is not an edge of the mesh");
  }
}

void check_edge_edge(const std::filesystem::path& path, const Scene& scene, std::uint64_t index, const EdgeEdgePair& pair) {
  const std::string where = pair_where("edge-edge", index);
  check_edge(path, scene.topology(), where, pair.a);
  check_edge(path, scene.topology(), where, pair.b);
  if (!(pair.a < pair.b) || shares_vertex(pair.a, pair.b) ||
      !scene.may_collide(scene.object_of_vertex(pair.a.v0), scene.object_of_vertex(pair.b.v0))) {
    throw InputError(path, where, "not an edge-edge pair this scene can have");
  }
}

void check_face_shape(const std::filesystem::path& path, const Scene& scene, std::uint64_t index, const FaceShapePair& pair) {
  const std::string where = pair_where("face-shape", index);
  if (pair.f >= scene.topology().num_faces() || pair.shape >= scene.objects().size() || scene.object(pair.shape).kind != ObjectKind::shape ||
      !scene.may_collide(scene.object_of_face(pair.f), pair.shape)) {
    throw InputError(path, where, "not a face-shape pair this scene can have");
  }
}

}  // namespace

std::string reference_version() { return std::string("reference sources ") + CCDBENCH_REFERENCE_SOURCE_DIGEST + ", CGAL " + CGAL_VERSION_STR; }

void hash_scene_structure(datasets::ContentHash& hash, const Scene& scene) {
  const MeshTopology& topology = scene.topology();
  hash.value(static_cast<std::uint64_t>(topology.num_vertices()));
  hash.value(static_cast<std::uint64_t>(topology.num_faces()));
  hash.bytes(topology.faces().data(), topology.faces().size() * sizeof(Face));
  hash.value(static_cast<std::uint64_t>(scene.objects().size()));
  for (const SceneObject& object : scene.objects()) {
    hash.text(object.name);
    hash.value(static_cast<std::uint8_t>(object.kind));
    hash.value(static_cast<std::uint8_t>(object.self_collision));
    hash.value(static_cast<std::uint64_t>(object.first_vertex));
    hash.value(static_cast<std::uint64_t>(object.first_face));
    if (object.shape) {  // only for shapes, so that scenes without them keep their keys
      hash.value(static_cast<std::uint8_t>(object.shape->kind));
      hash.value(object.shape->radius);
      for (int k = 0; k < 3; ++k) hash.value(object.shape->half_extents[k]);
    }
  }
  hash.value(static_cast<std::uint64_t>(scene.collidable_pairs().size()));
  for (const auto& [a, b] : scene.collidable_pairs()) {
    hash.value(static_cast<std::uint64_t>(a));
    hash.value(static_cast<std::uint64_t>(b));
  }
}

std::string truth_key(const Scene& scene, std::span<const Vec3> x0, std::span<const Vec3> x1) {
  datasets::ContentHash hash;
  hash.text("ccdbench truth v2");
  hash.text(reference_version());
  hash.value(scene.thickness());
  hash_scene_structure(hash, scene);
  hash.bytes(x0.data(), x0.size() * sizeof(Vec3));
  hash.bytes(x1.data(), x1.size() * sizeof(Vec3));
  return hash.hex();
}

void write_truth_file(const std::filesystem::path& path, const CollisionSet& truth, bool with_toi) {
  std::vector<unsigned char> bytes(kMagic, kMagic + 8);
  put_u64(bytes, truth.vertex_face().size());
  put_u64(bytes, truth.edge_edge().size());
  const bool with_face_shape = !truth.face_shape().empty();
  put_u64(bytes, (with_toi ? kWithToi : 0) | (with_face_shape ? kWithFaceShape : 0));
  if (with_face_shape) put_u64(bytes, truth.face_shape().size());
  for (const auto& c : truth.vertex_face()) {
    put_u32(bytes, c.pair.v);
    put_u32(bytes, c.pair.f);
  }
  for (const auto& c : truth.edge_edge()) {
    for (VertexId v : {c.pair.a.v0, c.pair.a.v1, c.pair.b.v0, c.pair.b.v1}) put_u32(bytes, v);
  }
  for (const auto& c : truth.face_shape()) {
    put_u32(bytes, c.pair.f);
    put_u32(bytes, c.pair.shape);
  }
  if (with_toi) {
    auto put_time = [&](double toi) { put_u64(bytes, std::bit_cast<std::uint64_t>(toi)); };
    for (const auto& c : truth.vertex_face()) put_time(c.toi);
    for (const auto& c : truth.edge_edge()) put_time(c.toi);
    for (const auto& c : truth.face_shape()) put_time(c.toi);
  }
  put_u64(bytes, datasets::checksum64(bytes.data(), bytes.size()));
  datasets::AtomicFile out(path);
  out.stream().write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  out.commit();
}

CachedTruth read_truth_file(const std::filesystem::path& path, const Scene& scene) {
  std::ifstream in = datasets::open_input_file(path, "truth cache file", std::ios::in | std::ios::binary);
  const std::uintmax_t size = datasets::input_file_size(path);
  if (size < kHeaderBytes + kChecksumBytes) throw InputError(path, "header", "truncated truth file");
  unsigned char header[kHeaderBytes];
  if (!in.read(reinterpret_cast<char*>(header), kHeaderBytes)) throw InputError(path, "header", "cannot read");
  if (std::memcmp(header, kMagic, 8) != 0) throw InputError(path, "header", "not a ccdbench truth file (bad magic)");
  const std::uint64_t vf = get_u64(header + 8), ee = get_u64(header + 16), flags = get_u64(header + 24);
  if (flags & ~(kWithToi | kWithFaceShape)) throw InputError(path, "header", "unknown flags " + std::to_string(flags));
  const bool with_toi = (flags & kWithToi) != 0;
  const std::size_t count_bytes = (flags & kWithFaceShape) ? 8 : 0;
  if (size < kHeaderBytes + count_bytes + kChecksumBytes) throw InputError(path, "header", "truncated truth file");
  std::uint64_t fs = 0;
  if (count_bytes) {
    unsigned char count[8];
    if (!in.read(reinterpret_cast<char*>(count), 8)) throw InputError(path, "header", "cannot read");
    fs = get_u64(count);
    if (fs == 0) throw InputError(path, "header", "the face-shape flag is set with no face-shape pairs");
  }
  const std::size_t time_bytes = with_toi ? kToiBytes : 0;
  const std::size_t vf_bytes = kVertexFaceBytes + time_bytes, ee_bytes = kEdgeEdgeBytes + time_bytes, fs_bytes = kFaceShapeBytes + time_bytes;
  // Counts first against the bytes that back them, so that no corrupt count is ever allocated.
  const std::uintmax_t body = size - kHeaderBytes - count_bytes - kChecksumBytes;
  if (vf > body / vf_bytes || ee > (body - vf * vf_bytes) / ee_bytes || fs > (body - vf * vf_bytes - ee * ee_bytes) / fs_bytes ||
      vf * vf_bytes + ee * ee_bytes + fs * fs_bytes != body) {
    throw InputError(path, "header",
                     std::to_string(vf) + " vertex-face, " + std::to_string(ee) + " edge-edge and " + std::to_string(fs) +
                         " face-shape pairs do not match the file's " + std::to_string(size) + " bytes");
  }
  std::vector<unsigned char> bytes(header, header + kHeaderBytes);
  if (count_bytes) put_u64(bytes, fs);
  const std::size_t start = bytes.size();
  bytes.resize(static_cast<std::size_t>(size));
  if (!in.read(reinterpret_cast<char*>(bytes.data() + start), static_cast<std::streamsize>(size - start))) {
    throw InputError(path, "body", "cannot read (file changed while reading?)");
  }
  const std::size_t checked = bytes.size() - kChecksumBytes;
  if (datasets::checksum64(bytes.data(), checked) != get_u64(bytes.data() + checked)) {
    throw InputError(path, "checksum", "does not match the content (the file is corrupt)");
  }
  const unsigned char* p = bytes.data() + start;
  const unsigned char* times = p + vf * kVertexFaceBytes + ee * kEdgeEdgeBytes + fs * kFaceShapeBytes;
  auto next_time = [&](const char* kind, std::uint64_t i) {
    if (!with_toi) return kNoToi;
    const double toi = std::bit_cast<double>(get_u64(times));
    times += kToiBytes;
    if (!(toi >= 0 && toi <= 1)) throw InputError(path, pair_where(kind, i), "TOI outside [0, 1]");
    return toi;
  };
  CachedTruth cached;
  cached.with_toi = with_toi;
  // Each list in turn: decoded, checked against the scene, sorted without repeats.
  auto read_pairs = [&](std::uint64_t count, std::size_t pair_bytes, const char* kind, auto decode, auto check) {
    decltype(decode(p)) previous{};
    for (std::uint64_t i = 0; i < count; ++i, p += pair_bytes) {
      const auto pair = decode(p);
      check(path, scene, i, pair);
      if (i > 0 && !(previous < pair)) throw InputError(path, pair_where(kind, i), "pairs out of order or repeated");
      cached.collisions.add(pair, next_time(kind, i));
      previous = pair;
    }
  };
  read_pairs(
      vf, kVertexFaceBytes, "vertex-face",
      [](const unsigned char* q) {
        return VertexFacePair{get_u32(q), get_u32(q + 4)};
      },
      check_vertex_face);
  read_pairs(
      ee, kEdgeEdgeBytes, "edge-edge",
      [](const unsigned char* q) {
        return EdgeEdgePair{{get_u32(q), get_u32(q + 4)}, {get_u32(q + 8), get_u32(q + 12)}};
      },
      check_edge_edge);
  read_pairs(
      fs, kFaceShapeBytes, "face-shape",
      [](const unsigned char* q) {
        return FaceShapePair{get_u32(q), get_u32(q + 4)};
      },
      check_face_shape);
  cached.collisions.normalize();
  return cached;
}

std::filesystem::path TruthCache::file_for(const Scene& scene, std::span<const Vec3> x0, std::span<const Vec3> x1) const {
  return directory_ / (truth_key(scene, x0, x1) + ".truth");
}

CollisionSet TruthCache::truth(const Scene& scene, std::span<const Vec3> x0, std::span<const Vec3> x1, bool& computed, bool with_toi) const {
  const std::filesystem::path file = file_for(scene, x0, x1);
  if (std::filesystem::exists(file)) {
    try {
      CachedTruth cached = read_truth_file(file, scene);
      if (cached.with_toi || !with_toi) {
        computed = false;
        return std::move(cached.collisions);
      }
    } catch (const InputError& error) {
      (warnings_ ? *warnings_ : std::cerr) << "ccdbench: warning: " << error.what() << "; the cached truth is not used, it is computed again\n";
    }
  }
  reference::TruthRequest request;
  request.thickness = scene.thickness();
  request.with_toi = with_toi;
  CollisionSet set = reference::compute_step_truth(scene, x0, x1, request).collisions;
  std::filesystem::create_directories(directory_);
  write_truth_file(file, set, with_toi);
  computed = true;
  return set;
}

}  // namespace ccd::harness
