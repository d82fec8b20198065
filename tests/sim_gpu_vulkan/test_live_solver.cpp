// The live loop's view of the two backends (sim_gpu/live/live_solver.hpp, live_backend.hpp):
// what the loop publishes every step (bodies, couplings) is current after every step on
// Vulkan as on the CPU and equal to it; the fluid comes back from the device only when the loop
// asks (frame rate); and the backend choice does what --backend says.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <sstream>
#include <string>

#include "hapfluid/config/log.hpp"
#include "hapfluid/config/scene.hpp"
#include "live_backend.hpp"

namespace hs = hapfluid::sim;

namespace {

hapfluid::config::Scene load(const std::string& relative) {
  return hapfluid::config::load_scene(std::filesystem::path(HAPFLUID_SOURCE_DIR) / relative);
}

double distance(const hs::Vec3& a, const hs::Vec3& b) { return hs::norm(a - b); }

const char* kSpoon = "tests/sim_gpu_vulkan/scenes/spoon_small.toml";

}  // namespace

TEST(LiveSolver, VulkanPublishesTheCpusBodyAndCouplingWrenchEveryStep) {
  // The 1 kHz loop renders the coupling wrench of every step: on Vulkan it must be the step's
  // own (host-side, no read-back of the fluid) and equal the reference's, to the equivalence
  // tests' tolerances (1e-7 m, 1e-4 relative on the wrench), step by step, with a moving hand.
  const hs::SimulationModel model = hs::build_model(load(kSpoon));
  hs::LiveBackendOptions options;
  auto cpu = hs::make_live_solver(model, "cpu", options);
  auto gpu = hs::make_live_solver(model, "vulkan", options);
  EXPECT_STREQ(gpu->backend(), "vulkan");
  EXPECT_FALSE(gpu->device().name.empty());
  for (int s = 0; s < 15; ++s) {
    hs::DeviceState hand = hs::device_state_from(hapfluid::config::evaluate_motion(model.devices[0].motion, cpu->time_s()));
    hand.position.x += 0.002 * s;  // a live pose, not the script
    hand.linear_velocity.x = 0.2;
    cpu->set_device_state(0, hand);
    gpu->set_device_state(0, hand);
    const double dt = cpu->stable_time_step();
    ASSERT_NEAR(gpu->stable_time_step(), dt, 1e-5 * dt);
    cpu->step(dt);
    gpu->step(dt);
    const hs::RigidBody &a = cpu->model().bodies[0], &b = gpu->model().bodies[0];
    EXPECT_LT(distance(a.position, b.position), 1e-7) << "step " << s;
    const hs::VirtualCoupling &ca = cpu->model().couplings[0], &cb = gpu->model().couplings[0];
    EXPECT_GT(hs::norm(ca.device_force), 0.0);
    EXPECT_LT(distance(ca.device_force, cb.device_force), 1e-4 * std::max(hs::norm(ca.device_force), 1e-3)) << "step " << s;
    EXPECT_LT(distance(ca.device_torque, cb.device_torque), 1e-4 * std::max(hs::norm(ca.device_torque), 1e-4)) << "step " << s;
  }
  EXPECT_EQ(gpu->steps(), 15u);
  EXPECT_NEAR(gpu->time_s(), cpu->time_s(), 1e-12);
}

