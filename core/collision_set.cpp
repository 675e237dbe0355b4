#include "core/collision_set.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <iterator>

namespace ccd {
namespace {

/// The order of a normalized list: by pair, then by TOI, NaN (no TOI) after every reported time, so that the first
/// of each run of one pair is its earliest reported TOI.
/// (A function object, not a function: std::sort and std::merge then inline it.)
struct Before {
  template <class Pair>
  bool operator()(const Contact<Pair>& x, const Contact<Pair>& y) const {
    if (x.pair != y.pair) return x.pair < y.pair;
    if (std::isnan(x.toi)) return false;
    return std::isnan(y.toi) || x.toi < y.toi;
  }
};

template <class Pair>
void keep_first_of_each_pair(std::vector<Contact<Pair>>& contacts) {
  contacts.erase(std::unique(contacts.begin(), contacts.end(), [](const Contact<Pair>& x, const Contact<Pair>& y) { return x.pair == y.pair; }),
                 contacts.end());
}

template <class Pair>
void normalize_contacts(std::vector<Contact<Pair>>& contacts) {
  std::sort(contacts.begin(), contacts.end(), Before{});
  keep_first_of_each_pair(contacts);
}

template <class Pair>
void merge_contacts(std::vector<Contact<Pair>>& into, const std::vector<Contact<Pair>>& other) {
  if (other.empty()) return;
  std::vector<Contact<Pair>> merged;
  merged.reserve(into.size() + other.size());
  std::merge(into.begin(), into.end(), other.begin(), other.end(), std::back_inserter(merged), Before{});
  keep_first_of_each_pair(merged);
  into = std::move(merged);
}

template <class Pair>
bool contains_pair(const std::vector<Contact<Pair>>& contacts, const Pair& pair) {
  const auto it = std::lower_bound(contacts.begin(), contacts.end(), pair, [](const Contact<Pair>& c, const Pair& p) { return c.pair < p; });
  return it != contacts.end() && it->pair == pair;
}

template <class Pair>
bool same_pair_lists(const std::vector<Contact<Pair>>& x, const std::vector<Contact<Pair>>& y) {
  return std::equal(x.begin(), x.end(), y.begin(), y.end(), [](const Contact<Pair>& p, const Contact<Pair>& q) { return p.pair == q.pair; });
}

template <class Pair>
std::vector<Contact<Pair>> contacts_difference(const std::vector<Contact<Pair>>& a, const std::vector<Contact<Pair>>& b) {
  std::vector<Contact<Pair>> out;
  std::set_difference(a.begin(), a.end(), b.begin(), b.end(), std::back_inserter(out),
                      [](const Contact<Pair>& x, const Contact<Pair>& y) { return x.pair < y.pair; });
  return out;
}

/// FNV-1a over 64-bit words, byte by byte (little-endian order whatever the machine's).
class Fnv1a {
 public:
  void add(std::uint64_t word) {
    for (int byte = 0; byte < 8; ++byte) {
      hash_ ^= (word >> (8 * byte)) & 0xffu;
      hash_ *= 0x100000001b3ull;
    }
  }
  std::uint64_t value() const { return hash_; }

 private:
  std::uint64_t hash_ = 0xcbf29ce484222325ull;
};

}  // namespace

void CollisionSet::append(const CollisionSet& other) {
  vertex_face_.insert(vertex_face_.end(), other.vertex_face_.begin(), other.vertex_face_.end());
  edge_edge_.insert(edge_edge_.end(), other.edge_edge_.begin(), other.edge_edge_.end());
  face_shape_.insert(face_shape_.end(), other.face_shape_.begin(), other.face_shape_.end());
}

void CollisionSet::normalize() {
  normalize_contacts(vertex_face_);
  normalize_contacts(edge_edge_);
  normalize_contacts(face_shape_);
}

void CollisionSet::merge_normalized(const CollisionSet& other) {
  merge_contacts(vertex_face_, other.vertex_face_);
  merge_contacts(edge_edge_, other.edge_edge_);
  merge_contacts(face_shape_, other.face_shape_);
}

bool CollisionSet::contains(const VertexFacePair& pair) const { return contains_pair(vertex_face_, pair); }
bool CollisionSet::contains(const EdgeEdgePair& pair) const { return contains_pair(edge_edge_, pair); }
bool CollisionSet::contains(const FaceShapePair& pair) const { return contains_pair(face_shape_, pair); }

bool CollisionSet::same_pairs(const CollisionSet& other) const {
  return same_pair_lists(vertex_face_, other.vertex_face_) && same_pair_lists(edge_edge_, other.edge_edge_) &&
         same_pair_lists(face_shape_, other.face_shape_);
}

CollisionSet set_difference(const CollisionSet& a, const CollisionSet& b) {
  CollisionSet out;
  for (const auto& c : contacts_difference(a.vertex_face(), b.vertex_face())) out.add(c.pair, c.toi);
  for (const auto& c : contacts_difference(a.edge_edge(), b.edge_edge())) out.add(c.pair, c.toi);
  for (const auto& c : contacts_difference(a.face_shape(), b.face_shape())) out.add(c.pair, c.toi);
  return out;
}

std::string answers_digest(const CollisionSet& set) {
  Fnv1a hash;
  // Each list's length goes first, so a pair cannot move from one list to the other unseen.
  hash.add(set.vertex_face().size());
  for (const VertexFaceContact& c : set.vertex_face()) {
    hash.add((std::uint64_t{c.pair.v} << 32) | c.pair.f);
    hash.add(std::bit_cast<std::uint64_t>(c.toi));
  }
  hash.add(set.edge_edge().size());
  for (const EdgeEdgeContact& c : set.edge_edge()) {
    hash.add((std::uint64_t{c.pair.a.v0} << 32) | c.pair.a.v1);
    hash.add((std::uint64_t{c.pair.b.v0} << 32) | c.pair.b.v1);
    hash.add(std::bit_cast<std::uint64_t>(c.toi));
  }
  if (!set.face_shape().empty()) {
    hash.add(set.face_shape().size());
    for (const FaceShapeContact& c : set.face_shape()) {
      hash.add((std::uint64_t{c.pair.f} << 32) | c.pair.shape);
      hash.add(std::bit_cast<std::uint64_t>(c.toi));
    }
  }
  char text[17];
  std::snprintf(text, sizeof(text), "%016llx", static_cast<unsigned long long>(hash.value()));
  return text;
}

}  // namespace ccd
