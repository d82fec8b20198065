// Runs the CPU backend's validation tests (tests/sim_gpu/test_*.cpp), unchanged, on the Vulkan
// backend: the same validation physics must hold on both, so the test bodies, scenes,
// durations and criteria are the CPU suite's own source, compiled a second time with
// `CpuSolver` standing for VulkanBackendSolver below, and `make_cpu_solver` making one. A change to a CPU validation test changes
// its Vulkan run with it; nothing is restated here.
//
// Use, in a translation unit of its own (the CPU files each have their own anonymous helpers):
//
//   #include "cpu_suite_on_vulkan.hpp"   // first: it includes gtest itself
//   #include "../sim_gpu/test_hydrostatic.cpp"
//
// Every TEST(Suite, Name) of the included file registers as VulkanSuite.Name. The Khronos
// validation layer is on for every solver, and a solver that saw any validation error or
// warning fails the test it ran in.
#pragma once

// gtest's TEST is redefined below to prefix the suite name; it must not define its own.
#define GTEST_DONT_DEFINE_TEST 1
#include <gtest/gtest.h>

#include <functional>
#include <memory>
#include <string>

// The CPU suite's helpers (temporary scenes, test meshes, run_for on a CpuSolver), included
// before CpuSolver is redirected so that they keep their CPU meaning; Vulkan overloads follow.
#include "../sim_gpu/test_support.hpp"
#include "hapfluid/sim/cpu_solver.hpp"
#include "hapfluid/sim_vulkan/vulkan_solver.hpp"

namespace hapfluid::sim {

// CpuSolver's interface (the part the validation tests use) and the Solver interface on the
// Vulkan backend. model() reflects the device after every step/advance: the particles are
// downloaded then (a few thousand in these scenes, small next to the steps of a frame), as the
// tests read them.
class VulkanBackendSolver final : public Solver {
 public:
  // `threads` is the CPU backend's worker count; the device has its own parallelism.
  VulkanBackendSolver(SimulationModel model, int /*threads*/) : gpu_(std::move(model), validated()) {}
  ~VulkanBackendSolver() override {
    const auto counts = gpu_.context().validation_counts();
    EXPECT_EQ(counts.errors, 0u) << "Khronos validation errors on " << gpu_.device().name;
    EXPECT_EQ(counts.warnings, 0u) << "Khronos validation warnings on " << gpu_.device().name;
    for (const auto& m : gpu_.context().validation_messages()) ADD_FAILURE() << m;
  }
  VulkanBackendSolver(const VulkanBackendSolver&) = delete;
  VulkanBackendSolver& operator=(const VulkanBackendSolver&) = delete;

  const SimulationModel& model() const override { return gpu_.model(); }
  double time_s() const override { return gpu_.time_s(); }
  std::uint64_t steps() const override { return gpu_.steps(); }
  std::uint64_t clamped_particle_count() const override { return gpu_.clamped_particle_count(); }
  double stable_time_step() const override { return gpu_.stable_time_step(); }
  void set_device_state(std::size_t device, const DeviceState& state) override { gpu_.set_device_state(device, state); }
  PhaseTimes phase_times() const override { return gpu_.phase_times(); }
  SolverIterations iterations() const override { return gpu_.iterations(); }
  const char* backend() const override { return gpu_.backend(); }
  ComputeDevice device() const override { return gpu_.device(); }
  int threads() const override { return gpu_.threads(); }

  void step(double dt) override {
    gpu_.step(dt);
    gpu_.sync_particles();
  }
  int advance(double duration_s, const std::function<void(double)>& before_substep = {}) override {
    const int substeps = gpu_.advance(duration_s, before_substep);
    gpu_.sync_particles();
    return substeps;
  }
  void check_finite() { gpu_.check_finite(); }
  void sync_and_check_finite() override { gpu_.check_finite(); }

  const vulkan::VulkanSolver& vulkan() const { return gpu_; }

 private:
  static vulkan::VulkanSolverOptions validated() {
    vulkan::VulkanSolverOptions o;
    o.context.validation = true;
    return o;
  }
  vulkan::VulkanSolver gpu_;
};

namespace test {

// test_support.hpp's solver helpers, for the Vulkan solver (same definitions).
inline double fluid_kinetic_energy(const VulkanBackendSolver& s) {
  const auto& f = s.model().fluid;
  double e = 0;
  for (std::size_t i = 0; i < f.size(); ++i) e += f.vx[i] * f.vx[i] + f.vy[i] * f.vy[i] + f.vz[i] * f.vz[i];
  return 0.5 * s.params().fluid_particle_mass_kg * e;
}

inline void run_for(VulkanBackendSolver& s, double seconds, double frame = 0.01) {
  const int frames = static_cast<int>(std::lround(seconds / frame));
  for (int k = 0; k < frames; ++k) s.advance(frame);
}

}  // namespace test
}  // namespace hapfluid::sim

namespace hapfluid::sim {
// make_cpu_solver of the CPU suite: the Vulkan backend, for either method.
inline std::unique_ptr<Solver> make_vulkan_suite_solver(SimulationModel model, int threads) {
  return std::make_unique<VulkanBackendSolver>(std::move(model), threads);
}
}  // namespace hapfluid::sim

// From here on, the CPU suite's source runs on the device.
#define CpuSolver VulkanBackendSolver
#define make_cpu_solver make_vulkan_suite_solver
#define TEST(suite, name) GTEST_TEST(Vulkan##suite, name)
