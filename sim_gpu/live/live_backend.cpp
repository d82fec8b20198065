#include "live_backend.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>

#include "hapfluid/config/log.hpp"
#ifdef HAPFLUID_WITH_VULKAN
#include "hapfluid/sim_vulkan/vulkan_solver.hpp"
#endif

namespace hapfluid::sim {
namespace {

#ifdef HAPFLUID_WITH_VULKAN
std::unique_ptr<LiveSolver> make_vulkan(const SimulationModel& model, const LiveBackendOptions& o) {
  vulkan::VulkanSolverOptions options;
  options.context.device = vulkan::parse_device_preference(o.vulkan_device);
  // No per-pass timestamps in live runs: their read-back would be one more wait per step.
  options.timestamps = false;
  return std::make_unique<vulkan::VulkanSolver>(model, options);
}
#endif

std::string fixed(double v, int digits) {
  char text[32];
  std::snprintf(text, sizeof text, "%.*f", digits, v);
  return text;
}

std::string probe_words(const BackendProbe& p) {
  return fixed(p.steps_per_s(), 0) + " steps/s, real-time factor " + fixed(p.real_time_factor(), 2);
}

}  // namespace

BackendProbe probe_backend(LiveSolver& solver, double simulated_s, double wall_s) {
  using clock = std::chrono::steady_clock;
  for (int i = 0; i < 3; ++i) solver.step(solver.stable_time_step());  // warm-up, not timed
  BackendProbe p;
  p.ran = true;
  const double t0 = solver.time_s();
  const std::uint64_t n0 = solver.steps();
  const auto start = clock::now();
  double wall = 0;
  while (solver.time_s() - t0 < simulated_s && wall < wall_s) {
    solver.step(solver.stable_time_step());
    wall = std::chrono::duration<double>(clock::now() - start).count();
  }
  p.steps = solver.steps() - n0;
  p.simulated_s = solver.time_s() - t0;
  p.wall_s = wall;
  return p;
}

std::unique_ptr<LiveSolver> make_live_solver(const SimulationModel& model, const std::string& backend,
                                             const LiveBackendOptions& options) {
  if (backend == "cpu") return make_cpu_solver(model, options.threads);
#ifdef HAPFLUID_WITH_VULKAN
  if (backend == "vulkan") return make_vulkan(model, options);
#endif
  throw BackendUnavailable("backend '" + backend + "': expected cpu" +
#ifdef HAPFLUID_WITH_VULKAN
                           " or vulkan"
#else
                           " (built without the Vulkan backend)"
#endif
  );
}

LiveBackend choose_live_backend(const config::Scene& scene, const LiveBackendOptions& o) {
  if (o.backend != "cpu" && o.backend != "vulkan" && o.backend != "auto")
    throw BackendUnavailable("--backend " + o.backend + ": expected cpu, vulkan or auto");
  const SimulationModel model = build_model(scene);
  LiveBackend r;
  r.requested = o.backend;
  auto make_cpu = [&] { return make_cpu_solver(model, o.threads); };
  if (o.backend == "cpu") {
    r.solver = make_cpu();
    r.reason = "--backend cpu";
    return r;
  }
#ifndef HAPFLUID_WITH_VULKAN
  if (o.backend == "vulkan")
    throw BackendUnavailable("--backend vulkan: this haptic-sim was built without the Vulkan backend (sim_gpu/vulkan)");
  log::Line(log::Level::notice) << "notice: --backend auto: built without the Vulkan backend; running on the cpu backend";
  r.solver = make_cpu();
  r.reason = "auto: built without the Vulkan backend";
  return r;
#else
  if (o.backend == "vulkan") {
    try {
      r.solver = make_vulkan(model, o);
    } catch (const vulkan::VulkanError& e) {
      throw BackendUnavailable(std::string("--backend vulkan: ") + e.what() + " (or run with --backend cpu or auto)");
    } catch (const std::invalid_argument& e) {
      throw BackendUnavailable(std::string("--vk-device: ") + e.what());
    }
    r.reason = "--backend vulkan";
    return r;
  }

  // auto: the rule in live_backend.hpp.
  if (model.params.solver == config::PressureSolver::dfsph && model.body_particles.size() > 0) {
    const std::string why = "the Vulkan backend runs fluid.solver = \"dfsph\" without dynamic bodies so far, this scene "
                            "has " + std::to_string(model.body_particles.size()) + " dynamic body particles";
    log::Line(log::Level::notice) << "notice: --backend auto: " << why << "; running on the cpu backend";
    r.solver = make_cpu();
    r.reason = "auto: " + why;
    return r;
  }
  std::unique_ptr<LiveSolver> probe;
  try {
    probe = make_vulkan(model, o);
  } catch (const std::invalid_argument& e) {
    throw BackendUnavailable(std::string("--vk-device: ") + e.what());
  } catch (const std::exception& e) {  // no loader, no ICD, no device, or a scene beyond its limits
    log::Line(log::Level::notice) << "notice: --backend auto: no usable Vulkan device (" << e.what()
                                  << "); running on the cpu backend";
    r.solver = make_cpu();
    r.reason = std::string("auto: no usable Vulkan device: ") + e.what();
    return r;
  }
  const std::string vulkan_name = probe->device().name;
  try {
    r.vulkan_probe = probe_backend(*probe, o.probe_simulated_s, o.probe_wall_s);
  } catch (const std::exception& e) {  // e.g. a lost device: as unusable as a missing one
    log::Line(log::Level::notice) << "notice: --backend auto: Vulkan on " << vulkan_name << " failed its probe (" << e.what()
                                  << "); running on the cpu backend";
    r.solver = make_cpu();
    r.reason = "auto: Vulkan on " + vulkan_name + " failed its probe: " + e.what();
    return r;
  }
  probe.reset();
  log::Line(log::Level::info) << "--backend auto: probe on Vulkan (" << vulkan_name << "): " << probe_words(r.vulkan_probe)
                              << " on this scene";
  if (r.vulkan_probe.real_time_factor() >= o.vulkan_min_real_time_factor) {
    r.solver = make_vulkan(model, o);
    r.reason = "auto: Vulkan keeps up (probe real-time factor " + fixed(r.vulkan_probe.real_time_factor(), 2) + " >= " +
               fixed(o.vulkan_min_real_time_factor, 2) + ")";
    return r;
  }
  {
    std::unique_ptr<LiveSolver> cpu_probe = make_cpu_solver(model, o.threads);
    r.cpu_probe = probe_backend(*cpu_probe, o.probe_simulated_s, o.probe_wall_s);
  }
  const bool cpu_faster = r.cpu_probe.real_time_factor() > r.vulkan_probe.real_time_factor();
  const std::string both = "Vulkan on " + vulkan_name + ": " + probe_words(r.vulkan_probe) + "; cpu backend (" +
                           std::to_string(o.threads) + (o.threads == 1 ? " thread): " : " threads): ") + probe_words(r.cpu_probe);
  log::Line(log::Level::notice) << "NOTICE: --backend auto: Vulkan (" << vulkan_name << ") cannot keep up with the wall clock on this "
                                << "scene (probe real-time factor " << fixed(r.vulkan_probe.real_time_factor(), 2) << " < "
                                << fixed(o.vulkan_min_real_time_factor, 2) << "); " << both << " => running on the "
                                << (cpu_faster ? "cpu backend" : "Vulkan backend (the cpu backend is no faster)")
                                << " (--backend vulkan|cpu forces one)";
  r.solver = cpu_faster ? std::unique_ptr<LiveSolver>(make_cpu()) : make_vulkan(model, o);
  r.reason = "auto: Vulkan on " + vulkan_name + " cannot keep up (probe real-time factor " +
             fixed(r.vulkan_probe.real_time_factor(), 2) + " < " + fixed(o.vulkan_min_real_time_factor, 2) + ", cpu " +
             fixed(r.cpu_probe.real_time_factor(), 2) + "): the " + (cpu_faster ? "cpu" : "Vulkan") + " backend is faster";
  return r;
#endif
}

}  // namespace hapfluid::sim
