// Meshes: the shipped meshes are closed and outward-oriented (mass properties by the divergence
// theorem depend on it), and OBJ/STL readers give the same mesh and clear errors.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>

#include "hapfluid/config/errors.hpp"
#include "hapfluid/config/mesh.hpp"

using namespace hapfluid::config;

namespace {

double signed_volume(const TriangleMesh& m) {
  double v = 0;
  for (const auto& t : m.triangles) {
    const Vec3 &a = m.vertices_m[t[0]], &b = m.vertices_m[t[1]], &c = m.vertices_m[t[2]];
    v += (a.x * (b.y * c.z - b.z * c.y) - a.y * (b.x * c.z - b.z * c.x) + a.z * (b.x * c.y - b.y * c.x)) / 6;
  }
  return v;
}

// Closed and consistently oriented: every directed edge appears once, and its reverse once.
bool closed_and_oriented(const TriangleMesh& m) {
  std::map<std::pair<uint32_t, uint32_t>, int> edges;
  for (const auto& t : m.triangles)
    for (int i = 0; i < 3; ++i) ++edges[{t[i], t[(i + 1) % 3]}];
  for (const auto& [e, n] : edges)
    if (n != 1 || edges.count({e.second, e.first}) == 0 || edges.at({e.second, e.first}) != 1) return false;
  return true;
}

std::filesystem::path temp_file(const std::string& name) {
  return std::filesystem::temp_directory_path() / ("hapfluid_test_" + std::to_string(::getpid()) + "_" + name);
}

}  // namespace

TEST(Mesh, EveryShippedMeshIsClosedAndOutwardOriented) {
  int count = 0;
  for (const auto& entry : std::filesystem::directory_iterator("config/meshes")) {
    SCOPED_TRACE(entry.path().string());
    TriangleMesh m = load_mesh(entry.path());
    EXPECT_TRUE(closed_and_oriented(m));
    EXPECT_GT(signed_volume(m), 0.0);
    ++count;
  }
  EXPECT_GE(count, 5);  // spoon, bowl, pan, glass, bucket at least
}

TEST(Mesh, SphereAndSlabHaveTheirAnalyticVolume) {
  // 16 x 32 facets under-estimate a sphere by ~1.6%; the slab is exact.
  EXPECT_NEAR(signed_volume(load_mesh("config/meshes/sphere.obj")), 4.0 / 3.0 * M_PI * 0.05 * 0.05 * 0.05, 0.02 * 5.236e-4);
  EXPECT_NEAR(signed_volume(load_mesh("config/meshes/slab.obj")), 0.12 * 0.12 * 0.04, 1e-12);
}

TEST(Mesh, BoundsFollowScaleAndPose) {
  TriangleMesh slab = load_mesh("config/meshes/slab.obj");
  const double s = std::sqrt(0.5);
  Aabb b = transformed_bounds(slab, 2.0, Pose{{1, 0, 0}, {s, 0, 0, s}});  // 90 deg about z
  EXPECT_NEAR(b.min_m.x, 1 - 0.12, 1e-12);
  EXPECT_NEAR(b.max_m.z, 0.04, 1e-12);
}

TEST(Mesh, BinaryAndAsciiStlReadAsTheSameWeldedMesh) {
  TriangleMesh slab = load_mesh("config/meshes/slab.obj");
  auto ascii = temp_file("slab_ascii.stl"), binary = temp_file("slab_binary.stl");
  {
    std::ofstream a(ascii), b(binary, std::ios::binary);
    a << "solid slab\n";
    char header[80] = {};
    uint32_t n = slab.triangles.size();
    b.write(header, 80);
    b.write(reinterpret_cast<const char*>(&n), 4);
    for (const auto& t : slab.triangles) {
      a << "facet normal 0 0 0\nouter loop\n";
      float record[12] = {};
      for (int c = 0; c < 3; ++c) {
        const Vec3& v = slab.vertices_m[t[c]];
        a << "vertex " << v.x << ' ' << v.y << ' ' << v.z << '\n';
        record[3 + 3 * c] = v.x, record[4 + 3 * c] = v.y, record[5 + 3 * c] = v.z;
      }
      a << "endloop\nendfacet\n";
      uint16_t attribute = 0;
      b.write(reinterpret_cast<const char*>(record), sizeof record);
      b.write(reinterpret_cast<const char*>(&attribute), 2);
    }
    a << "endsolid slab\n";
  }
  for (const auto& file : {ascii, binary}) {
    TriangleMesh m = load_mesh(file);
    EXPECT_EQ(m.vertices_m.size(), 8u);
    EXPECT_TRUE(closed_and_oriented(m));
    EXPECT_NEAR(signed_volume(m), signed_volume(slab), 1e-9);
    std::filesystem::remove(file);
  }
}

TEST(Mesh, ObjErrorsNameTheLine) {
  auto file = temp_file("broken.obj");
  std::ofstream(file) << "v 0 0 0\nv 1 0 0\nf 1 2 7\n";
  try {
    load_mesh(file);
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("broken.obj:3: face refers to vertex 7"), std::string::npos) << e.what();
  }
  std::filesystem::remove(file);
}

TEST(Mesh, TruncatedBinaryStlAndUnknownFormatAreRejected) {
  auto stl = temp_file("short.stl");
  {
    std::ofstream out(stl, std::ios::binary);
    char header[84] = {};
    uint32_t n = 10;
    std::memcpy(header + 80, &n, 4);
    out.write(header, 84);
  }
  EXPECT_THROW(load_mesh(stl), ConfigError);
  std::filesystem::remove(stl);
  EXPECT_THROW(load_mesh("config/scenes/dam_break.toml"), ConfigError);
}

TEST(Mesh, BinaryStlWithANonFiniteVertexIsRejectedLikeAnObjOne) {
  // A NaN or infinite coordinate would reach the simulator's sampling grid; OBJ and ASCII STL
  // refuse one as text, and the binary reader must too.
  auto stl = temp_file("nan.stl");
  {
    std::ofstream out(stl, std::ios::binary);
    char header[80] = {};
    uint32_t n = 2;
    out.write(header, 80);
    out.write(reinterpret_cast<const char*>(&n), 4);
    for (float bad : {0.0f, std::nanf("")}) {
      const float record[12] = {0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 1, bad};
      uint16_t attribute = 0;
      out.write(reinterpret_cast<const char*>(record), sizeof record);
      out.write(reinterpret_cast<const char*>(&attribute), 2);
    }
  }
  try {
    load_mesh(stl);
    FAIL() << "a NaN vertex must not load";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("nan.stl: binary STL triangle 1 has a vertex that is not 3 finite numbers"),
              std::string::npos)
        << e.what();
  }
  std::filesystem::remove(stl);
}
