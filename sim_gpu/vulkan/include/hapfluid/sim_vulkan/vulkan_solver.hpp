// The Vulkan compute backend: the same step as CpuSolver (hapfluid/sim/cpu_solver.hpp) with the
// particle work on the device (§3.3, §4.3). The scene set-up (particles, walls, mesh sampling,
// mass properties, couplings) is the CPU reference's build_model; only the step is replaced.
//
// Per step on the device: hashing into the uniform grid, counting sort by cell (atomic counts,
// a three-dispatch prefix scan, scatter, per-cell ordering by particle index so the order equals
// the CPU's stable sort), density (eqs. 2, 7), forces (eqs. 5, 6, 9), fluid leap-frog. Without
// dynamic bodies the substeps of a frame are one command buffer (recorded once per substep
// count, then re-submitted); only the CFL inputs (two maxima) come back per frame, and the
// particles only when sync_particles() is called (frame export, publishing).
//
// fluid.solver = "dfsph" runs the incompressible solver of dfsph_solver.hpp pass by pass
// (dfsph_recording.cpp): the walls as their volume map, static bodies as particles, both pressure
// solves and the viscosity solve iterating on the device to their tolerances within the one
// submission. Dynamic bodies are not on the device yet with this method.
//
// With dynamic bodies each step is two submissions: the device computes the body particles'
// forces and reduces them per body (eqs. 10-12, two-pass tree reduction of §4.3); the host reads
// back those few numbers, integrates each body with the couplings (Algorithm 2, lines 6-9:
// CpuSolver's integrate_body, a 6x6 implicit solve in double) and writes the body states; the
// device then moves the rigid particles (eq. 14) and integrates the fluid. Per step only the
// per-body sums come back, which is also what the 1 kHz loop needs.
//
// It is a sim::Solver: batch runs, the live sim, benches and tests drive it as they drive the
// CPU solvers.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "hapfluid/sim/cpu_solver.hpp"
#include "hapfluid/sim/model.hpp"
#include "hapfluid/sim/solver.hpp"
#include "hapfluid/sim_vulkan/compute_program.hpp"
#include "hapfluid/sim_vulkan/iteration_budget.hpp"
#include "hapfluid/sim_vulkan/base.hpp"

namespace hapfluid::sim::vulkan {

struct VulkanSolverOptions {
  ContextOptions context;
  bool timestamps = true;  // per-pass GPU timing (where the queue supports timestamps)
};

// GPU time per pass group, summed over all steps (timestamp queries), in seconds.
struct PassTimes {
  double sort_s = 0;        // hash, prefix scan, scatter, in-cell order, gather
  double density_s = 0;
  double forces_s = 0;
  double pressure_s = 0;    // dfsph: divergence-free and constant-density solves
  double integration_s = 0;
  double bodies_s = 0;      // body contact pressure, body forces, per-body reductions, eq. 14
  double reductions_s = 0;  // CFL maxima
  std::uint64_t steps = 0;
};

// Commands and host round trips of the steps taken (benchmarks, stats.json): the dispatches and
// barriers recorded in the command buffers submitted (an indirect dispatch may run with no
// workgroups), the submissions and the host's fence waits.
struct StepWork {
  std::uint64_t dispatches = 0, indirect_dispatches = 0, barriers = 0, submissions = 0, host_waits = 0;
};

class VulkanSolver final : public Solver {
 public:
  // Throws VulkanUnavailable when no usable Vulkan device exists, std::runtime_error when the
  // model uses something this backend does not run.
  VulkanSolver(SimulationModel model, const VulkanSolverOptions& options);
  ~VulkanSolver() override;
  VulkanSolver(const VulkanSolver&) = delete;
  VulkanSolver& operator=(const VulkanSolver&) = delete;

  // The model; its particle arrays are those of the last sync_particles() call.
  const SimulationModel& model() const override { return m_; }
  double time_s() const override { return time_s_; }
  std::uint64_t steps() const override { return steps_; }
  // Fluid particles the domain-box clamp put back, summed over all steps (as CpuSolver).
  std::uint64_t clamped_particle_count() const override { return clamped_; }
  const DeviceDescription& device_description() const { return context_->description(); }
  ComputeDevice device() const override {
    const DeviceDescription& d = device_description();
    return {d.name, d.type, d.driver};
  }
  const char* backend() const override { return "vulkan"; }
  int threads() const override { return 0; }
  const Context& context() const { return *context_; }

  void set_device_state(std::size_t device, const DeviceState& state) override;

  // Same bound as CpuSolver::stable_time_step, from maxima computed on the device.
  double stable_time_step() const override;
  void step(double dt) override { step_many(dt, 1); }
  // `substeps` steps of dt in one submission.
  void step_many(double dt, int substeps);
  // Advances by `duration_s` in equal substeps no longer than stable_time_step() (as
  // Solver::advance); returns the number of substeps. With before_substep the substeps are
  // submitted one by one; without it the frame is one submission where the scene allows (no
  // dynamic bodies) and device states are held.
  int advance(double duration_s, const std::function<void(double)>& before_substep = {}) override;

