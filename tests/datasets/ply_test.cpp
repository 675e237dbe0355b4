#include "datasets/ply.hpp"
#include "core/error.hpp"
#include "tests/support/test_support.hpp"

#include <gtest/gtest.h>
#include <sys/resource.h>

#include <bit>
#include <cstring>
#include <fstream>
#include <limits>
#include <random>

namespace ccd::datasets {
namespace {

using testing::TempDir;
using testing::write_text;

/// Frame with awkward doubles: subnormals, extremes, negative zero, values with all 53 bits set.
MeshFrame awkward_frame(std::uint32_t seed) {
  std::mt19937_64 random(seed);
  std::uniform_real_distribution<double> uniform(-1e3, 1e3);
  MeshFrame frame;
  frame.positions = testing::grid_positions(4);
  for (Vec3& p : frame.positions) p = Vec3(uniform(random), uniform(random), uniform(random));
  frame.positions[0] = Vec3(std::numeric_limits<double>::denorm_min(), std::numeric_limits<double>::max(), -0.0);
  frame.positions[1] = Vec3(0.1, 1.0 / 3.0, std::nextafter(1.0, 2.0));
  frame.positions[2] = Vec3(-std::numeric_limits<double>::min(), 1e-300, -1e300);
  frame.faces = testing::grid_faces(4);
  return frame;
}

void expect_bit_identical(const MeshFrame& a, const MeshFrame& b) {
  ASSERT_EQ(a.positions.size(), b.positions.size());
  EXPECT_EQ(std::memcmp(a.positions.data(), b.positions.data(), a.positions.size() * sizeof(Vec3)), 0);
  EXPECT_EQ(a.faces, b.faces);
}

TEST(Ply, WriteReadRoundTripIsBitExactInEveryEncoding) {
  const std::uint32_t seed = 20261121;
  SCOPED_TRACE("seed " + std::to_string(seed));
  const MeshFrame frame = awkward_frame(seed);
  TempDir dir;
  for (PlyEncoding encoding : {PlyEncoding::ascii, PlyEncoding::binary_little_endian, PlyEncoding::binary_big_endian}) {
    const auto path = dir / ("frame" + std::to_string(static_cast<int>(encoding)) + ".ply");
    write_ply(path, frame, encoding);
    expect_bit_identical(read_ply(path), frame);
  }
}

TEST(Ply, WriteLeavesNoTemporaryFiles) {
  TempDir dir;
  write_ply(dir / "a.ply", awkward_frame(1));
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir.path()), std::filesystem::directory_iterator()), 1);
}

template <class T>
void put_big_endian(std::string& out, T value) {
  char raw[sizeof(T)];
  std::memcpy(raw, &value, sizeof(T));
  if constexpr (std::endian::native == std::endian::little) std::reverse(raw, raw + sizeof(T));
  out.append(raw, sizeof(T));
}

TEST(Ply, ReadsBigEndianFloatsWithExtraPropertiesAndElements) {
  std::string text =
      "ply\nformat binary_big_endian 1.0\ncomment hand-made\nelement vertex 3\nproperty float x\n"
      "property uchar flag\nproperty float y\nproperty float z\nelement face 1\nproperty uchar material\n"
      "property list uint8 uint32 vertex_indices\nelement edge 1\nproperty int a\nproperty int b\nend_header\n";
  const float coordinates[3][3] = {{0.1f, 2.0f, -3.5f}, {1.0f, 0.0f, 0.0f}, {0.0f, 1.0f, 0.25f}};
  for (const auto& v : coordinates) {
    put_big_endian(text, v[0]);
    text += '\x07';
    put_big_endian(text, v[1]);
    put_big_endian(text, v[2]);
  }
  text += '\x01';
  text += '\x03';
  for (std::uint32_t index : {0u, 1u, 2u}) put_big_endian(text, index);
  put_big_endian(text, std::int32_t{0});
  put_big_endian(text, std::int32_t{1});
  TempDir dir;
  write_text(dir / "be.ply", text);
  const MeshFrame frame = read_ply(dir / "be.ply");
  ASSERT_EQ(frame.positions.size(), 3u);
  EXPECT_EQ(frame.positions[0].x(), static_cast<double>(0.1f));
  EXPECT_EQ(frame.positions[0].z(), -3.5);
  EXPECT_EQ(frame.positions[2].z(), 0.25);
  EXPECT_EQ(frame.faces, (std::vector<Face>{{0, 1, 2}}));
  EXPECT_EQ(frame.format, "PLY binary_big_endian (float)");
}

