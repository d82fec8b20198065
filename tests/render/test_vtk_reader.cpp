// The legacy VTK reader against files written here, in every form haptic-sim or ParaView may
// produce: ASCII and big-endian BINARY, POLYDATA and UNSTRUCTURED_GRID, SCALARS and FIELD arrays,
// VTK 5.1's OFFSETS/CONNECTIVITY cells. Bad files must fail with the file and line named.
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cstring>

#include "hapfluid/render/vtk_reader.hpp"

using namespace hapfluid::render;

namespace {

template <typename T>
void put_big_endian(std::string& out, T value) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  std::reverse(bytes, bytes + sizeof(T));
  out.append(bytes, sizeof(T));
}

}  // namespace

TEST(VtkReader, ReadsAsciiPolydataPointsAndKindScalars) {
  const std::string file =
      "# vtk DataFile Version 3.0\nhaptic-sim frame\nASCII\nDATASET POLYDATA\n"
      "FIELD FieldData 1\nTIME 1 1 double\n0.25\n"
      "POINTS 3 float\n0 0 0  0.1 0.2 0.3\n-1.5 2e-3 7\n"
      "VERTICES 3 6\n1 0\n1 1\n1 2\n"
      "POINT_DATA 3\nSCALARS kind int 1\nLOOKUP_TABLE default\n0 1 2\n"
      "VECTORS velocity float\n0 0 0 1 1 1 2 2 2\n";
  VtkPoints v = parse_vtk_points(file, "frame.vtk");
  ASSERT_EQ(v.points_m.size(), 3u);
  EXPECT_NEAR(v.points_m[1].z, 0.3, 1e-7);
  EXPECT_DOUBLE_EQ(v.points_m[2].x, -1.5);
  EXPECT_NEAR(v.points_m[2].y, 0.002, 1e-9);
  ASSERT_TRUE(v.time_s.has_value());
  EXPECT_DOUBLE_EQ(*v.time_s, 0.25);
  ASSERT_EQ(v.point_scalars.count("kind"), 1u);
  EXPECT_EQ(v.point_scalars["kind"], (std::vector<double>{0, 1, 2}));
}

TEST(VtkReader, ReadsBigEndianBinaryUnstructuredGridWithFieldArrays) {
  std::string file = "# vtk DataFile Version 2.0\nbinary test\nBINARY\nDATASET UNSTRUCTURED_GRID\nPOINTS 2 double\n";
  for (double c : {1.0, 2.0, 3.0, -4.0, 5.5, 6.25}) put_big_endian(file, c);
  file += "\nCELLS 2 4\n";
  for (int32_t c : {1, 0, 1, 1}) put_big_endian(file, c);
  file += "\nCELL_TYPES 2\n";
  for (int32_t c : {1, 1}) put_big_endian(file, c);
  file += "\nPOINT_DATA 2\nFIELD FieldData 2\nkind 1 2 int\n";
  for (int32_t c : {0, 3}) put_big_endian(file, c);
  file += "\ndensity 1 2 float\n";
  for (float c : {1000.0f, 998.5f}) put_big_endian(file, c);
  file += "\n";
  VtkPoints v = parse_vtk_points(file, "frame.vtk");
  ASSERT_EQ(v.points_m.size(), 2u);
  EXPECT_EQ(v.points_m[1], glm::dvec3(-4.0, 5.5, 6.25));
  EXPECT_EQ(v.point_scalars["kind"], (std::vector<double>{0, 3}));
  EXPECT_EQ(v.point_scalars["density"], (std::vector<double>{1000.0, 998.5}));
}

TEST(VtkReader, ReadsVersion51OffsetsAndConnectivityCells) {
  const std::string file =
      "# vtk DataFile Version 5.1\nv5\nASCII\nDATASET POLYDATA\nPOINTS 2 float\n0 0 0 1 1 1\n"
      "VERTICES 3 2\nOFFSETS vtktypeint64\n0 1 2\nCONNECTIVITY vtktypeint64\n0 1\n"
      "POINT_DATA 2\nSCALARS kind float\nLOOKUP_TABLE default\n0 1\n";
  VtkPoints v = parse_vtk_points(file, "v5.vtk");
  EXPECT_EQ(v.points_m.size(), 2u);
  EXPECT_EQ(v.point_scalars["kind"], (std::vector<double>{0, 1}));
}