  // Downloads fluid particles (position, velocity, acceleration, density, pressure, volume,
  // viscosity, id) into model(), in the device's current (cell-sorted) order.
  void sync_particles();
  // Throws std::runtime_error naming the first non-finite particle or body (syncs first;
  // check_finite_state).
  void check_finite();
  void sync_and_check_finite() override { check_finite(); }

  // Per-pass GPU times and the same split as the CPU backend's PhaseTimes (sort is the
  // neighbour search; reductions count as integration).
  const PassTimes& pass_times() const { return pass_times_; }
  // Since the first step (after settling).
  const StepWork& work() const { return work_; }
  PhaseTimes phase_times() const override;
  // dfsph: the iterations of the solves, read back with each submission's results.
  SolverIterations iterations() const override { return iterations_; }

 private:
  void check_device_limits() const;
  void create_buffers();
  void upload_model();
  void write_params(float dt);
  VkCommandBuffer command_buffer_for(int substeps);
  void record_steps(VkCommandBuffer cb, int substeps);
  void record_sort(VkCommandBuffer cb);
  void record_body_sort(VkCommandBuffer cb);
  void step_with_bodies(double dt, bool last_of_frame);
  void integrate_bodies(double dt);
  void write_body_states();
  VkCommandBuffer allocate_command_buffer();
  void record_maxima(VkCommandBuffer cb);
  // The incompressible solver (dfsph_recording.cpp).
  void record_dfsph_initial(VkCommandBuffer cb);
  void record_dfsph_step(VkCommandBuffer cb, const std::function<void()>& stamp);
  void record_pressure_solve(VkCommandBuffer cb, bool density, int budget);
  void record_viscosity_solve(VkCommandBuffer cb, int budget);
  const Buffer& dfsph_solve_buffer() const;
  // fluid.settle_s, as DfsphSolver::settle: steps at max_dt_s keeping part of the velocity, then
  // the clock, counters and timings start from zero.
  void settle(double duration_s);
  void read_solver_counters();
  // Records the head (may be null) and the tail of a body step; the tail computes the CFL
  // maxima when `with_maxima` (the last substep of a frame).
  void record_body_step(VkCommandBuffer head, VkCommandBuffer tail, bool with_maxima);
  static constexpr std::uint32_t kBodyStepQueries = 9;
  void submit_and_wait(VkCommandBuffer cb);
  void read_results(int substeps);
  // Substep counts up to this many get per-pass timestamps (the query pool is sized once).
  static constexpr std::uint32_t kMaxTimedSubsteps = 256;
  bool timed(int substeps) const {
    return queries_ != VK_NULL_HANDLE && static_cast<std::uint32_t>(substeps) <= kMaxTimedSubsteps;
  }

  SimulationModel m_;
  std::unique_ptr<Context> context_;
  std::unique_ptr<ComputeProgram> program_;
  std::vector<DeviceState> devices_;

  std::uint32_t fluid_count_ = 0, solid_count_ = 0, cell_count_ = 0, scan_blocks_ = 0, max_groups_ = 0;
  std::uint32_t body_particle_count_ = 0, body_start_base_ = 0, body_chunk_count_ = 0;
  std::vector<std::vector<VirtualCoupling*>> couplings_of_body_;
  VkCommandBuffer body_head_ = VK_NULL_HANDLE, body_tail_ = VK_NULL_HANDLE, body_tail_maxima_ = VK_NULL_HANDLE;
  VkQueryPool body_queries_ = VK_NULL_HANDLE;
  struct Buffers;
  std::unique_ptr<Buffers> b_;
  VkQueryPool queries_ = VK_NULL_HANDLE;
  std::uint32_t queries_per_step_ = 0, query_capacity_ = 0;
  VkFence fence_ = VK_NULL_HANDLE;
  // (substep count, dfsph: the recorded iterations of the divergence, density and viscosity
  // solves) -> command buffer
  using RecordingKey = std::array<int, 4>;
  RecordingKey recording_key(int substeps) const;
  std::map<RecordingKey, VkCommandBuffer> recorded_;
  std::map<VkCommandBuffer, RecordedWork> work_of_;  // what each recorded command buffer holds
  // The commands recorded by `record` into their command buffer `cb`.
  void note_recorded(VkCommandBuffer cb, const std::function<void()>& record);
  StepWork work_;

  // The static solids the fluid's passes read: all of them (wcsph), or those beside the walls'
  // volume map (dfsph).
  const SortedSolids& fluid_statics() const { return dfsph_ ? fluid_statics_ : m_.static_solids; }
  SortedSolids fluid_statics_;
  bool dfsph_ = false;     // the model's method is the incompressible solver
  bool viscous_ = false;   // dfsph: some viscosity acts (the viscosity solve is recorded)
  float velocity_kept_ = 1;  // dfsph: 1, or the settling's share of the velocity kept per step
  SolverIterations iterations_;
  IterationBudget divergence_budget_{0}, density_budget_{0}, viscosity_budget_{0};
  float max_speed2_ = 0, max_accel2_ = 0;
  double time_s_ = 0;
  std::uint64_t steps_ = 0, clamped_ = 0;
  PassTimes pass_times_;
};

}  // namespace hapfluid::sim::vulkan
