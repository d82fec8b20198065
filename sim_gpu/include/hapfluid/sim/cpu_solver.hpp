// The CPU reference backend: one SPH step of the unified particle model (Algorithm 1 with the
// rigid-body step of Algorithm 2), multithreaded over particles with a static split so results
// are bit-for-bit repeatable for a given thread count. The oracle of the Vulkan backend.
//
// The stepping API does no I/O: callers set device states, step, and read bodies, couplings and
// particles (batch export, shared-memory publishing in the live sim).
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "hapfluid/sim/model.hpp"
#include "hapfluid/sim/neighbour_lists.hpp"
#include "hapfluid/sim/thread_pool.hpp"

namespace hapfluid::sim {

// Wall-clock seconds spent in each phase, summed over all steps.
struct PhaseTimes {
  double neighbour_search_s = 0;  // counting sort of fluid and body particles by cell
  // eq. 2 and eq. 7 (fluid), contact pressure (bodies); includes the distance checks over the
  // 27 cells that build the neighbour lists (fused with the density sum).
  double density_s = 0;
  double forces_s = 0;            // eqs. 5, 6, 9 on fluid (over the lists) and body particles
  double bodies_s = 0;            // eqs. 10-14, couplings (Algorithm 2)
  double integration_s = 0;       // fluid leap-frog
};

class CpuSolver {
 public:
  CpuSolver(SimulationModel model, int threads);

  const SimulationModel& model() const { return m_; }
  const SimulationParams& params() const { return m_.params; }
  double time_s() const { return time_s_; }
  std::uint64_t steps() const { return steps_; }
  int threads() const { return pool_.size(); }
  const PhaseTimes& phase_times() const { return times_; }
  // Fluid particles the domain-box clamp had to put back (0 when the walls hold the fluid).
  std::uint64_t clamped_particle_count() const { return clamped_; }

  // Device poses for the couplings, set before each step (scripted motion or live devices).
  void set_device_state(std::size_t device, const DeviceState& state);
  const std::vector<DeviceState>& device_states() const { return devices_; }

  // Largest stable step for the current state: CFL on the speed of sound and the fastest
  // particle, the viscous and force limits, the scene's max_dt_s (or the scene's fixed dt_s).
  double stable_time_step() const;
  // One step of dt seconds.
  void step(double dt);
  // Advances by `duration_s` in equal substeps no longer than stable_time_step(); returns the
  // number of substeps. before_substep(t), when given, runs before each substep with the
  // substep's start time (the caller sets device states there); otherwise they are held.
  int advance(double duration_s, const std::function<void(double)>& before_substep = {});

  // Throws std::runtime_error naming the first particle or body whose state is not finite
  // (check_finite_state).
  void check_finite() const;

 private:
  void sort_fluid();
  void build_body_view();
  void compute_density(std::size_t begin, std::size_t end, int worker);
  void compute_body_contact_pressure(std::size_t begin, std::size_t end);
  void compute_fluid_forces(std::size_t begin, std::size_t end, int worker);
  void compute_body_particle_forces(std::size_t begin, std::size_t end);
  void step_bodies(double dt);
  void integrate_fluid(std::size_t begin, std::size_t end, int worker, float dt);

  SimulationModel m_;
  ThreadPool pool_;
  CellSort fluid_sort_, body_sort_;
  SortedSolids body_view_;  // dynamic body particles sorted by cell (rebuilt each step)
  std::vector<DeviceState> devices_;
  std::vector<std::vector<VirtualCoupling*>> couplings_of_body_;
  std::vector<float> worker_max_accel_;
  std::vector<std::uint64_t> worker_clamped_;
  std::vector<detail::NeighbourLists> neighbour_lists_;  // one per worker
  std::vector<detail::NeighbourRange> neighbour_ranges_;  // one per fluid particle
  double time_s_ = 0;
  std::uint64_t steps_ = 0;
  std::uint64_t clamped_ = 0;
  PhaseTimes times_;
};

}  // namespace hapfluid::sim
