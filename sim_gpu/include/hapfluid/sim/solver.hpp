// The one stepping interface of every SPH backend and method (CPU WCSPH, CPU DFSPH, Vulkan):
// batch runs, the live sim, benchmarks and tests drive a Solver and never ask which it is.
//
// The stepping API does no I/O: callers set device states, step, and read bodies, couplings and
// particles (batch export, shared-memory publishing in the live sim).
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "hapfluid/sim/coupling.hpp"
#include "hapfluid/sim/model.hpp"

namespace hapfluid::sim {

// Wall-clock seconds spent in each phase, summed over all steps.
struct PhaseTimes {
  double neighbour_search_s = 0;  // sorting by cell (and, dfsph, building the neighbour lists)
  // Density: eq. 2 and eq. 7 (wcsph, including the distance checks that build the neighbour
  // lists), or density and DFSPH factor (dfsph); contact pressure of bodies.
  double density_s = 0;
  double forces_s = 0;            // non-pressure forces (and, wcsph, pressure): eqs. 5, 6, 9
  double pressure_s = 0;          // dfsph: divergence-free and constant-density solves
  double bodies_s = 0;            // eqs. 10-14, couplings (Algorithm 2)
  double integration_s = 0;       // fluid positions
};

// What an incompressible solve did, summed over all steps (zero for wcsph).
struct SolverIterations {
  std::uint64_t density_iterations = 0;
  std::uint64_t divergence_iterations = 0;
  std::uint64_t viscosity_iterations = 0;  // conjugate-gradient iterations of the implicit viscosity
  std::uint64_t explicit_viscosity_steps = 0;  // steps whose viscosity was one explicit step (as exact)
  std::uint64_t unconverged_solves = 0;   // solves that stopped at max_solver_iterations
  // Vulkan: of those, solves that stopped at the iterations recorded for them, below
  // max_solver_iterations (iteration_budget.hpp)
  std::uint64_t budget_overruns = 0;
  double last_density_error = 0;          // mean (rho* - rho0) / rho0 of the last constant-density solve
  double max_density_error = 0;           // largest such mean over the run
};

struct ComputeDevice {
  std::string name;    // "llvmpipe (LLVM 15.0.6, 256 bits)", "2 CPU threads"
  std::string type;    // "CPU", "discrete GPU", ... ; "host" for the cpu backend
  std::string driver;  // "llvmpipe Mesa 22.3.6 (LLVM 15.0.6)"; empty for the cpu backend
};

// The device of a CPU backend: its worker threads.
inline ComputeDevice cpu_threads_device(int threads) {
  return {std::to_string(threads) + (threads == 1 ? " CPU thread" : " CPU threads"), "host", ""};
}

class Solver {
 public:
  virtual ~Solver() = default;

  // Bodies and couplings are current after every step; fluid particles after sync().
  virtual const SimulationModel& model() const = 0;
  const SimulationParams& params() const { return model().params; }
  virtual double time_s() const = 0;
  virtual std::uint64_t steps() const = 0;

  // Device poses for the couplings, set before each step (scripted motion or live devices).
  virtual void set_device_state(std::size_t device, const DeviceState& state) = 0;
  // Largest stable step for the current state (the method's CFL bound, the viscous, force and
  // contact limits, the scene's max_dt_s; or the scene's fixed dt_s).
  virtual double stable_time_step() const = 0;
  virtual void step(double dt) = 0;
  // Advances by `duration_s` in equal substeps no longer than stable_time_step(); returns the
  // number of substeps. before_substep(t), when given, runs before each substep with the
  // substep's start time (the caller sets device states there); otherwise they are held. A
  // backend may run the substeps of a frame without returning to the host in between.
  virtual int advance(double duration_s, const std::function<void(double)>& before_substep = {});

  // Brings the fluid particles of model() up to date (a read-back on Vulkan) and throws
  // std::runtime_error naming the first non-finite particle or body (check_finite_state).
  virtual void sync_and_check_finite() = 0;

  // Fluid particles the last-resort clamp had to put back at the domain box, summed over all
  // steps: a fault (the walls alone must hold the fluid), counted and reported.
  virtual std::uint64_t clamped_particle_count() const = 0;
  virtual PhaseTimes phase_times() const = 0;
  virtual SolverIterations iterations() const { return {}; }

  virtual const char* backend() const = 0;  // "cpu" or "vulkan"
  const char* method() const { return config::to_string(params().solver); }  // "dfsph" or "wcsph"
  virtual ComputeDevice device() const = 0;
  virtual int threads() const = 0;  // CPU worker threads (0 on Vulkan: the driver's own)
  // How many of the worker threads the next steps use, 1..threads(); the same results for any
  // count (thread_pool.hpp). No effect on Vulkan.
  virtual void set_active_threads(int) {}
  virtual int active_threads() const { return threads(); }
};

// The CPU solver of the model's method (params.solver).
std::unique_ptr<Solver> make_cpu_solver(SimulationModel model, int threads);

}  // namespace hapfluid::sim
