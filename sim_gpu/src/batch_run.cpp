#include "hapfluid/sim/batch_run.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <stdexcept>

#include "hapfluid/config/log.hpp"
#include "hapfluid/config/scene.hpp"
#include "hapfluid/sim/solver.hpp"
#include "hapfluid/sim/thread_pool.hpp"
#include "hapfluid/sim/outputs.hpp"
#include "hapfluid/sim/run_stats.hpp"

namespace hapfluid::sim {
namespace {

std::string stats_json(const Solver& solver, const BatchOptions& o, const BatchResult& r, double dt_min, double dt_max,
                       const std::string& error, const ExtraStats& extra) {
  StatsJson j =
      batch_stats({&solver.model(), &o, &r, dt_min, dt_max, solver.clamped_particle_count(), error}, solver.backend());
  j["solver"] = solver.method();
  j["threads"] = solver.threads();
  add_solver_work(j, solver);
  if (extra) extra(solver, j);
  return config::json_text(j);
}

}  // namespace

BatchResult run_batch(const BatchOptions& options, std::ostream& progress) {
  BatchOptions o = options;
  if (o.backend == "auto") {
    log::notice("--backend auto: no GPU backend in this build, using the cpu backend");
    o.backend = "cpu";
  }
  if (o.backend != "cpu")
    throw std::runtime_error("--backend " + o.backend + ": this build has the cpu backend only (use cpu or auto)");
  if (o.threads < 1 || o.threads > kMaxWorkerThreads)
    throw std::runtime_error("--threads " + std::to_string(o.threads) + ": must be 1.." + std::to_string(kMaxWorkerThreads));
  return run_batch_with(o, progress, [&](SimulationModel model) { return make_cpu_solver(std::move(model), o.threads); });
}

BatchResult run_batch_with(const BatchOptions& o, std::ostream& progress, const SolverFactory& make_solver,
                           const ExtraStats& extra) {
  const config::Scene scene = config::load_scene(o.scene);
  const double duration = o.duration_s > 0 ? o.duration_s : scene.duration_s;
  // The scene loads and builds (and the backend starts) before the output folder is touched: a
  // bad scene leaves a previous run there as it was. From here on, nothing of the previous run
  // may remain to pass for this run's outputs.
  std::unique_ptr<Solver> solver_ptr = make_solver(build_model(scene));
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
      const int substeps =
          m.couplings.empty() ? solver.advance(t1 - t0) : solver.advance(t1 - t0, set_devices);
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
        std::snprintf(line, sizeof line, "t = %.3f / %.3f s, %llu steps, %.1f steps/s, real-time factor %.3f",
                      t1, duration, static_cast<unsigned long long>(r.steps), r.steps / std::max(wall, 1e-9),
                      t1 / std::max(wall, 1e-9));
        // A terminal gets one line redrawn in place; a log, a line every tenth of the run.
        if (o.progress_line)
          progress << "\r" << line << (k + 1 < frames ? "" : "\n") << std::flush;
        else
          log::info("%s", line);
      }
    }
    bodies_csv.finish();
    couplings_csv.finish();
  } catch (const std::exception& e) {
    error = e.what();
  }
  r.wall_time_s = elapsed();
  if (!error.empty()) {
    write_text_atomically(o.out / "stats.json", stats_json(solver, o, r, dt_min, dt_max, error, extra));
    throw std::runtime_error(error);
  }
  write_text_atomically(o.out / "stats.json", stats_json(solver, o, r, dt_min, dt_max, "", extra));
  return r;
}

}  // namespace hapfluid::sim
