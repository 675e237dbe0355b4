#include "harness/truth_cache.hpp"

#include "datasets/atomic_file.hpp"
#include "reference/step_truth.hpp"

#include <cstring>
#include <fstream>
#include <iomanip>
#include <sstream>

namespace ccd::harness {
namespace {

/// Two FNV-1a streams with different offsets: 128 bits, so unrelated steps never share a key in practice.
class ContentHash {
 public:
  void bytes(const void* data, std::size_t size) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < size; ++i) {
      a_ = (a_ ^ p[i]) * 1099511628211ull;
      b_ = (b_ ^ p[i]) * 1099511628211ull;
    }
  }
  template <class T>
  void value(const T& v) {
    bytes(&v, sizeof v);
  }
  std::string hex() const {
    std::ostringstream out;
    out << std::hex << std::setfill('0') << std::setw(16) << a_ << std::setw(16) << b_;
    return out.str();
  }

 private:
  std::uint64_t a_ = 14695981039346656037ull;
  std::uint64_t b_ = 0x6c62272e07bb0142ull;
};

constexpr char kMagic[8] = {'C', 'C', 'D', 'T', 'R', 'U', 'T', 'H'};

}  // namespace

std::string truth_key(const Scene& scene, std::span<const Vec3> x0, std::span<const Vec3> x1) {
  ContentHash hash;
  hash.bytes(kReferenceVersion, std::strlen(kReferenceVersion));
  hash.value(scene.thickness());
  hash.value(scene.topology().num_vertices());
  hash.bytes(scene.topology().faces().data(), scene.topology().faces().size() * sizeof(Face));
  for (const SceneObject& object : scene.objects()) {
    hash.value(object.first_vertex);
    hash.value(object.first_face);
    hash.value(object.self_collision);
  }
  for (const auto& pair : scene.collidable_pairs()) hash.value(pair);
  hash.bytes(x0.data(), x0.size() * sizeof(Vec3));
  hash.bytes(x1.data(), x1.size() * sizeof(Vec3));
  return hash.hex();
}

CollisionSet TruthCache::truth(const Scene& scene, std::span<const Vec3> x0, std::span<const Vec3> x1, bool& computed) const {
  const std::filesystem::path file = directory_ / (truth_key(scene, x0, x1) + ".truth");
  if (std::ifstream in{file, std::ios::binary}) {
    char magic[8];
    std::uint64_t vf = 0, ee = 0;
    if (in.read(magic, 8) && std::memcmp(magic, kMagic, 8) == 0 && in.read(reinterpret_cast<char*>(&vf), 8) &&
        in.read(reinterpret_cast<char*>(&ee), 8)) {
      std::vector<VertexFacePair> vf_pairs(vf);
      std::vector<EdgeEdgePair> ee_pairs(ee);
      if (in.read(reinterpret_cast<char*>(vf_pairs.data()), static_cast<std::streamsize>(vf * sizeof(VertexFacePair))) &&
          in.read(reinterpret_cast<char*>(ee_pairs.data()), static_cast<std::streamsize>(ee * sizeof(EdgeEdgePair)))) {
        CollisionSet set;
        for (const auto& p : vf_pairs) set.add(p);
        for (const auto& p : ee_pairs) set.add(p);
        set.normalize();
        computed = false;
        return set;
      }
    }
  }
  reference::TruthRequest request;
  request.thickness = scene.thickness();
  CollisionSet set = reference::compute_step_truth(scene, x0, x1, request).collisions;
  std::filesystem::create_directories(directory_);
  datasets::AtomicFile out(file);
  const std::uint64_t vf = set.vertex_face().size(), ee = set.edge_edge().size();
  out.stream().write(kMagic, 8);
  out.stream().write(reinterpret_cast<const char*>(&vf), 8);
  out.stream().write(reinterpret_cast<const char*>(&ee), 8);
  for (const auto& c : set.vertex_face()) out.stream().write(reinterpret_cast<const char*>(&c.pair), sizeof c.pair);
  for (const auto& c : set.edge_edge()) out.stream().write(reinterpret_cast<const char*>(&c.pair), sizeof c.pair);
  out.commit();
  computed = true;
  return set;
}

}  // namespace ccd::harness
