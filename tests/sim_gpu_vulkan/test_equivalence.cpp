// The Vulkan backend equals the CPU reference (the oracle) to float tolerance after a
// few steps, and stays statistically equivalent over longer runs. Both backends start from the
// same model (the CPU reference's scene set-up) and take the same time steps.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "hapfluid/config/scene.hpp"
#include "hapfluid/sim/cpu_solver.hpp"
#include "hapfluid/sim/model.hpp"
#include "hapfluid/sim/solver.hpp"
#include "hapfluid/sim_vulkan/vulkan_solver.hpp"

namespace hs = hapfluid::sim;
namespace hv = hapfluid::sim::vulkan;

namespace {

std::filesystem::path scene_path(const std::string& relative) { return std::filesystem::path(HAPFLUID_SOURCE_DIR) / relative; }

hv::VulkanSolverOptions validated() {
  hv::VulkanSolverOptions o;
  o.context.validation = true;
  return o;
}

void expect_no_validation_messages(const hv::VulkanSolver& gpu) {
  const auto counts = gpu.context().validation_counts();
  EXPECT_EQ(counts.errors, 0u);
  EXPECT_EQ(counts.warnings, 0u);
  for (const auto& m : gpu.context().validation_messages()) ADD_FAILURE() << m;
}

struct Difference {
  double position_m = 0, velocity_m_s = 0, density_kg_m3 = 0, max_speed_m_s = 0;
  double volume_correction = 0;  // 1 / c of the pressure force (gradient_correction.hpp), dimensionless
  bool same_order = true;
};

// Particle by particle in `a`'s order; `by_id`: b's particles found by their id (b may be in
// another order).
Difference compare(const hs::FluidParticles& a, const hs::FluidParticles& b_in, bool by_id = false) {
  hs::FluidParticles reordered;
  if (by_id) {
    std::vector<std::uint32_t> order(b_in.size());
    for (std::size_t i = 0; i < b_in.size(); ++i) order[b_in.id[i]] = static_cast<std::uint32_t>(i);
    std::vector<std::uint32_t> at(a.size());
    for (std::size_t i = 0; i < a.size(); ++i) at[i] = order[a.id[i]];
    reordered = b_in;
    for (auto* v : {&reordered.x, &reordered.y, &reordered.z, &reordered.vx, &reordered.vy, &reordered.vz,
                    &reordered.density, &reordered.volume_correction}) {
      const std::vector<float> source = *v;
      for (std::size_t i = 0; i < at.size(); ++i) (*v)[i] = source[at[i]];
    }
    reordered.id = a.id;
  }
  const hs::FluidParticles& b = by_id ? reordered : b_in;
  Difference d;
  for (std::size_t i = 0; i < a.size(); ++i) {
    d.same_order = d.same_order && a.id[i] == b.id[i];
    d.position_m = std::max({d.position_m, std::abs(double(a.x[i]) - b.x[i]), std::abs(double(a.y[i]) - b.y[i]),
                             std::abs(double(a.z[i]) - b.z[i])});
    d.velocity_m_s = std::max({d.velocity_m_s, std::abs(double(a.vx[i]) - b.vx[i]), std::abs(double(a.vy[i]) - b.vy[i]),
                               std::abs(double(a.vz[i]) - b.vz[i])});
    d.density_kg_m3 = std::max(d.density_kg_m3, std::abs(double(a.density[i]) - b.density[i]));
    d.volume_correction =
        std::max(d.volume_correction, std::abs(double(a.volume_correction[i]) - b.volume_correction[i]));
    d.max_speed_m_s = std::max(d.max_speed_m_s, std::sqrt(double(a.vx[i]) * a.vx[i] + double(a.vy[i]) * a.vy[i] +
                                                           double(a.vz[i]) * a.vz[i]));
  }
  return d;
}

// Runs both backends `steps` steps with the CPU's time step and returns the difference.
Difference run_both(const std::string& scene, int steps, double* out_dt = nullptr) {
  const hs::SimulationModel model = hs::build_model(hapfluid::config::load_scene(scene_path(scene)));
  hs::CpuSolver cpu(model, 1);
  hv::VulkanSolver gpu(model, validated());
  for (int s = 0; s < steps; ++s) {
    const double dt = cpu.stable_time_step();
    // The CFL inputs (maxima over particles) come from the device: the same bound, up to the
    // float rounding of the fastest particle's speed and acceleration.
    EXPECT_NEAR(gpu.stable_time_step(), dt, 1e-5 * dt) << "step " << s;
    cpu.step(dt);
    gpu.step(dt);
    if (out_dt) *out_dt = dt;
  }
  gpu.sync_particles();
  EXPECT_EQ(gpu.model().fluid.size(), cpu.model().fluid.size());
  expect_no_validation_messages(gpu);
  const Difference d = compare(cpu.model().fluid, gpu.model().fluid);
  std::printf("%s: %zu fluid particles, %d steps on %s: max |dx| = %.3g m, |dv| = %.3g m/s, |drho| = %.3g kg/m^3, "
              "|d(1/c)| = %.3g, max speed %.3g m/s\n",
              scene.c_str(), model.fluid.size(), steps, gpu.device().name.c_str(), d.position_m, d.velocity_m_s,
              d.density_kg_m3, d.volume_correction, d.max_speed_m_s);
  return d;
}

}  // namespace

