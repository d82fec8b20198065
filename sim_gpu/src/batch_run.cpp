#include "hapfluid/sim/batch_run.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <sstream>
#include <stdexcept>

#include "hapfluid/config/build_id.hpp"
#include "hapfluid/config/scene.hpp"
#include "hapfluid/sim/solver.hpp"
#include "hapfluid/sim/thread_pool.hpp"
#include "hapfluid/sim/outputs.hpp"

namespace hapfluid::sim {
namespace {

std::string num(double v) { return csv_number(v); }

std::string stats_json(const Solver& solver, const BatchOptions& o, const BatchResult& r, double dt_min, double dt_max,
                       bool complete, const std::string& error) {
  const SimulationModel& m = solver.model();
  const std::size_t fluid = m.fluid.size(), walls = m.wall_particle_count, statics = m.static_body_particle_count,
                    bodies = m.body_particles.size();
  const std::size_t total = fluid + walls + statics + bodies;
  const double steps = static_cast<double>(r.steps);
  const double wall = r.wall_time_s > 0 ? r.wall_time_s : 1e-12;
  const PhaseTimes t = solver.phase_times();
  const SolverIterations it = solver.iterations();
  auto per_step_ms = [&](double s) { return num(steps > 0 ? 1000.0 * s / steps : 0.0); };
  std::ostringstream j;
  j << "{\n  \"complete\": " << (complete ? "true" : "false") << ",\n";
  if (!complete) j << "  \"error\": \"" << json_escape(error) << "\",\n";
  j << "  \"build_id\": \"" << json_escape(config::build_id()) << "\",\n"
    << "  \"scene\": \"" << json_escape(o.scene.string()) << "\",\n"
    << "  \"backend\": \"" << o.backend << "\",\n"
    << "  \"solver\": \"" << solver.method() << "\",\n"
    << "  \"threads\": " << solver.threads() << ",\n"
    << "  \"particles\": {\"fluid\": " << fluid << ", \"boundary\": " << walls << ", \"static_body\": " << statics
    << ", \"body\": " << bodies << ", \"total\": " << total << "},\n"
    << "  \"steps\": " << r.steps << ",\n"
    << "  \"dt_s\": {\"min\": " << num(dt_min) << ", \"max\": " << num(dt_max)
    << ", \"mean\": " << num(steps > 0 ? r.simulated_time_s / steps : 0) << "},\n"
    << "  \"simulated_time_s\": " << num(r.simulated_time_s) << ",\n"
    << "  \"wall_time_s\": " << num(r.wall_time_s) << ",\n"
    << "  \"steps_per_s\": " << num(steps / wall) << ",\n"
    // Particles that are computed each step: fluid and dynamic body particles.
    << "  \"particle_steps_per_s\": " << num(steps * static_cast<double>(fluid + bodies) / wall) << ",\n"
    << "  \"real_time_factor\": " << num(r.simulated_time_s / wall) << ",\n"
    << "  \"frames_exported\": " << r.frames_exported << ",\n"
    << "  \"clamped_particle_events\": " << solver.clamped_particle_count() << ",\n"
    << "  \"solver_iterations\": {\"density_per_step\": " << num(steps > 0 ? it.density_iterations / steps : 0)
    << ", \"divergence_per_step\": " << num(steps > 0 ? it.divergence_iterations / steps : 0)
    << ", \"viscosity_per_step\": " << num(steps > 0 ? it.viscosity_iterations / steps : 0)
    << ", \"unconverged_solves\": " << it.unconverged_solves
    << ", \"max_mean_density_error\": " << num(it.max_density_error) << "},\n"
    << "  \"phase_ms_per_step\": {\"neighbour_search\": " << per_step_ms(t.neighbour_search_s)
    << ", \"density\": " << per_step_ms(t.density_s) << ", \"forces\": " << per_step_ms(t.forces_s)
    << ", \"pressure_solve\": " << per_step_ms(t.pressure_s)
    << ", \"bodies\": " << per_step_ms(t.bodies_s) << ", \"integration\": " << per_step_ms(t.integration_s) << "}\n}\n";
  return j.str();
}


}  // namespace

BatchResult run_batch(const BatchOptions& options, std::ostream& progress) {
  BatchOptions o = options;
  if (o.backend == "auto") {
    progress << "haptic-sim: --backend auto: no GPU backend in this build, using the cpu backend\n";
    o.backend = "cpu";
  }
  if (o.backend != "cpu")
    throw std::runtime_error("--backend " + o.backend + ": this build has the cpu backend only (use cpu or auto)");
  if (o.threads < 1 || o.threads > kMaxWorkerThreads)
    throw std::runtime_error("--threads " + std::to_string(o.threads) + ": must be 1.." + std::to_string(kMaxWorkerThreads));
  const config::Scene scene = config::load_scene(o.scene);
  const double duration = o.duration_s > 0 ? o.duration_s : scene.duration_s;
  // The scene loads and builds before the output folder is touched: a bad scene leaves a
  // previous run there as it was. From here on, nothing of the previous run may remain to pass
  // for this run's outputs.
  std::unique_ptr<Solver> solver_ptr = make_cpu_solver(build_model(scene), o.threads);
  Solver& solver = *solver_ptr;
  const SimulationModel& m = solver.model();
  std::filesystem::create_directories(o.out / "particles");
  remove_previous_outputs(o.out);
  VtkFrameSeries vtk_frames(o.out / "particles", o.export_every_s);
  CsvFile bodies_csv(o.out / "bodies.csv", kBodiesCsvHeader);
  CsvFile couplings_csv(o.out / "couplings.csv", kCouplingsCsvHeader);

  BatchResult r;
  double dt_min = 1e300, dt_max = 0;
  const double frame = 1.0 / m.params.frame_rate_hz;
  const int frames = std::max(1, static_cast<int>(std::ceil(duration / frame - 1e-9)));
  const auto start = std::chrono::steady_clock::now();
  auto elapsed = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(); };
  auto set_devices = [&](double t) {
    for (std::size_t d = 0; d < m.devices.size(); ++d)
      solver.set_device_state(d, device_state_from(config::evaluate_motion(m.devices[d].motion, t)));
  };
  auto record = [&](double t) {
    for (const RigidBody& b : m.bodies) bodies_csv.row(body_row(b, t));
    for (const VirtualCoupling& c : m.couplings) couplings_csv.row(coupling_row(m, c, t));
  };
  auto export_frame = [&](double t) {
    if (!vtk_frames.due(t)) return;
    vtk_frames.write(m, t);
    r.frames_exported = vtk_frames.written();
  };

