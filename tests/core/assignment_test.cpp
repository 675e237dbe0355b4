#include "core/assignment.hpp"
#include "core/pair_id.hpp"
#include "tests/support/test_support.hpp"

#include <gtest/gtest.h>

#include <map>

namespace ccd {
namespace {

struct NamedMesh {
  std::string name;
  std::size_t num_vertices;
  std::vector<Face> faces;
};

std::vector<NamedMesh> meshes_with_every_shape() {
  std::vector<Face> two_parts = testing::tetrahedron_faces();
  for (Face f : testing::grid_faces(3)) two_parts.push_back({f[0] + 4, f[1] + 4, f[2] + 4});
  return {
      {"tetrahedron (closed)", 4, testing::tetrahedron_faces()},
      {"grid 4x4 (open)", 16, testing::grid_faces(4)},
      {"tetrahedron + grid, 2 unused vertices", 15, two_parts},
      // Three triangles on one edge: a non-manifold fan.
      {"non-manifold fan", 5, {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}}},
  };
}

TEST(Assignment, EveryUsedVertexAndEveryEdgeIsOwnedExactlyOnceByAnIncidentFace) {
  for (const NamedMesh& m : meshes_with_every_shape()) {
    const MeshTopology mesh(m.num_vertices, m.faces);
    const std::vector<AssignmentMask> masks = assign_primitives(mesh);
    std::vector<int> vertex_owners(mesh.num_vertices(), 0), edge_owners(mesh.num_edges(), 0);
    for (FaceId f = 0; f < mesh.num_faces(); ++f) {
      for (int k = 0; k < 3; ++k) {
        if (masks[f] & owns_vertex_bit(k)) ++vertex_owners[mesh.face(f)[k]];
        if (masks[f] & owns_edge_bit(k)) ++edge_owners[mesh.face_edges(f)[k]];
      }
    }
    for (VertexId v = 0; v < mesh.num_vertices(); ++v) {
      EXPECT_EQ(vertex_owners[v], mesh.is_used(v) ? 1 : 0) << m.name << ", vertex " << v;
    }
    for (EdgeId e = 0; e < mesh.num_edges(); ++e) EXPECT_EQ(edge_owners[e], 1) << m.name << ", edge " << e;
  }
}

// docs/DESIGN.md §1: expanding every triangle pair A != B by the masks generates every elementary pair exactly once,
// including those of adjacent triangles that share no vertex.
TEST(Assignment, ExpandingAllTrianglePairsGeneratesEveryElementaryPairExactlyOnce) {
  for (const NamedMesh& m : meshes_with_every_shape()) {
    const MeshTopology mesh(m.num_vertices, m.faces);
    const std::vector<AssignmentMask> masks = assign_primitives(mesh);
    std::map<VertexFacePair, int> vf_generated;
    std::map<EdgeEdgePair, int> ee_generated;
    auto owned_vertices_against_face = [&](FaceId a, FaceId b) {
      for (int k = 0; k < 3; ++k) {
        const VertexId v = mesh.face(a)[k];
        const Face& fb = mesh.face(b);
        if ((masks[a] & owns_vertex_bit(k)) && v != fb[0] && v != fb[1] && v != fb[2]) ++vf_generated[{v, b}];
      }
    };
    for (FaceId a = 0; a < mesh.num_faces(); ++a) {
      for (FaceId b = a + 1; b < mesh.num_faces(); ++b) {
        owned_vertices_against_face(a, b);
        owned_vertices_against_face(b, a);
        for (int i = 0; i < 3; ++i) {
          for (int j = 0; j < 3; ++j) {
            if (!(masks[a] & owns_edge_bit(i)) || !(masks[b] & owns_edge_bit(j))) continue;
            const Edge ea = mesh.edge(mesh.face_edges(a)[i]);
            const Edge eb = mesh.edge(mesh.face_edges(b)[j]);
            if (ea.v0 == eb.v0 || ea.v0 == eb.v1 || ea.v1 == eb.v0 || ea.v1 == eb.v1) continue;
            ++ee_generated[make_edge_edge_pair(ea, eb)];
          }
        }
      }
    }
    std::size_t vf_expected = 0, ee_expected = 0;
    for (VertexId v = 0; v < mesh.num_vertices(); ++v) {
      if (!mesh.is_used(v)) continue;
      for (FaceId f = 0; f < mesh.num_faces(); ++f) {
        const Face& face = mesh.face(f);
        if (v == face[0] || v == face[1] || v == face[2]) continue;
        ++vf_expected;
        EXPECT_EQ((vf_generated[VertexFacePair{v, f}]), 1) << m.name << ": VF (" << v << ", " << f << ")";
      }
    }
    for (EdgeId p = 0; p < mesh.num_edges(); ++p) {
      for (EdgeId q = p + 1; q < mesh.num_edges(); ++q) {
        const Edge ep = mesh.edge(p), eq = mesh.edge(q);
        if (ep.v0 == eq.v0 || ep.v0 == eq.v1 || ep.v1 == eq.v0 || ep.v1 == eq.v1) continue;
        ++ee_expected;
        EXPECT_EQ(ee_generated[make_edge_edge_pair(ep, eq)], 1) << m.name << ": EE (" << p << ", " << q << ")";
      }
    }
    EXPECT_EQ(vf_generated.size(), vf_expected) << m.name;
    EXPECT_EQ(ee_generated.size(), ee_expected) << m.name;
  }
}

}  // namespace
}  // namespace ccd
