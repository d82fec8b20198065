// stats.json of a batch run: the keys every backend writes (which build, scene, particles, steps
// and their sizes, speed, frames, wall clamps, phase times), as JSON that each backend extends
// with its own (the CPU solver's iterations, the GPU's device and pass times).
#pragma once

#include <cstdint>
#include <string>

#include "hapfluid/config/json_output.hpp"
#include "hapfluid/sim/batch_run.hpp"
#include "hapfluid/sim/model.hpp"
#include "hapfluid/sim/solver.hpp"

namespace hapfluid::sim {

// Keys in the order written (a person reads the file); config::json_text makes the text.
using StatsJson = config::Json;

struct RunRecord {
  const SimulationModel* model = nullptr;
  const BatchOptions* options = nullptr;
  const BatchResult* result = nullptr;
  double dt_min_s = 0, dt_max_s = 0;
  std::uint64_t clamped_particle_events = 0;
  std::string error;  // empty: the run completed
};

// {"complete", ["error"], "build_id", "scene", "backend", "particles", "steps", "dt_s",
//  "simulated_time_s", "wall_time_s", "steps_per_s", "particle_steps_per_s", "real_time_factor",
//  "frames_exported", "clamped_particle_events"}; the solver's own work is added by
// add_solver_work.
StatsJson batch_stats(const RunRecord& run, const std::string& backend);

// Adds what the solver's steps did, batch or live: "solver_iterations" (per step, and the
// solves that did not converge) and "phase_ms_per_step" (the backend's own phase timers).
void add_solver_work(StatsJson& j, const Solver& solver);

// Milliseconds per step of a phase's total seconds over `steps` (0 before the first step).
double per_step_ms(double total_s, double steps);

}  // namespace hapfluid::sim