TEST(VulkanEquivalence, HydrostaticTankEqualsCpuAfterTenSteps) {
  // Same kernels, same boundary particles, same sort order, same summation order: after 10
  // steps the only differences are float rounding (fused multiply-adds on the device). 1e-7 m
  // is 1e-5 of the 1 cm spacing; velocities differ by far less than gravity changes them in a
  // step (9.81 m/s^2 * 0.4 ms = 4 mm/s).
  const Difference d = run_both("tests/sim_gpu/scenes/hydrostatic_tank.toml", 10);
  EXPECT_TRUE(d.same_order) << "the device's counting sort must order particles like the CPU's stable sort";
  EXPECT_LT(d.position_m, 1e-7);
  EXPECT_LT(d.velocity_m_s, 1e-4);
  EXPECT_LT(d.density_kg_m3, 0.05);  // of 1000 kg/m^3
  EXPECT_LT(d.volume_correction, 1e-5);  // of ~1.04: the first-moment sums agree to float rounding
}

TEST(VulkanEquivalence, DamBreakEqualsCpuAfterTwentySteps) {
  // A violent flow: particles cross cells, hit the walls, the pressure field is far from
  // hydrostatic. Still float-rounding equal after 20 steps.
  const Difference d = run_both("tests/sim_gpu_vulkan/scenes/dam_break_small.toml", 20);
  EXPECT_TRUE(d.same_order);
  EXPECT_LT(d.position_m, 1e-6);
  EXPECT_LT(d.velocity_m_s, 1e-3);
  EXPECT_LT(d.density_kg_m3, 0.5);
  EXPECT_LT(d.volume_correction, 1e-4);
}

namespace {
double distance(const hs::Vec3& a, const hs::Vec3& b) { return hs::norm(a - b); }
}  // namespace

