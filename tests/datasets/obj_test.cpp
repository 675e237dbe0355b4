#include "datasets/obj.hpp"
#include "core/error.hpp"
#include "datasets/mesh_file.hpp"
#include "datasets/mesh_frame.hpp"
#include "tests/support/test_support.hpp"

#include <gtest/gtest.h>

#include <cstring>

namespace ccd::datasets {
namespace {

using testing::TempDir;
using testing::write_text;

TEST(Obj, WriteReadRoundTripIsBitExact) {
  MeshFrame frame;
  frame.positions = testing::grid_positions(3, 0.1);
  frame.positions[4] = Vec3(1.0 / 3.0, -1e-310, 123456789.123456789);
  frame.faces = testing::grid_faces(3);
  TempDir dir;
  write_mesh(dir / "m.obj", frame);
  const MeshFrame back = read_mesh(dir / "m.obj");
  ASSERT_EQ(back.positions.size(), frame.positions.size());
  EXPECT_EQ(std::memcmp(back.positions.data(), frame.positions.data(), frame.positions.size() * sizeof(Vec3)), 0);
  EXPECT_EQ(back.faces, frame.faces);
}

TEST(Obj, ReadsSlashFormsNegativeIndicesAndIgnoresOtherStatements) {
  TempDir dir;
  write_text(dir / "m.obj", "# c\no thing\nv 0 0 0\nv 1 0 0\nvn 0 0 1\nvt 0 0\nv 0 1 0 1\ns off\nf 1/1/1 2//1 -1\n");
  const MeshFrame frame = read_obj(dir / "m.obj");
  EXPECT_EQ(frame.positions.size(), 3u);
  EXPECT_EQ(frame.faces, (std::vector<Face>{{0, 1, 2}}));
}

std::string obj_error(const std::string& text) {
  TempDir dir;
  write_text(dir / "bad.obj", text);
  try {
    read_obj(dir / "bad.obj");
  } catch (const InputError& error) {
    return error.what();
  }
  return "";
}

TEST(ObjBadInput, EveryProblemNamesTheLine) {
  EXPECT_NE(obj_error("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3 4\n").find("line 5"), std::string::npos);
  EXPECT_NE(obj_error("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n").find("out of range"), std::string::npos);
  EXPECT_NE(obj_error("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n").find("out of range"), std::string::npos);
  EXPECT_NE(obj_error("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 2\n").find("degenerate"), std::string::npos);
  const std::string nan = obj_error("v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n");
  EXPECT_NE(nan.find("line 2"), std::string::npos) << nan;
  EXPECT_NE(nan.find("NaN"), std::string::npos) << nan;
  EXPECT_NE(obj_error("v 0 0 x\n").find("malformed"), std::string::npos);
}

TEST(MeshFrame, UnknownExtensionIsAnError) { EXPECT_THROW(read_mesh("mesh.stl"), InputError); }

}  // namespace
}  // namespace ccd::datasets
