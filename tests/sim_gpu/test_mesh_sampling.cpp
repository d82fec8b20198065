// Rigid bodies from meshes (§4.1): mass properties of the closed mesh must match the analytic
// values (they set how a tool feels in the hand), surface samples must cover the surface with
// the requested spacing, and meshes that are not closed are refused with a clear message.
#include <gtest/gtest.h>

#include <cmath>

#include "hapfluid/sim/mesh_sampling.hpp"
#include "test_support.hpp"

using namespace hapfluid::sim;
namespace config = hapfluid::config;

TEST(MeshMassProperties, BoxIsExact) {
  const auto mesh = test::box_mesh(0.2, 0.1, 0.05);
  const MassProperties mp = mass_properties(mesh, 2.0);  // scaled to 0.4 x 0.2 x 0.1 m
  EXPECT_NEAR(mp.volume_m3, 0.4 * 0.2 * 0.1, 1e-12);
  EXPECT_NEAR(mp.centre_of_mass_m.x, 0.2, 1e-12);
  EXPECT_NEAR(mp.centre_of_mass_m.y, 0.1, 1e-12);
  EXPECT_NEAR(mp.centre_of_mass_m.z, 0.05, 1e-12);
  const double v = mp.volume_m3;
  EXPECT_NEAR(mp.inertia_per_density.m[0][0], v * (0.2 * 0.2 + 0.1 * 0.1) / 12, 1e-12);
  EXPECT_NEAR(mp.inertia_per_density.m[1][1], v * (0.4 * 0.4 + 0.1 * 0.1) / 12, 1e-12);
  EXPECT_NEAR(mp.inertia_per_density.m[2][2], v * (0.4 * 0.4 + 0.2 * 0.2) / 12, 1e-12);
  EXPECT_NEAR(mp.inertia_per_density.m[0][1], 0, 1e-14);
}

TEST(MeshMassProperties, SphereWithinOnePercent) {
  const double r = 0.05;
  const auto mesh = test::sphere_mesh(r, 4);
  const MassProperties mp = mass_properties(mesh, 1.0);
  const double volume = 4.0 / 3.0 * kPi * r * r * r;
  EXPECT_NEAR(mp.volume_m3, volume, 0.01 * volume);
  EXPECT_NEAR(norm(mp.centre_of_mass_m), 0, 1e-6);
  const double inertia = 0.4 * volume * r * r;  // per unit density, 2/5 m r^2
  for (int a = 0; a < 3; ++a) EXPECT_NEAR(mp.inertia_per_density.m[a][a], inertia, 0.01 * inertia);
}

TEST(MeshMassProperties, CupCentreOfMassIsLowAndVolumeIsTheShell) {
  // A cup of radius 5 cm, height 8 cm, walls 5 mm: volume = outer cylinder - inner cavity.
  const double R = 0.05, H = 0.08, t = 0.005;
  const auto mesh = test::cup_mesh(R, H, t, 128);
  check_closed_mesh(mesh, "cup");
  const MassProperties mp = mass_properties(mesh, 1.0);
  const double outer = kPi * R * R * H, inner = kPi * (R - t) * (R - t) * (H - t);
  const double polygon = 128 / (2 * kPi) * std::sin(2 * kPi / 128);  // inscribed polygon area factor
  EXPECT_NEAR(mp.volume_m3, (outer - inner) * polygon, 0.01 * (outer - inner));
  EXPECT_LT(mp.centre_of_mass_m.z, H / 2);  // the bottom makes it bottom-heavy
}

TEST(MeshChecks, OpenMeshIsRefusedNamingTheEdge) {
  auto mesh = test::box_mesh(0.1, 0.1, 0.1);
  mesh.triangles.pop_back();
  try {
    check_closed_mesh(mesh, "bodies.lid");
    FAIL() << "an open mesh was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("bodies.lid: mesh is not closed"), std::string::npos) << e.what();
  }
}

TEST(MeshChecks, InsideOutMeshIsRefused) {
  auto mesh = test::box_mesh(0.1, 0.1, 0.1);
  for (auto& t : mesh.triangles) std::swap(t[1], t[2]);
  EXPECT_THROW(check_closed_mesh(mesh, "box"), std::runtime_error);
}