TEST(VulkanEquivalence, CoupledSpoonBodyForcesEqualCpuAfterTwentySteps) {
  // The rigid-body path: body particles sorted on the device, fluid<->body forces with the
  // body's viscosity (eq. 9), the per-body tree reduction (eqs. 10-12), the host's implicit body
  // step with the coupling, eq. 14 on the device. The spoon sits in the fluid held by the
  // scripted hand. Forces are sums over ~1000 particles reduced as a float tree on the device
  // and in double in particle order on the CPU: equal to 1e-4 relative.
  const hs::SimulationModel model =
      hs::build_model(hapfluid::config::load_scene(scene_path("tests/sim_gpu_vulkan/scenes/spoon_small.toml")));
  ASSERT_GT(model.body_particles.size(), 100u);
  hs::CpuSolver cpu(model, 1);
  hv::VulkanSolver gpu(model, validated());
  for (int s = 0; s < 20; ++s) {
    const double dt = cpu.stable_time_step();
    EXPECT_NEAR(gpu.stable_time_step(), dt, 1e-5 * dt) << "step " << s;
    cpu.step(dt);
    gpu.step(dt);
  }
  const hs::RigidBody& a = cpu.model().bodies[0];
  const hs::RigidBody& b = gpu.model().bodies[0];
  const double force_scale = std::max(hs::norm(a.fluid_force), 1e-3), torque_scale = std::max(hs::norm(a.fluid_torque), 1e-4);
  std::printf("spoon after 20 steps: fluid force cpu %.6g N gpu %.6g N, torque cpu %.6g gpu %.6g N m, |dx| %.3g m\n",
              hs::norm(a.fluid_force), hs::norm(b.fluid_force), hs::norm(a.fluid_torque), hs::norm(b.fluid_torque),
              distance(a.position, b.position));
  EXPECT_GT(hs::norm(a.fluid_force), 0.01) << "the spoon must feel the fluid, or the comparison proves nothing";
  EXPECT_LT(distance(a.fluid_force, b.fluid_force), 1e-4 * force_scale);
  EXPECT_LT(distance(a.fluid_torque, b.fluid_torque), 1e-4 * torque_scale);
  EXPECT_LT(distance(a.position, b.position), 1e-7);
  EXPECT_LT(distance(a.linear_velocity, b.linear_velocity), 1e-5);
  const auto& ca = cpu.model().couplings[0];
  const auto& cb = gpu.model().couplings[0];
  EXPECT_LT(distance(ca.device_force, cb.device_force), 1e-4 * std::max(hs::norm(ca.device_force), 1e-3));
  EXPECT_LT(distance(ca.device_torque, cb.device_torque), 1e-4 * std::max(hs::norm(ca.device_torque), 1e-4));

  gpu.sync_particles();
  const Difference d = compare(cpu.model().fluid, gpu.model().fluid);
  EXPECT_TRUE(d.same_order);
  EXPECT_LT(d.position_m, 1e-6);
  EXPECT_LT(d.velocity_m_s, 1e-3);
  double body_particle_dx = 0;
  const auto& pa = cpu.model().body_particles;
  const auto& pb = gpu.model().body_particles;
  for (std::size_t i = 0; i < pa.size(); ++i)
    body_particle_dx = std::max({body_particle_dx, std::abs(double(pa.x[i]) - pb.x[i]), std::abs(double(pa.y[i]) - pb.y[i]),
                                 std::abs(double(pa.z[i]) - pb.z[i])});
  EXPECT_LT(body_particle_dx, 1e-6);
  expect_no_validation_messages(gpu);
}

TEST(VulkanEquivalence, TwoSpheresInContactEqualCpuStepByStep) {
  // Body<->body contact: each sphere's contact pressure comes from the other's particles (and
  // the walls'), and the contact force pushes them apart within a few steps. At every step
  // both bodies' contact and fluid forces and torques equal the CPU's to 1e-4 relative, and
  // their positions to 0.1 micrometre.
  const hs::SimulationModel model =
      hs::build_model(hapfluid::config::load_scene(scene_path("tests/sim_gpu_vulkan/scenes/two_spheres_small.toml")));
  ASSERT_EQ(model.bodies.size(), 2u);
  hs::CpuSolver cpu(model, 1);
  hv::VulkanSolver gpu(model, validated());
  double largest_contact_n = 0;
  for (int s = 0; s < 10; ++s) {
    const double dt = cpu.stable_time_step();
    cpu.step(dt);
    gpu.step(dt);
    for (std::size_t b = 0; b < 2; ++b) {
      const hs::RigidBody& a = cpu.model().bodies[b];
      const hs::RigidBody& g = gpu.model().bodies[b];
      largest_contact_n = std::max(largest_contact_n, hs::norm(a.contact_force));
      EXPECT_LT(distance(a.contact_force, g.contact_force), 1e-4 * std::max(hs::norm(a.contact_force), 1e-3))
          << a.name << ", step " << s;
      // The contact torque nearly cancels (the push is through the centres): its rounding is
      // that of terms of size force x radius (0.035 m), not of the small total.
      const double torque_scale = std::max(hs::norm(a.contact_torque), 0.035 * hs::norm(a.contact_force));
      EXPECT_LT(distance(a.contact_torque, g.contact_torque), 1e-4 * std::max(torque_scale, 1e-5))
          << a.name << ", step " << s;
      // The fluid force is a sum of pressure terms of the order of the buoyancy (~ the weight)
      // that partly cancel: its rounding scales with the weight, not with the small total.
      const double weight_n = a.mass_kg * 9.81;
      EXPECT_LT(distance(a.fluid_force, g.fluid_force), 1e-4 * std::max(hs::norm(a.fluid_force), weight_n))
          << a.name << ", step " << s;
      EXPECT_LT(distance(a.position, g.position), 1e-7) << a.name << ", step " << s;
    }
  }
  std::printf("two spheres: largest contact force %.4g N\n", largest_contact_n);
  EXPECT_GT(largest_contact_n, 0.01) << "the spheres must touch, or contact was not compared";
  expect_no_validation_messages(gpu);
}