  std::string error;
  try {
    set_devices(0);
    export_frame(0);
    for (int k = 0; k < frames; ++k) {
      const double t0 = k * frame, t1 = std::min(duration, (k + 1) * frame);
      const int substeps = solver.advance(t1 - t0, set_devices);
      const double dt = (t1 - t0) / substeps;
      dt_min = std::min(dt_min, dt), dt_max = std::max(dt_max, dt);
      solver.sync_and_check_finite();
      r.steps = solver.steps();
      r.simulated_time_s = t1;
      record(t1);
      export_frame(t1);
      const double wall = elapsed();
      if (o.progress_line || k + 1 == frames || (k + 1) % std::max(1, frames / 10) == 0) {
        char line[160];
        std::snprintf(line, sizeof line, "haptic-sim: t = %.3f / %.3f s, %llu steps, %.1f steps/s, real-time factor %.3f",
                      t1, duration, static_cast<unsigned long long>(r.steps), r.steps / std::max(wall, 1e-9),
                      t1 / std::max(wall, 1e-9));
        progress << (o.progress_line ? "\r" : "") << line << (o.progress_line && k + 1 < frames ? "" : "\n") << std::flush;
      }
    }
    bodies_csv.finish();
    couplings_csv.finish();
  } catch (const std::exception& e) {
    error = e.what();
  }
  r.wall_time_s = elapsed();
  if (!error.empty()) {
    write_text_atomically(o.out / "stats.json", stats_json(solver, o, r, dt_min, dt_max, false, error));
    throw std::runtime_error(error);
  }
  write_text_atomically(o.out / "stats.json", stats_json(solver, o, r, dt_min, dt_max, true, ""));
  return r;
}

}  // namespace hapfluid::sim
