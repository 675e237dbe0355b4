#include "strategies/plugin/contact_check.hpp"

#include "strategies/narrowphase/spec.hpp"

#include <cmath>

namespace ccd::plugin {

void refuse_shapes(const std::string& name, const Scene& scene, const std::string& why) {
  if (!scene.shape_objects().empty()) {
    throw std::invalid_argument(name + ": " + why + "; scene object '" + scene.object(scene.shape_objects().front()).name + "' is one");
  }
}

void ContactCheck::reset() {
  vertex_face_.clear();
  edge_edge_.clear();
}

bool ContactCheck::check_toi(double& toi, std::string& why) const {
  if (toi_ == Toi::ignored) {
    toi = kNoToi;
    return true;
  }
  if (std::isnan(toi)) {
    if (toi_ == Toi::optional) return true;
    why = "its TOI is not a number";
    return false;
  }
  if (!(toi >= 0.0 && toi <= 1.0)) {
    why = "its TOI " + narrowphase::format_spec_number(toi) + " is not in [0, 1]";
    return false;
  }
  return true;
}

std::optional<VertexFacePair> ContactCheck::vertex_face(std::uint64_t v, std::uint64_t f, double& toi, std::string& why) {
  const MeshTopology& topology = scene_.topology();
  if (v >= topology.num_vertices()) {
    why = "vertex " + std::to_string(v) + " is out of range (the mesh has " + std::to_string(topology.num_vertices()) + ")";
    return std::nullopt;
  }
  if (f >= topology.num_faces()) {
    why = "face " + std::to_string(f) + " is out of range (the mesh has " + std::to_string(topology.num_faces()) + ")";
    return std::nullopt;
  }
  const VertexFacePair pair{static_cast<VertexId>(v), static_cast<FaceId>(f)};
  const Face& face = topology.face(pair.f);
  if (face[0] == pair.v || face[1] == pair.v || face[2] == pair.v) {
    why = "vertex " + std::to_string(v) + " is a corner of face " + std::to_string(f);
    return std::nullopt;
  }
  if (!topology.is_used(pair.v)) {
    why = "vertex " + std::to_string(v) + " is on no face (not a primitive)";
    return std::nullopt;
  }
  if (!scene_.may_collide(scene_.object_of_vertex(pair.v), scene_.object_of_face(pair.f))) {
    why = "the scene does not let vertex " + std::to_string(v) + "'s object collide with face " + std::to_string(f) + "'s";
    return std::nullopt;
  }
  if (!check_toi(toi, why)) return std::nullopt;
  if (!vertex_face_.insert(pair).second) {
    why = "vertex-face pair (" + std::to_string(v) + ", " + std::to_string(f) + ") is reported twice";
    return std::nullopt;
  }
  return pair;
}

std::optional<EdgeEdgePair> ContactCheck::edge_edge(std::uint64_t a0, std::uint64_t a1, std::uint64_t b0, std::uint64_t b1, double& toi,
                                                    std::string& why) {
  const MeshTopology& topology = scene_.topology();
  const std::string name = "(" + std::to_string(a0) + ", " + std::to_string(a1) + ") and (" + std::to_string(b0) + ", " + std::to_string(b1) + ")";
  for (std::uint64_t v : {a0, a1, b0, b1}) {
    if (v >= topology.num_vertices()) {
      why = "edges " + name + ": vertex " + std::to_string(v) + " is out of range (the mesh has " + std::to_string(topology.num_vertices()) + ")";
      return std::nullopt;
    }
  }
  auto edge_of = [&](std::uint64_t p, std::uint64_t q) -> std::optional<Edge> {
    if (!topology.find_edge(static_cast<VertexId>(p), static_cast<VertexId>(q))) return std::nullopt;
    return p < q ? Edge{static_cast<VertexId>(p), static_cast<VertexId>(q)} : Edge{static_cast<VertexId>(q), static_cast<VertexId>(p)};
  };
  const std::optional<Edge> a = edge_of(a0, a1), b = edge_of(b0, b1);
  if (!a || !b) {
    why = "edges " + name + ": (" + std::to_string(a ? b0 : a0) + ", " + std::to_string(a ? b1 : a1) + ") is not an edge of the mesh";
    return std::nullopt;
  }
  if (a->v0 == b->v0 || a->v0 == b->v1 || a->v1 == b->v0 || a->v1 == b->v1) {
    why = "edges " + name + " share a vertex";
    return std::nullopt;
  }
  if (!scene_.may_collide(scene_.object_of_vertex(a->v0), scene_.object_of_vertex(b->v0))) {
    why = "edges " + name + ": the scene does not let their objects collide";
    return std::nullopt;
  }
  if (!check_toi(toi, why)) return std::nullopt;
  const EdgeEdgePair pair = make_edge_edge_pair(*a, *b);
  if (!edge_edge_.insert(pair).second) {
    why = "edge-edge pair " + name + " is reported twice";
    return std::nullopt;
  }
  return pair;
}

}  // namespace ccd::plugin
