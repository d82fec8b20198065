// The CPU reference backend of the paper's method (WCSPH): one SPH step of the unified particle
// model (Algorithm 1 with the rigid-body step of Algorithm 2), multithreaded over particles with a static split so results
// are bit-for-bit repeatable for a given thread count. The oracle of the Vulkan backend.
//
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "hapfluid/sim/body_reach.hpp"
#include "hapfluid/sim/model.hpp"
#include "hapfluid/sim/neighbour_lists.hpp"
#include "hapfluid/sim/solver.hpp"
#include "hapfluid/sim/thread_pool.hpp"

namespace hapfluid::sim {

class CpuSolver final : public Solver {
 public:
  CpuSolver(SimulationModel model, int threads);

  const SimulationModel& model() const override { return m_; }
  double time_s() const override { return time_s_; }
  std::uint64_t steps() const override { return steps_; }
  int threads() const override { return pool_.size(); }
  void set_active_threads(int n) override { pool_.set_active(n); }
  int active_threads() const override { return pool_.active(); }
  PhaseTimes phase_times() const override { return times_; }
  std::uint64_t clamped_particle_count() const override { return clamped_; }

  void set_device_state(std::size_t device, const DeviceState& state) override;
  const std::vector<DeviceState>& device_states() const { return devices_; }

  // CFL on the speed of sound and the fastest particle, the viscous and force limits.
  double stable_time_step() const override;
  void step(double dt) override;

  void sync_and_check_finite() override { check_finite(); }
  // Throws std::runtime_error naming the first particle or body whose state is not finite
  // (check_finite_state).
  void check_finite() const;
  const char* backend() const override { return "cpu"; }
  ComputeDevice device() const override;

 private:
  void sort_fluid();
  void build_body_view();
  void compute_density(std::size_t begin, std::size_t end, int slot);
  void compute_fluid_forces(std::size_t begin, std::size_t end, int slot);
  void compute_body_particle_forces(std::size_t begin, std::size_t end);
  void integrate_fluid(std::size_t begin, std::size_t end, int slot, float dt);

  SimulationModel m_;
  ThreadPool pool_;
  CellSort fluid_sort_, body_sort_;
  SortedSolids body_view_;  // dynamic body particles sorted by cell (rebuilt each step)
  detail::BodyReach body_reach_;
  std::vector<DeviceState> devices_;
  std::vector<std::vector<VirtualCoupling*>> couplings_of_body_;
  std::vector<float> slot_max_accel_;
  std::vector<std::uint64_t> slot_clamped_;
  std::vector<detail::NeighbourLists> neighbour_lists_;  // one per slot
  std::vector<detail::NeighbourRange> neighbour_ranges_;  // one per fluid particle
  double time_s_ = 0;
  std::uint64_t steps_ = 0;
  std::uint64_t clamped_ = 0;
  PhaseTimes times_;
};

}  // namespace hapfluid::sim
