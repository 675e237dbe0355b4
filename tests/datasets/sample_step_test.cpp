#include "datasets/sample_step.hpp"
#include "core/error.hpp"
#include "tests/support/test_support.hpp"

#include <gtest/gtest.h>

#include <map>

namespace ccd::datasets {
namespace {

struct ExpectedStep {
  const char* name;
  std::size_t vertices, faces, vf, ee;
};

// The candidate ids and the query coordinates must describe the same primitives: this pins down the id scheme
// (vertices, then edges, then faces) and that our unique-edge count equals the source's.
TEST(SampleStepSharedData, LoadsBothStepsAndIdsMatchQueryCoordinates) {
  CCD_REQUIRE_EXTERNAL_DATA(data);
  for (const ExpectedStep& expected : {ExpectedStep{"cloth-funnel", 9450, 18484, 92, 263}, ExpectedStep{"rod-twist", 39940, 79864, 801, 4370}}) {
    SCOPED_TRACE(expected.name);
    const SampleStep step = load_sample_step(data / "scalable-ccd-sample" / expected.name);
    EXPECT_EQ(step.topology.num_vertices(), expected.vertices);
    EXPECT_EQ(step.topology.num_faces(), expected.faces);
    ASSERT_EQ(step.vertex_face_candidates.size(), expected.vf);
    ASSERT_EQ(step.edge_edge_candidates.size(), expected.ee);
    for (std::size_t q = 0; q < expected.vf; ++q) {
      const auto [v, f] = step.vertex_face_candidates[q];
      const auto& rows = step.vertex_face_queries.queries[q].rounded;
      const Face& face = step.topology.face(f);
      ASSERT_EQ(rows[0], step.x0[v]) << "query " << q;
      ASSERT_EQ(rows[4], step.x1[v]) << "query " << q;
      for (int k = 0; k < 3; ++k) {
        ASSERT_EQ(rows[1 + k], step.x0[face[k]]) << "query " << q;
        ASSERT_EQ(rows[5 + k], step.x1[face[k]]) << "query " << q;
      }
    }
    // EE: every query's endpoints are mesh vertices joined by a mesh edge (matched by coordinates).
    std::map<std::array<double, 6>, VertexId> by_position;
    for (VertexId v = 0; v < step.x0.size(); ++v) {
      by_position[{step.x0[v].x(), step.x0[v].y(), step.x0[v].z(), step.x1[v].x(), step.x1[v].y(), step.x1[v].z()}] = v;
    }
    auto vertex_at = [&](const Vec3& p0, const Vec3& p1) {
      const auto it = by_position.find({p0.x(), p0.y(), p0.z(), p1.x(), p1.y(), p1.z()});
      return it == by_position.end() ? std::optional<VertexId>() : std::optional<VertexId>(it->second);
    };
    for (std::size_t q = 0; q < expected.ee; ++q) {
      const auto& rows = step.edge_edge_queries.queries[q].rounded;
      for (int e = 0; e < 2; ++e) {
        const auto a = vertex_at(rows[2 * e], rows[4 + 2 * e]);
        const auto b = vertex_at(rows[2 * e + 1], rows[5 + 2 * e]);
        ASSERT_TRUE(a && b) << "query " << q;
        ASSERT_TRUE(step.topology.find_edge(*a, *b).has_value()) << "query " << q;
      }
    }
  }
}

TEST(SampleStepBadInput, CandidateAndQueryCountsMustAgree) {
  CCD_REQUIRE_EXTERNAL_DATA(data);
  testing::TempDir dir;
  const auto source = data / "scalable-ccd-sample/cloth-funnel";
  std::filesystem::copy(source, dir.path(), std::filesystem::copy_options::recursive);
  // The shared data is read-only; the copy must be writable to edit it and to be removed afterwards.
  std::filesystem::permissions(dir.path(), std::filesystem::perms::owner_all, std::filesystem::perm_options::add);
  for (const auto& entry : std::filesystem::recursive_directory_iterator(dir.path())) {
    std::filesystem::permissions(entry.path(), std::filesystem::perms::owner_write, std::filesystem::perm_options::add);
  }
  std::filesystem::remove(dir / "boxes/227vf.json");
  testing::write_text(dir / "boxes/227vf.json", "[[8877, 54785]]");
  try {
    load_sample_step(dir.path());
    FAIL() << "count mismatch accepted";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("has 1 pairs but"), std::string::npos) << error.what();
  }
}

}  // namespace
}  // namespace ccd::datasets