TEST(Ply, ReadsAsciiWithCommentsAndCrLf) {
  TempDir dir;
  write_text(dir / "a.ply",
             "ply\r\nformat ascii 1.0\r\ncomment x\r\nelement vertex 3\r\nproperty double x\r\nproperty double y\r\n"
             "property double z\r\nelement face 1\r\nproperty list uchar int vertex_index\r\nend_header\r\n"
             "0 0 0\r\n1 0 0\r\n0 1 1e-300\r\n3 0 1 2");
  const MeshFrame frame = read_ply(dir / "a.ply");
  EXPECT_EQ(frame.positions[2].z(), 1e-300);
  EXPECT_EQ(frame.faces.size(), 1u);
}

std::string ascii_ply(const std::string& vertices, const std::string& faces, int num_vertices = 3, int num_faces = 1) {
  return "ply\nformat ascii 1.0\nelement vertex " + std::to_string(num_vertices) +
         "\nproperty double x\nproperty double y\nproperty double z\nelement face " + std::to_string(num_faces) +
         "\nproperty list uchar int vertex_indices\nend_header\n" + vertices + faces;
}

/// Reads `text` as a PLY file and returns the error message, or "" when it was accepted.
std::string ply_error(const std::string& text) {
  TempDir dir;
  write_text(dir / "bad.ply", text);
  try {
    read_ply(dir / "bad.ply");
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("bad.ply"), std::string::npos) << "message must name the file";
    return error.what();
  }
  return "";
}

TEST(PlyBadInput, NaNAndInfiniteCoordinatesNameTheLine) {
  const std::string nan_error = ply_error(ascii_ply("0 0 0\n1 nan 0\n0 1 0\n", "3 0 1 2\n"));
  EXPECT_NE(nan_error.find("line 11"), std::string::npos) << nan_error;
  EXPECT_NE(nan_error.find("NaN"), std::string::npos) << nan_error;
  const std::string inf_error = ply_error(ascii_ply("0 0 0\n1 0 0\n0 1 inf\n", "3 0 1 2\n"));
  EXPECT_NE(inf_error.find("infinite"), std::string::npos) << inf_error;
}

TEST(PlyBadInput, FaceIndexOutOfRange) {
  const std::string error = ply_error(ascii_ply("0 0 0\n1 0 0\n0 1 0\n", "3 0 1 3\n"));
  EXPECT_NE(error.find("line 13"), std::string::npos) << error;
  EXPECT_NE(error.find("out of range"), std::string::npos) << error;
  EXPECT_NE(ply_error(ascii_ply("0 0 0\n1 0 0\n0 1 0\n", "3 0 1 -1\n")).find("out of range"), std::string::npos);
}

TEST(PlyBadInput, DegenerateFaceWithRepeatedIndex) {
  const std::string error = ply_error(ascii_ply("0 0 0\n1 0 0\n0 1 0\n", "3 0 1 1\n"));
  EXPECT_NE(error.find("degenerate"), std::string::npos) << error;
}