TEST(LiveSolver, VulkanFluidComesBackOnlyWhenTheLoopSyncs) {
  // Particles are published at the frame rate: between frames the fluid stays on the device
  // (no per-step read-back), and sync_and_check_finite() brings back the device's fluid, equal
  // to the reference's (same cell order, 1e-6 m as the equivalence tests after 10 steps).
  const hs::SimulationModel model = hs::build_model(load(kSpoon));
  hs::LiveBackendOptions options;
  auto cpu = hs::make_live_solver(model, "cpu", options);
  auto gpu = hs::make_live_solver(model, "vulkan", options);
  gpu->sync_and_check_finite();
  const std::vector<float> z_synced = gpu->model().fluid.z;
  for (int s = 0; s < 10; ++s) {
    const double dt = cpu->stable_time_step();
    cpu->step(dt);
    gpu->step(dt);
  }
  EXPECT_EQ(gpu->model().fluid.z, z_synced) << "the fluid was read back during steps";
  gpu->sync_and_check_finite();
  const hs::FluidParticles &a = cpu->model().fluid, &b = gpu->model().fluid;
  ASSERT_EQ(a.size(), b.size());
  double dz_m = 0, moved_m = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a.id[i], b.id[i]) << "particle " << i;
    dz_m = std::max({dz_m, std::abs(double(a.x[i]) - b.x[i]), std::abs(double(a.y[i]) - b.y[i]),
                     std::abs(double(a.z[i]) - b.z[i])});
    moved_m = std::max(moved_m, std::abs(double(b.z[i]) - z_synced[i]));
  }
  EXPECT_LT(dz_m, 1e-6);
  EXPECT_GT(moved_m, 0.0) << "nothing moved in 10 steps: the test above could not fail";
}

TEST(LiveBackend, CpuRequestedRunsTheCpuBackendWithoutAProbe) {
  hapfluid::log::Capture log;
  hs::LiveBackendOptions options;
  options.backend = "cpu";
  options.threads = 2;
  const hs::LiveBackend b = hs::choose_live_backend(load(kSpoon), options);
  EXPECT_STREQ(b.solver->backend(), "cpu");
  EXPECT_EQ(b.solver->threads(), 2);
  EXPECT_EQ(b.solver->device().name, "2 CPU threads");
  EXPECT_FALSE(b.vulkan_probe.ran);
  EXPECT_FALSE(b.cpu_probe.ran);
  EXPECT_EQ(b.solver->time_s(), 0.0);
  EXPECT_TRUE(log.text().empty()) << log.text();
}

TEST(LiveBackend, AutoStartsTheChosenSolverAtTimeZeroAfterItsProbe) {
  // The probe runs on a throw-away solver: the live run's simulated time starts at 0 whatever
  // was probed, and the probe measured real steps.
  hapfluid::log::Capture log;
  hs::LiveBackendOptions options;
  options.probe_simulated_s = 0.02;
  const hs::LiveBackend b = hs::choose_live_backend(load(kSpoon), options);
  EXPECT_EQ(b.solver->time_s(), 0.0);
  EXPECT_EQ(b.solver->steps(), 0u);
  ASSERT_TRUE(b.vulkan_probe.ran) << log.text();
  EXPECT_GT(b.vulkan_probe.steps, 0u);
  EXPECT_GE(b.vulkan_probe.simulated_s, 0.02);
  // The rule of live_backend.hpp on the measured numbers.
  if (b.vulkan_probe.real_time_factor() >= options.vulkan_min_real_time_factor) {
    EXPECT_STREQ(b.solver->backend(), "vulkan");
    EXPECT_FALSE(b.cpu_probe.ran);
  } else {
    ASSERT_TRUE(b.cpu_probe.ran);
    const bool cpu_faster = b.cpu_probe.real_time_factor() > b.vulkan_probe.real_time_factor();
    EXPECT_STREQ(b.solver->backend(), cpu_faster ? "cpu" : "vulkan");
    EXPECT_NE(log.text().find("NOTICE"), std::string::npos) << log.text();
  }
}

TEST(LiveBackend, AnUnknownBackendIsNamedWithTheKnownOnes) {
  hapfluid::log::Capture log;
  hs::LiveBackendOptions options;
  options.backend = "cuda";
  try {
    hs::choose_live_backend(load(kSpoon), options);
    FAIL() << "no error for --backend cuda";
  } catch (const hs::BackendUnavailable& e) {
    EXPECT_NE(std::string(e.what()).find("--backend cuda: expected cpu, vulkan or auto"), std::string::npos) << e.what();
  }
}