TEST(VtkReader, TruncatedBinaryDataNamesTheFileAndTheSection) {
  std::string file = "# vtk DataFile Version 3.0\nt\nBINARY\nDATASET POLYDATA\nPOINTS 4 float\n";
  put_big_endian(file, 1.0f);  // 1 of 12 values
  try {
    parse_vtk_points(file, "run/particles/frame_000007.vtk");
    FAIL() << "a truncated file must not load";
  } catch (const std::runtime_error& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("run/particles/frame_000007.vtk: line 5"), std::string::npos) << m;
    EXPECT_NE(m.find("ends early"), std::string::npos) << m;
  }
}

TEST(VtkReader, RejectsFilesThatAreNotParticleData) {
  auto message = [](const std::string& text) {
    try {
      parse_vtk_points(text, "x.vtk");
    } catch (const std::runtime_error& e) {
      return std::string(e.what());
    }
    return std::string("(no error)");
  };
  EXPECT_NE(message("hello\n").find("first line"), std::string::npos);
  EXPECT_NE(message("# vtk DataFile Version 3.0\nt\nASCII\nDATASET STRUCTURED_POINTS\n").find("not supported"),
            std::string::npos);
  EXPECT_NE(message("# vtk DataFile Version 3.0\nt\nASCII\nDATASET POLYDATA\n").find("no POINTS"), std::string::npos);
  EXPECT_NE(message("# vtk DataFile Version 3.0\nt\nASCII\nDATASET POLYDATA\nPOINTS 1 float\n0 zero 0\n")
                .find("expected a number"),
            std::string::npos);
  EXPECT_NE(message("# vtk DataFile Version 3.0\nt\nASCII\nDATASET POLYDATA\nPOINTS 1 float\n0 0 0\n"
                    "POINT_DATA 2\n")
                .find("does not match POINTS"),
            std::string::npos);
}

TEST(VtkReader, CountsTheFileCannotHoldFailBeforeAnythingIsAllocated) {
  // haptic-render --replay reads any file it is pointed at: a count in a 70-byte file must not
  // make it allocate for it (2^31 ASCII points were 48 GB of doubles; a binary section of 2^62
  // values overflowed the size check and was then allocated).
  auto message = [](const std::string& text) {
    try {
      parse_vtk_points(text, "big.vtk");
    } catch (const std::runtime_error& e) {
      return std::string(e.what());
    }
    return std::string("(no error)");
  };
  const std::string ascii = "# vtk DataFile Version 3.0\nt\nASCII\nDATASET POLYDATA\nPOINTS 2147483648 float\n1 2 3\n";
  EXPECT_NE(message(ascii).find("big.vtk: line 5: ASCII data ends early: 6442450944 values"), std::string::npos)
      << message(ascii);
  std::string binary = "# vtk DataFile Version 3.0\nt\nBINARY\nDATASET POLYDATA\nPOINT_DATA 2147483648\n"
                       "SCALARS speed double 2147483648\nLOOKUP_TABLE default\n";
  put_big_endian(binary, 1.0);
  EXPECT_NE(message(binary).find("binary data ends early: 4611686018427387904 values"), std::string::npos)
      << message(binary);
}

TEST(VtkReader, ALineOfOtherWhitespaceIsBlank) {
  // A line of a vertical tab or a form feed has no word: it is skipped like an empty line (it
  // once reached the section parser as a header without a first word).
  const std::string file =
      "# vtk DataFile Version 3.0\nt\nASCII\nDATASET POLYDATA\n\v\nPOINTS 1 float\n0 0 1\n\f \n"
      "POINT_DATA 1\nSCALARS kind int 1\nLOOKUP_TABLE default\n2\n";
  VtkPoints v = parse_vtk_points(file, "x.vtk");
  ASSERT_EQ(v.points_m.size(), 1u);
  EXPECT_EQ(v.point_scalars["kind"], (std::vector<double>{2}));
}