TEST(VulkanEquivalence, AdvanceSetsDevicePosesBeforeEverySubstep) {
  // advance(duration, before_substep) is how a batch run or test moves a device during a frame
  // (as CpuSolver::advance): the callback runs once before each substep with that substep's
  // start time, and the run equals setting the pose and stepping by hand.
  const hs::SimulationModel model =
      hs::build_model(hapfluid::config::load_scene(scene_path("tests/sim_gpu_vulkan/scenes/spoon_small.toml")));
  ASSERT_EQ(model.devices.size(), 1u);
  hv::VulkanSolver by_callback(model, validated());
  hv::VulkanSolver by_hand(model, validated());
  auto pose_at = [&](double t) { return hs::device_state_from(hapfluid::config::evaluate_motion(model.devices[0].motion, t)); };
  const double frame = 1.0 / 60;
  std::vector<double> starts;
  const int substeps = by_callback.advance(frame, [&](double t) {
    starts.push_back(t);
    by_callback.set_device_state(0, pose_at(t));
  });
  ASSERT_GE(substeps, 2) << "a frame of several substeps, or the per-substep poses were not exercised";
  ASSERT_EQ(starts.size(), static_cast<std::size_t>(substeps));
  const double dt = frame / substeps;
  for (int i = 0; i < substeps; ++i) {
    EXPECT_NEAR(starts[i], i * dt, 1e-12) << "substep " << i;
    by_hand.set_device_state(0, pose_at(i * dt));
    by_hand.step(dt);
  }
  EXPECT_NEAR(by_callback.time_s(), frame, 1e-12);
  const hs::RigidBody& a = by_hand.model().bodies[0];
  const hs::RigidBody& b = by_callback.model().bodies[0];
  EXPECT_EQ(distance(a.position, b.position), 0.0);
  EXPECT_EQ(distance(a.linear_velocity, b.linear_velocity), 0.0);
  EXPECT_EQ(distance(by_hand.model().couplings[0].device_force, by_callback.model().couplings[0].device_force), 0.0);
  EXPECT_GT(hs::norm(a.linear_velocity), 0.0) << "the hand must have moved the spoon";
  expect_no_validation_messages(by_callback);
  expect_no_validation_messages(by_hand);
}

