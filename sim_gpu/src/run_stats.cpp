#include "hapfluid/sim/run_stats.hpp"

#include "hapfluid/config/build_id.hpp"

namespace hapfluid::sim {

double per_step_ms(double total_s, double steps) { return steps > 0 ? 1000.0 * total_s / steps : 0.0; }

StatsJson batch_stats(const RunRecord& run, const std::string& backend) {
  const SimulationModel& m = *run.model;
  const BatchResult& r = *run.result;
  const std::size_t fluid = m.fluid.size(), walls = m.wall_particle_count, statics = m.static_body_particle_count,
                    bodies = m.body_particles.size();
  const double steps = static_cast<double>(r.steps);
  const double wall = r.wall_time_s > 0 ? r.wall_time_s : 1e-12;
  StatsJson j;
  j["complete"] = run.error.empty();
  if (!run.error.empty()) j["error"] = run.error;
  j["build_id"] = config::build_id();
  j["scene"] = run.options->scene.string();
  j["backend"] = backend;
  j["particles"] = {{"fluid", fluid}, {"boundary", walls}, {"static_body", statics}, {"body", bodies},
                    {"total", fluid + walls + statics + bodies}};
  j["fluid_mass_kg"] = static_cast<double>(fluid) * m.params.fluid_particle_mass_kg;
  j["steps"] = r.steps;
  j["dt_s"] = {{"min", r.steps > 0 ? run.dt_min_s : 0.0}, {"max", run.dt_max_s},
               {"mean", steps > 0 ? r.simulated_time_s / steps : 0.0}};
  j["simulated_time_s"] = r.simulated_time_s;
  j["wall_time_s"] = r.wall_time_s;
  j["steps_per_s"] = steps / wall;
  // Particles that are computed each step: fluid and dynamic body particles.
  j["particle_steps_per_s"] = steps * static_cast<double>(fluid + bodies) / wall;
  j["real_time_factor"] = r.simulated_time_s / wall;
  j["frames_exported"] = r.frames_exported;
  j["clamped_particle_events"] = run.clamped_particle_events;
  return j;
}

void add_solver_work(StatsJson& j, const Solver& solver) {
  const PhaseTimes t = solver.phase_times();
  const SolverIterations it = solver.iterations();
  const double steps = static_cast<double>(solver.steps());
  auto per_step = [&](double n) { return steps > 0 ? n / steps : 0.0; };
  j["solver_iterations"] = {{"density_per_step", per_step(static_cast<double>(it.density_iterations))},
                            {"divergence_per_step", per_step(static_cast<double>(it.divergence_iterations))},
                            {"viscosity_per_step", per_step(static_cast<double>(it.viscosity_iterations))},
                            {"explicit_viscosity_steps", it.explicit_viscosity_steps},
                            {"unconverged_solves", it.unconverged_solves},
                            {"budget_overruns", it.budget_overruns},
                            {"max_mean_density_error", it.max_density_error}};
  j["phase_ms_per_step"] = {{"neighbour_search", per_step_ms(t.neighbour_search_s, steps)},
                            {"density", per_step_ms(t.density_s, steps)},
                            {"forces", per_step_ms(t.forces_s, steps)},
                            {"pressure_solve", per_step_ms(t.pressure_s, steps)},
                            {"bodies", per_step_ms(t.bodies_s, steps)},
                            {"integration", per_step_ms(t.integration_s, steps)}};
}

}  // namespace hapfluid::sim
