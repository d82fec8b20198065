// bodies.csv: the body poses of a recorded run, interpolated to each particle frame's time.
#include <gtest/gtest.h>

#include <fstream>

#include "hapfluid/render/bodies_csv.hpp"

using namespace hapfluid::render;

namespace {
std::filesystem::path write_temp(const std::string& name, const std::string& text) {
  auto path = std::filesystem::temp_directory_path() / ("hapfluid_render_" + std::to_string(::getpid()) + "_" + name);
  std::ofstream(path) << text;
  return path;
}
}  // namespace

TEST(BodyHistory, InterpolatesPositionAndOrientationBetweenSamples) {
  // A spoon moving 10 cm along x and turning 90 degrees about z in 0.1 s: halfway it is at 5 cm
  // and 45 degrees (slerp), so a replayed frame shows the tool where the sim had it.
  const double s = std::sqrt(0.5);
  auto file = write_temp("bodies.csv",
                         "t,body,px,py,pz,qw,qx,qy,qz,vx,vy,vz\n"
                         "0.0,spoon,0,0,0.2,1,0,0,0,0,0,0\n"
                         "0.1,spoon,0.1,0,0.2," + std::to_string(s) + ",0,0," + std::to_string(s) + ",1,0,0\n");
  BodyHistory h = BodyHistory::load(file);
  BodyPose p;
  ASSERT_TRUE(h.pose_at("spoon", 0.05, p));
  EXPECT_NEAR(p.position_m.x, 0.05, 1e-6);
  EXPECT_NEAR(p.position_m.z, 0.2, 1e-6);
  EXPECT_NEAR(glm::degrees(glm::angle(p.orientation)), 45.0, 0.01);
  ASSERT_TRUE(h.pose_at("spoon", 5.0, p));  // after the last sample: held
  EXPECT_NEAR(p.position_m.x, 0.1, 1e-6);
  EXPECT_FALSE(h.pose_at("bowl", 0.0, p));
  std::filesystem::remove(file);
}

TEST(BodyHistory, MalformedFilesNameTheLineAndColumn) {
  auto missing = write_temp("missing.csv", "t,body,px,py,pz,qw,qx,qy\n");
  EXPECT_THROW(
      {
        try {
          BodyHistory::load(missing);
        } catch (const std::runtime_error& e) {
          EXPECT_NE(std::string(e.what()).find("missing column \"qz\""), std::string::npos) << e.what();
          throw;
        }
      },
      std::runtime_error);
  auto bad = write_temp("bad.csv", "t,body,px,py,pz,qw,qx,qy,qz\n0,spoon,0,0,zero,1,0,0,0\n");
  try {
    BodyHistory::load(bad);
    FAIL() << "a non-numeric position must not load";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("line 2: pz = \"zero\""), std::string::npos) << e.what();
  }
  std::filesystem::remove(missing);
  std::filesystem::remove(bad);
}
