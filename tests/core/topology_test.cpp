#include "core/topology.hpp"
#include "core/error.hpp"
#include "tests/support/test_support.hpp"

#include <gtest/gtest.h>

#include <algorithm>

namespace ccd {
namespace {

TEST(Topology, ClosedTetrahedronHasSixEdgesAndNoBoundary) {
  const MeshTopology mesh(4, testing::tetrahedron_faces());
  EXPECT_EQ(mesh.num_edges(), 6u);
  EXPECT_EQ(mesh.num_boundary_edges(), 0u);
  EXPECT_EQ(mesh.num_unused_vertices(), 0u);
  for (EdgeId e = 0; e < mesh.num_edges(); ++e) EXPECT_EQ(mesh.edge_faces(e).size(), 2u);
  // Euler characteristic of a sphere.
  EXPECT_EQ(static_cast<long>(mesh.num_vertices()) - static_cast<long>(mesh.num_edges()) + static_cast<long>(mesh.num_faces()), 2);
}

TEST(Topology, OpenGridEdgeCounts) {
  for (std::size_t n : {2u, 3u, 5u, 17u}) {
    const MeshTopology mesh(n * n, testing::grid_faces(n));
    const std::size_t cells = (n - 1) * (n - 1);
    EXPECT_EQ(mesh.num_faces(), 2 * cells) << "n = " << n;
    // Each cell adds its diagonal; the grid has 2n(n-1) axis-aligned edges.
    EXPECT_EQ(mesh.num_edges(), cells + 2 * n * (n - 1)) << "n = " << n;
    EXPECT_EQ(mesh.num_boundary_edges(), 4 * (n - 1)) << "n = " << n;
  }
}

TEST(Topology, EdgesAreCanonicalSortedAndIndependentOfFaceOrder) {
  std::vector<Face> faces = testing::grid_faces(4);
  const MeshTopology mesh(16, faces);
  EXPECT_TRUE(std::is_sorted(mesh.edges().begin(), mesh.edges().end()));
  for (const Edge& e : mesh.edges()) EXPECT_LT(e.v0, e.v1);
  std::reverse(faces.begin(), faces.end());
  for (Face& f : faces) std::rotate(f.begin(), f.begin() + 1, f.end());
  const MeshTopology reordered(16, faces);
  EXPECT_EQ(mesh.edges(), reordered.edges());
}

TEST(Topology, IncidenceListsAreAscendingAndConsistent) {
  const MeshTopology mesh(25, testing::grid_faces(5));
  for (FaceId f = 0; f < mesh.num_faces(); ++f) {
    for (int k = 0; k < 3; ++k) {
      const Edge& e = mesh.edge(mesh.face_edges(f)[k]);
      EXPECT_EQ(e, make_edge(mesh.face(f)[k], mesh.face(f)[(k + 1) % 3]));
      const auto faces_of_edge = mesh.edge_faces(mesh.face_edges(f)[k]);
      EXPECT_NE(std::find(faces_of_edge.begin(), faces_of_edge.end(), f), faces_of_edge.end());
      const auto faces_of_vertex = mesh.vertex_faces(mesh.face(f)[k]);
      EXPECT_TRUE(std::is_sorted(faces_of_vertex.begin(), faces_of_vertex.end()));
      EXPECT_NE(std::find(faces_of_vertex.begin(), faces_of_vertex.end(), f), faces_of_vertex.end());
    }
  }
}

TEST(Topology, AdjacencyAndEdgeLookup) {
  const MeshTopology mesh(4, testing::tetrahedron_faces());
  // Faces 0 {0,2,1} and 1 {0,1,3} share the edge (0,1).
  EXPECT_TRUE(mesh.share_edge(0, 1));
  EXPECT_TRUE(mesh.share_vertex(0, 1));
  const MeshTopology grid(9, testing::grid_faces(3));
  // Face 0 {0,1,4} and face 7 {4,8,7} share only vertex 4.
  EXPECT_TRUE(grid.share_vertex(0, 7));
  EXPECT_FALSE(grid.share_edge(0, 7));
  EXPECT_TRUE(grid.find_edge(4, 0).has_value());
  EXPECT_FALSE(grid.find_edge(0, 8).has_value());
}

TEST(Topology, UnusedVerticesAreCountedAndHaveNoFaces) {
  const MeshTopology mesh(6, testing::tetrahedron_faces());
  EXPECT_EQ(mesh.num_unused_vertices(), 2u);
  EXPECT_FALSE(mesh.is_used(4));
  EXPECT_TRUE(mesh.vertex_faces(5).empty());
}

TEST(Topology, RejectsOutOfRangeAndRepeatedIndices) {
  try {
    MeshTopology(3, {{0, 1, 3}});
    FAIL() << "out-of-range index accepted";
  } catch (const InputError& error) {
    EXPECT_EQ(error.where(), "face 0");
    EXPECT_NE(std::string(error.what()).find("out of range"), std::string::npos) << error.what();
  }
  try {
    MeshTopology(3, {{0, 1, 2}, {2, 1, 2}});
    FAIL() << "degenerate face accepted";
  } catch (const InputError& error) {
    EXPECT_EQ(error.where(), "face 1");
    EXPECT_NE(std::string(error.what()).find("degenerate"), std::string::npos) << error.what();
  }
}

}  // namespace
}  // namespace ccd
