#include <chrono>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "hapfluid/config/log.hpp"
#include "hapfluid/config/scene.hpp"
#include "hapfluid/sim/outputs.hpp"
#include "hapfluid/sim/run_stats.hpp"
#include "hapfluid/sim_vulkan/backend.hpp"
#include "hapfluid/sim_vulkan/vulkan_solver.hpp"

namespace hapfluid::sim::vulkan {
namespace {

// stats.json of the cpu backend's batch run (the shared keys), plus the device, the GPU's
// per-pass split and the validation counts.
std::string stats_json(const VulkanSolver& solver, const BatchOptions& o, const BatchResult& r, double dt_min,
                       double dt_max, const std::string& error) {
  const PhaseTimes t = solver.phase_times();
  const PassTimes& g = solver.pass_times();
  const double steps = static_cast<double>(r.steps), timed = static_cast<double>(g.steps);
  const ValidationCounts counts = solver.context().validation_counts();
  StatsJson j = batch_stats({&solver.model(), &o, &r, dt_min, dt_max, t, solver.clamped_particle_count(), error}, "vulkan");
  j["device"] = {{"name", solver.device().name}, {"type", solver.device().type}, {"driver", solver.device().driver}};
  j["phase_ms_per_step"] = {{"neighbour_search", per_step_ms(t.neighbour_search_s, steps)},
                            {"density", per_step_ms(t.density_s, steps)},
                            {"forces", per_step_ms(t.forces_s, steps)},
                            {"bodies", per_step_ms(t.bodies_s, steps)},
                            {"integration", per_step_ms(t.integration_s, steps)}};
  j["gpu_pass_ms_per_step"] = {{"timed_steps", g.steps},
                               {"sort", per_step_ms(g.sort_s, timed)},
                               {"density", per_step_ms(g.density_s, timed)},
                               {"forces", per_step_ms(g.forces_s, timed)},
                               {"bodies", per_step_ms(g.bodies_s, timed)},
                               {"integration", per_step_ms(g.integration_s, timed)},
                               {"reductions", per_step_ms(g.reductions_s, timed)}};
  j["vulkan_validation"] = {{"enabled", solver.context().validation_enabled()},
                            {"warnings", counts.warnings},
                            {"errors", counts.errors}};
  return config::json_text(j);
}

}  // namespace

BatchResult run_batch_vulkan(const BatchOptions& o, const VulkanRunOptions& vulkan, std::ostream& progress) {
  const config::Scene scene = config::load_scene(o.scene);
  const double duration = o.duration_s > 0 ? o.duration_s : scene.duration_s;
  VulkanSolverOptions solver_options;
  solver_options.context.validation = vulkan.validation;
  solver_options.context.device = vulkan.device;
  // The device is chosen (or found missing) before any output is touched.
  VulkanSolver solver(build_model(scene), solver_options);
  const SimulationModel& m = solver.model();
  log::Line(log::Level::info) << "Vulkan device: " << solver.device().name << " (" << solver.device().type << ", "
                              << solver.device().driver << ")";

  std::filesystem::create_directories(o.out / "particles");
  remove_previous_outputs(o.out);  // only now: a scene or device that fails leaves a previous run as it was
  VtkFrameSeries vtk_frames(o.out / "particles", o.export_every_s);
  CsvFile bodies_csv(o.out / "bodies.csv", kBodiesCsvHeader);
  CsvFile couplings_csv(o.out / "couplings.csv", kCouplingsCsvHeader);

  BatchResult r;
  double dt_min = 1e300, dt_max = 0;
  const double frame = 1.0 / m.params.frame_rate_hz;
  const int frames = std::max(1, static_cast<int>(std::ceil(duration / frame - 1e-9)));
  const bool per_substep_devices = !m.couplings.empty();
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
    solver.sync_particles();  // particle arrays come back only for a frame
    vtk_frames.write(m, t);
    r.frames_exported = vtk_frames.written();
  };

  std::string error;
  try {
    set_devices(0);
    export_frame(0);
    for (int k = 0; k < frames; ++k) {
      const double t0 = k * frame, t1 = std::min(duration, (k + 1) * frame);
      const double dt_limit = solver.stable_time_step();
      const int substeps = std::max(1, static_cast<int>(std::ceil((t1 - t0) / dt_limit - 1e-9)));
      const double dt = (t1 - t0) / substeps;
      dt_min = std::min(dt_min, dt), dt_max = std::max(dt_max, dt);
      if (per_substep_devices) {
        for (int s = 0; s < substeps; ++s) {
          set_devices(t0 + s * dt);
          solver.step(dt);
        }
      } else {
        solver.step_many(dt, substeps);  // one submission for the frame
      }
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
    solver.check_finite();
    bodies_csv.finish();
    couplings_csv.finish();
  } catch (const std::exception& e) {
    error = e.what();
  }
  r.wall_time_s = elapsed();
  if (!error.empty()) {
    write_text_atomically(o.out / "stats.json", stats_json(solver, o, r, dt_min, dt_max, error));
    throw std::runtime_error(error);
  }
  write_text_atomically(o.out / "stats.json", stats_json(solver, o, r, dt_min, dt_max, ""));
  return r;
}

BatchResult run_batch_on_backend(const BatchOptions& options, const VulkanRunOptions& vulkan, std::ostream& progress) {
  if (options.backend == "cpu") return run_batch(options, progress);
  if (options.backend == "vulkan") return run_batch_vulkan(options, vulkan, progress);
  if (options.backend == "auto") {
    try {
      return run_batch_vulkan(options, vulkan, progress);
    } catch (const VulkanUnavailable& e) {
      log::notice("notice: %s", e.what());
      log::notice("notice: --backend auto: running on the cpu backend instead");
      BatchOptions cpu = options;
      cpu.backend = "cpu";
      return run_batch(cpu, progress);
    }
  }
  throw std::runtime_error("--backend " + options.backend + ": expected cpu, vulkan or auto");
}

}  // namespace hapfluid::sim::vulkan
