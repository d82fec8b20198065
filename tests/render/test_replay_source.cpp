// Replay of a recorded run (haptic-sim --out DIR): frames in index order, particles split by kind,
// bodies placed from bodies.csv at each frame's time.
#include <gtest/gtest.h>

#include <fstream>

#include "hapfluid/config/mesh.hpp"
#include "hapfluid/config/scene.hpp"
#include "hapfluid/render/replay_source.hpp"

using namespace hapfluid;
using namespace hapfluid::render;

namespace {

struct RecordedRun {
  std::filesystem::path dir;
  RecordedRun() {
    dir = std::filesystem::temp_directory_path() / ("hapfluid_replay_" + std::to_string(::getpid()));
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir / "particles");
    config::TriangleMesh cube;
    for (int i = 0; i < 8; ++i) cube.vertices_m.push_back({(i & 1) * 0.1 - 0.05, (i >> 1 & 1) * 0.1 - 0.05, (i >> 2) * 0.1 - 0.05});
    cube.triangles = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                      {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
    config::save_obj(cube, dir / "cube.obj");
    std::ofstream(dir / "scene.toml") << R"(name = "replay_test"
[domain]
min_m = [-0.3, -0.3, 0.0]
max_m = [0.3, 0.3, 0.5]
[fluid]
solver = "wcsph"
particle_spacing_m = 0.02
speed_of_sound_m_s = 20.0
look = "honey"
[time]
frame_rate_hz = 10.0
[[bodies]]
name = "spoon"
mesh = "cube.obj"
position_m = [0.0, 0.0, 0.2]
density_kg_m3 = 500.0
)";
    // Three frames: two fluid particles, one boundary, one body particle (kind 2).
    for (int f = 0; f < 3; ++f) {
      char name[64];
      std::snprintf(name, sizeof name, "frame_%06d.vtk", f);
      std::ofstream(dir / "particles" / name) << "# vtk DataFile Version 3.0\nframe\nASCII\nDATASET POLYDATA\n"
                                              << "POINTS 4 float\n0 0 " << 0.01 * f << "\n0.02 0 0\n0 0 -0.02\n0 0 0.2\n"
                                              << "POINT_DATA 4\nSCALARS kind int 1\nLOOKUP_TABLE default\n0 0 1 2\n";
    }
    std::ofstream(dir / "particles" / "notes.txt") << "not a frame";
    std::ofstream(dir / "bodies.csv") << "t,body,px,py,pz,qw,qx,qy,qz,vx,vy,vz\n"
                                         "0.0,spoon,0,0,0.2,1,0,0,0,0,0,0\n0.2,spoon,0.1,0,0.2,1,0,0,0,0.5,0,0\n";
  }
  ~RecordedRun() { std::filesystem::remove_all(dir); }
};

}  // namespace

TEST(ReplaySource, PlaysEveryFrameInOrderAndSplitsParticlesByKind) {
  RecordedRun run;
  ReplaySource source(run.dir, config::load_scene(run.dir / "scene.toml"));
  EXPECT_EQ(source.frame_count(), 3);
  EXPECT_NEAR(source.scene().particle_radius_m, 0.01, 1e-12);  // half the 2 cm spacing
  ASSERT_EQ(source.scene().bodies.size(), 1u);
  EXPECT_EQ(source.scene().bodies[0].mesh.triangles.size(), 12u);
  Frame frame;
  for (int f = 0; f < 3; ++f) {
    ASSERT_EQ(source.next_frame(frame), FrameStatus::new_frame);
    EXPECT_EQ(frame.index, uint64_t(f));
    ASSERT_EQ(frame.fluid_m.size(), 2u);
    EXPECT_NEAR(frame.fluid_m[0].z, 0.01 * f, 1e-6);
    EXPECT_EQ(frame.solid_m.size(), 2u);
    // 10 frames/s: frame 1 is at t = 0.1 s, halfway between the two body samples.
    ASSERT_EQ(frame.body_poses.size(), 1u);
    EXPECT_NEAR(frame.body_poses[0].position_m.x, 0.05 * f, 1e-6);
  }
  EXPECT_EQ(source.next_frame(frame), FrameStatus::end_of_stream);
}

TEST(ReplaySource, BodiesMayBeNamedByTheirIndexInTheScene) {
  RecordedRun run;
  std::ofstream(run.dir / "bodies.csv") << "t,body,px,py,pz,qw,qx,qy,qz\n0.0,0,0.3,0,0.2,1,0,0,0\n";
  ReplaySource source(run.dir, config::load_scene(run.dir / "scene.toml"));
  Frame frame;
  ASSERT_EQ(source.next_frame(frame), FrameStatus::new_frame);
  EXPECT_NEAR(frame.body_poses.at(0).position_m.x, 0.3, 1e-6);
}

TEST(ReplaySource, TakesTheFrameTimeFromHapticSimsVtkTitle) {
  // haptic-sim titles its frames "hapfluid <scene> t=<s> s"; that time places the bodies even when
  // frames were skipped or exported at another rate than the scene's frame_rate_hz.
  RecordedRun run;
  std::ofstream(run.dir / "particles" / "frame_000000.vtk")
      << "# vtk DataFile Version 3.0\nhapfluid replay_test t=0.150000 s\nASCII\nDATASET POLYDATA\n"
      << "POINTS 1 float\n0 0 0\n";
  ReplaySource source(run.dir, config::load_scene(run.dir / "scene.toml"));
  Frame frame;
  ASSERT_EQ(source.next_frame(frame), FrameStatus::new_frame);
  EXPECT_DOUBLE_EQ(frame.sim_time_s, 0.15);
  EXPECT_NEAR(frame.body_poses.at(0).position_m.x, 0.075, 1e-6);  // 3/4 of the way to 0.1 m at 0.2 s
}

TEST(ReplaySource, AnIncompleteRunIsReportedByPath) {
  RecordedRun run;
  std::filesystem::remove(run.dir / "bodies.csv");
  try {
    ReplaySource source(run.dir, config::load_scene(run.dir / "scene.toml"));
    FAIL() << "a run with bodies but no bodies.csv must be refused";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("bodies.csv: missing"), std::string::npos) << e.what();
  }
  std::filesystem::remove_all(run.dir / "particles");
  try {
    ReplaySource source(run.dir, config::load_scene(run.dir / "scene.toml"));
    FAIL() << "a run without frames must be refused";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("particles: no particle frames"), std::string::npos) << e.what();
  }
}