TEST(SurfaceSampling, SamplesAreSpacedAndCoverTheSurface) {
  // No two particles closer than 0.8 spacing; every surface point within 0.8 spacing of a
  // particle, so fluid particles (support radius 2 spacings) cannot slip between them.
  const double r = 0.05, s = 0.01;
  const auto mesh = test::sphere_mesh(r, 3);
  const auto samples = sample_surface(mesh, 1.0, s);
  ASSERT_GT(samples.size(), 50u);
  double closest = 1e9;
  for (std::size_t i = 0; i < samples.size(); ++i)
    for (std::size_t j = i + 1; j < samples.size(); ++j) closest = std::min(closest, norm(samples[i] - samples[j]));
  EXPECT_GE(closest, kSampleRadiusFactor * s * (1 - 1e-6));
  const auto vertices = scaled_vertices(mesh, 1.0);
  for (const auto& v : vertices) {
    double nearest = 1e9;
    for (const auto& p : samples) nearest = std::min(nearest, norm(p - v));
    EXPECT_LE(nearest, kSampleRadiusFactor * s) << "a mesh vertex is not covered";
  }
  // About area / spacing^2 particles.
  const double area = 4 * kPi * r * r;
  EXPECT_GT(samples.size(), 0.6 * area / (s * s));
  EXPECT_LT(samples.size(), 1.6 * area / (s * s));
}

TEST(SurfaceSampling, InsideTest) {
  const auto mesh = test::sphere_mesh(0.05, 2);
  const auto v = scaled_vertices(mesh, 1.0);
  EXPECT_TRUE(inside_closed_mesh(v, mesh, {0, 0, 0}));
  EXPECT_TRUE(inside_closed_mesh(v, mesh, {0.03, -0.02, 0.01}));
  EXPECT_FALSE(inside_closed_mesh(v, mesh, {0.06, 0, 0}));
  const auto cup = test::cup_mesh(0.05, 0.08, 0.005, 64);
  const auto cv = scaled_vertices(cup, 1.0);
  EXPECT_FALSE(inside_closed_mesh(cv, cup, {0, 0, 0.04}));   // in the cavity: outside the solid
  EXPECT_TRUE(inside_closed_mesh(cv, cup, {0, 0, 0.0025}));  // in the bottom
}

// A fluid block poured into a vessel fills the vessel's inside and nothing around it: a block
// drawn around a cup (inner radius 45 mm, floor 5 mm thick) keeps only the lattice points with
// the cup below them. The fill is clear of the surface by 0.75 spacing like any block, so it
// lies within the inner radius and above the floor, and holds at least the lattice points of
// the cavity shrunk by one spacing (a looser bound would pass a fill that left gaps).
TEST(FluidBlocks, AVesselBlockFillsTheCupAndNotTheAirAroundIt) {
  const double s = 0.01, r_in = 0.045, floor_top = 0.02 + 0.005, top = 0.095;
  const std::string base = R"(
[domain]
min_m = [0.0, 0.0, 0.0]
max_m = [0.3, 0.3, 0.2]
[fluid]
particle_spacing_m = 0.01
solver = "dfsph"
[[fluid.blocks]]
min_m = [0.08, 0.08, 0.0]
max_m = [0.22, 0.22, 0.095]
VESSEL
[[bodies]]
name = "cup"
mesh = "cup.obj"
position_m = [0.15, 0.15, 0.02]
dynamic = false
sampling_spacing_m = 0.008
)";
  const auto dir = test::temp_dir("vessel");
  const auto cup = test::cup_mesh(0.05, 0.1, 0.005, 64);
  auto with = [&](const std::string& vessel) {
    std::string text = base;
    text.replace(text.find("VESSEL"), 6, vessel);
    return build_model(test::write_scene(dir, text, {{"cup.obj", cup}}));
  };
  const SimulationModel filled = with("vessel = \"cup\"");
  const SimulationModel whole = with("");
  const auto& f = filled.fluid;
  for (std::size_t i = 0; i < f.size(); ++i) {
    ASSERT_LT(std::hypot(f.x[i] - 0.15, f.y[i] - 0.15), r_in) << "particle " << i << " outside the cup's wall";
    ASSERT_GT(f.z[i], floor_top) << "particle " << i << " under the cup's floor";
  }
  std::size_t cavity = 0;  // lattice points at least one spacing inside the cavity
  for (double z = 0.5 * s; z < top; z += s)
    for (double y = 0.08 + 0.5 * s; y < 0.22; y += s)
      for (double x = 0.08 + 0.5 * s; x < 0.22; x += s)
        cavity += std::hypot(x - 0.15, y - 0.15) < r_in - s && z > floor_top + s ? 1 : 0;
  EXPECT_GE(f.size(), cavity);
  EXPECT_GT(whole.fluid.size(), 2 * f.size());  // without the vessel the block fills around the cup too
}