namespace {

// The incompressible solver on both backends, `steps` steps of the CPU's time step, against the
// CPU's own sensitivity to rounding. Its solves stop on thresholds (a particle compresses or
// not, a mean error is below its tolerance or not) and turn density errors, small differences
// of sums near 1, into pressures, so a flow amplifies rounding differences within a few steps.
// The scale for "equal" is therefore the CPU run again from the same state with every x
// coordinate moved by one float step (the smallest change a float state can take): the device
// sums in another order every step, so it may stray further than that one-time change, but by
// rounding alone not by an order of magnitude more; a wrong term in a pass shows as differences
// of the flow's own size (millimetres, cm/s). Particles are matched by id: a particle on a
// cell boundary may sort to the other cell. A solve whose mean error lands within rounding of its
// tolerance may stop one iteration apart on the two backends: at most one per solve.
struct DfsphRun {
  Difference gpu, one_ulp;
  hs::SolverIterations cpu_its, gpu_its;
};

DfsphRun run_both_dfsph(const std::string& scene, int steps) {
  hs::SimulationModel model = hs::build_model(hapfluid::config::load_scene(scene_path(scene)));
  EXPECT_EQ(model.params.solver, hapfluid::config::PressureSolver::dfsph);
  const auto cpu = hs::make_cpu_solver(model, 1);
  hv::VulkanSolver gpu(model, validated());
  for (float& x : model.fluid.x) x = std::nextafter(x, 1.0f);
  const auto moved = hs::make_cpu_solver(model, 1);
  for (int s = 0; s < steps; ++s) {
    const double dt = cpu->stable_time_step();
    EXPECT_NEAR(gpu.stable_time_step(), dt, 1e-5 * dt) << "step " << s;
    cpu->step(dt);
    gpu.step(dt);
    moved->step(dt);
  }
  cpu->sync_and_check_finite();
  moved->sync_and_check_finite();
  gpu.sync_particles();
  expect_no_validation_messages(gpu);
  DfsphRun r{compare(cpu->model().fluid, gpu.model().fluid, true), compare(cpu->model().fluid, moved->model().fluid, true),
             cpu->iterations(), gpu.iterations()};
  std::printf("%s: %zu fluid particles, %d steps on %s: max |dx| = %.3g m (cpu moved by one ulp: %.3g), |dv| = %.3g m/s "
              "(%.3g), |drho| = %.3g kg/m^3 (%.3g), max speed %.3g m/s; iterations cpu/gpu: density %llu/%llu, "
              "divergence %llu/%llu, viscosity %llu/%llu, explicit viscous steps %llu/%llu\n",
              scene.c_str(), model.fluid.size(), steps, gpu.device().name.c_str(), r.gpu.position_m, r.one_ulp.position_m,
              r.gpu.velocity_m_s, r.one_ulp.velocity_m_s, r.gpu.density_kg_m3, r.one_ulp.density_kg_m3,
              r.gpu.max_speed_m_s, static_cast<unsigned long long>(r.cpu_its.density_iterations),
              static_cast<unsigned long long>(r.gpu_its.density_iterations),
              static_cast<unsigned long long>(r.cpu_its.divergence_iterations),
              static_cast<unsigned long long>(r.gpu_its.divergence_iterations),
              static_cast<unsigned long long>(r.cpu_its.viscosity_iterations),
              static_cast<unsigned long long>(r.gpu_its.viscosity_iterations),
              static_cast<unsigned long long>(r.cpu_its.explicit_viscosity_steps),
              static_cast<unsigned long long>(r.gpu_its.explicit_viscosity_steps));
  EXPECT_LT(r.gpu.position_m, 10 * r.one_ulp.position_m);
  EXPECT_LT(r.gpu.velocity_m_s, 10 * r.one_ulp.velocity_m_s);
  EXPECT_LT(r.gpu.density_kg_m3, 10 * r.one_ulp.density_kg_m3);
  auto apart = [](std::uint64_t a, std::uint64_t b) { return a > b ? a - b : b - a; };
  const std::uint64_t solves = static_cast<std::uint64_t>(steps);
  EXPECT_LE(apart(r.gpu_its.density_iterations, r.cpu_its.density_iterations), solves);
  EXPECT_LE(apart(r.gpu_its.divergence_iterations, r.cpu_its.divergence_iterations), solves);
  EXPECT_LE(apart(r.gpu_its.viscosity_iterations, r.cpu_its.viscosity_iterations), solves);
  EXPECT_EQ(r.gpu_its.explicit_viscosity_steps, r.cpu_its.explicit_viscosity_steps);
  EXPECT_EQ(r.gpu_its.unconverged_solves, r.cpu_its.unconverged_solves);
  return r;
}

}  // namespace

TEST(VulkanEquivalence, DfsphDamBreakAgainstAFixedSphereEqualsCpuAfterFiveSteps) {
  // Water: the walls' volume map, the sphere's particles, both pressure solves iterating on the
  // device, the explicit viscous step.
  const DfsphRun r = run_both_dfsph("tests/sim_gpu_vulkan/scenes/dam_break_small_dfsph.toml", 5);
  EXPECT_GT(r.cpu_its.density_iterations, 5u) << "the density solve must iterate, or its passes were not compared";
  EXPECT_EQ(r.cpu_its.explicit_viscosity_steps, 5u);
  EXPECT_GT(r.gpu.max_speed_m_s, 0.1) << "the column must be falling";
}

TEST(VulkanEquivalence, DfsphXsphEqualsCpuAfterFiveSteps) {
  // The same surge with a strong XSPH (0.3): its pass over the neighbour lists, recomputing each
  // pair's kernel value from the positions, as the CPU's.
  const DfsphRun r = run_both_dfsph("tests/sim_gpu_vulkan/scenes/dam_break_small_dfsph_xsph.toml", 5);
  EXPECT_GT(r.gpu.max_speed_m_s, 0.1) << "the column must be falling";
}

TEST(VulkanEquivalence, DfsphViscousTankEqualsCpuAfterSettlingAndFiveSteps) {
  // 1 Pa s: each step's viscosity is a conjugate-gradient solve on the device, with the walls'
  // friction on its diagonal; the settling run before t = 0 damps the velocities on both.
  const DfsphRun r = run_both_dfsph("tests/sim_gpu_vulkan/scenes/viscous_tank_dfsph.toml", 5);
  EXPECT_EQ(r.cpu_its.explicit_viscosity_steps, 0u);
  EXPECT_GT(r.cpu_its.viscosity_iterations, 5u) << "the viscosity must be solved, or the CG passes were not compared";
}