TEST(PlyBadInput, TruncatedBinaryBody) {
  TempDir dir;
  MeshFrame frame;
  frame.positions = testing::grid_positions(3);
  frame.faces = testing::grid_faces(3);
  write_ply(dir / "full.ply", frame);
  std::ifstream in(dir / "full.ply", std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string error = ply_error(bytes.substr(0, bytes.size() - 5));
  EXPECT_NE(error.find("truncated"), std::string::npos) << error;
  EXPECT_NE(error.find("face 7"), std::string::npos) << error;
  const std::string early = ply_error(bytes.substr(0, bytes.find("end_header\n") + 11 + 30));
  EXPECT_NE(early.find("vertex 1"), std::string::npos) << early;
}

TEST(PlyBadInput, MalformedHeaderAndBody) {
  EXPECT_NE(ply_error("plx\n").find("not a PLY"), std::string::npos);
  EXPECT_NE(ply_error("ply\nformat ascii 1.0\nelement vertex 1\n").find("end_header"), std::string::npos);
  EXPECT_NE(ply_error("ply\nformat ascii 1.0\nelement vertex 1\nproperty double x\nend_header\n0\n").find("'y'"), std::string::npos);
  EXPECT_NE(ply_error(ascii_ply("0 0 0\n1 0 0\n0 1 0\n", "4 0 1 2 0\n")).find("triangle"), std::string::npos);
  EXPECT_NE(ply_error(ascii_ply("0 0 0\n1 0\n0 1 0\n", "3 0 1 2\n")).find("line 11"), std::string::npos);
  EXPECT_NE(ply_error(ascii_ply("0 0 0\n1 0 0 5\n0 1 0\n", "3 0 1 2\n")).find("too many"), std::string::npos);
  EXPECT_NE(ply_error(ascii_ply("0 0 0\n1 0 0\n0 1 0\n", "")).find("file ends"), std::string::npos);
}

// ASCII files used to keep the declared number of faces and ignore the lines after them (binary refused them).
TEST(PlyBadInput, MoreLinesThanTheHeaderDeclaresAreAnError) {
  const std::string extra = ply_error(ascii_ply("0 0 0\n1 0 0\n0 1 0\n", "3 0 1 2\n3 0 2 1\n"));
  EXPECT_NE(extra.find("bad.ply:line 14: more lines than the header declares"), std::string::npos) << extra;
  EXPECT_EQ(ply_error(ascii_ply("0 0 0\n1 0 0\n0 1 0\n", "3 0 1 2\n\n  \n")), "") << "blank lines at the end are fine";
}

/// The largest resident set of this process so far, in kilobytes.
long peak_resident_kilobytes() {
  rusage usage{};
  ::getrusage(RUSAGE_SELF, &usage);
  return usage.ru_maxrss;
}

// `element face 300000000` in a 200-byte file used to allocate 3.5 GB before refusing: elements are appended as
// the body delivers them, so what is allocated is backed by the file's bytes.
TEST(PlyBadInput, HeaderCountsAreNotAllocatedBeforeTheBodyBacksThem) {
  const long before = peak_resident_kilobytes();
  const std::string ascii = ply_error(ascii_ply("0 0 0\n1 0 0\n0 1 0\n", "3 0 1 2\n", 3, 300000000));
  EXPECT_NE(ascii.find("file ends at face 1 of 300000000"), std::string::npos) << ascii;
  const std::string vertices = ply_error(ascii_ply("0 0 0\n", "", 1000000000));
  EXPECT_NE(vertices.find("file ends at vertex 1 of 1000000000"), std::string::npos) << vertices;
  std::string binary =
      "ply\nformat binary_little_endian 1.0\nelement vertex 3000000000\nproperty double x\n"
      "property double y\nproperty double z\nelement face 1\nproperty list uchar int vertex_indices\n"
      "end_header\n";
  binary += std::string(200, '\0');
  const std::string truncated = ply_error(binary);
  EXPECT_NE(truncated.find("truncated binary PLY"), std::string::npos) << truncated;
  EXPECT_LT(peak_resident_kilobytes() - before, 200 * 1024) << "reading a 200-byte file must not allocate gigabytes";
  const std::string no_properties = ply_error(
      "ply\nformat ascii 1.0\nelement junk 18446744073709551615\nelement vertex 0\nproperty double x\nproperty double y\n"
      "property double z\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n");
  EXPECT_NE(no_properties.find("element 'junk' has 18446744073709551615 entries but no properties"), std::string::npos) << no_properties;
}

TEST(PlyBadInput, AMeshWithoutTrianglesOrAFolderIsRefused) {
  EXPECT_NE(ply_error(ascii_ply("0 0 0\n1 0 0\n0 1 0\n", "", 3, 0)).find("bad.ply:faces: the mesh has no triangles"), std::string::npos);
  TempDir dir;
  std::filesystem::create_directories(dir / "folder.ply");
  const std::string folder = testing::error_message<InputError>([&] { read_ply(dir / "folder.ply"); });
  EXPECT_NE(folder.find("folder.ply: is a folder, expected a PLY file"), std::string::npos) << folder;
  // A device never ends (reading /dev/zero for a header line grew a string until memory ran out).
  const std::string device = testing::error_message<InputError>([&] { read_ply("/dev/zero"); });
  EXPECT_NE(device.find("/dev/zero: is not a regular file"), std::string::npos) << device;
}

TEST(PlyBadInput, UnusedVerticesWarnButAreRead) {
  TempDir dir;
  write_text(dir / "u.ply", ascii_ply("0 0 0\n1 0 0\n0 1 0\n5 5 5\n", "3 0 1 2\n", 4));
  ::testing::internal::CaptureStderr();
  const MeshFrame frame = read_ply(dir / "u.ply");
  const std::string warning = ::testing::internal::GetCapturedStderr();
  EXPECT_EQ(frame.positions.size(), 4u);
  EXPECT_NE(warning.find("1 vertices are used by no face"), std::string::npos) << warning;
}

TEST(PlySharedData, ReadsTheSampleFramesWithTheirCounts) {
  CCD_REQUIRE_EXTERNAL_DATA(data);
  const MeshFrame cloth = read_ply(data / "scalable-ccd-sample/cloth-funnel/frames/227.ply");
  EXPECT_EQ(cloth.positions.size(), 9450u);
  EXPECT_EQ(cloth.faces.size(), 18484u);
  const MeshFrame rod = read_ply(data / "scalable-ccd-sample/rod-twist/frames/3037.ply");
  EXPECT_EQ(rod.positions.size(), 39940u);
  EXPECT_EQ(rod.faces.size(), 79864u);
}

}  // namespace
}  // namespace ccd::datasets
