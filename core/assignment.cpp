#include "core/assignment.hpp"

namespace ccd {

std::vector<AssignmentMask> assign_primitives(const MeshTopology& topology) {
  std::vector<AssignmentMask> masks(topology.num_faces(), 0);
  for (FaceId f = 0; f < topology.num_faces(); ++f) {
    const Face& face = topology.face(f);
    const auto& edges = topology.face_edges(f);
    for (int k = 0; k < 3; ++k) {
      // Incidence lists are ascending, so the front is the lowest-id face.
      if (topology.vertex_faces(face[k]).front() == f) masks[f] |= owns_vertex_bit(k);
      if (topology.edge_faces(edges[k]).front() == f) masks[f] |= owns_edge_bit(k);
    }
  }
  return masks;
}

}  // namespace ccd
