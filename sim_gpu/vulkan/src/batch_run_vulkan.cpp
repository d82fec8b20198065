#include <algorithm>
#include <memory>

#include "hapfluid/config/log.hpp"
#include "hapfluid/sim/run_stats.hpp"
#include "hapfluid/sim_vulkan/backend.hpp"
#include "hapfluid/sim_vulkan/vulkan_solver.hpp"

namespace hapfluid::sim::vulkan {
namespace {

// stats.json's Vulkan keys, after the shared ones: the device, the GPU's per-pass split and the
// validation counts.
void vulkan_stats(const VulkanSolver& solver, config::Json& j) {
  const PassTimes& g = solver.pass_times();
  const double timed = static_cast<double>(g.steps);
  const ValidationCounts counts = solver.context().validation_counts();
  j["device"] = {{"name", solver.device().name}, {"type", solver.device().type}, {"driver", solver.device().driver}};
  j["gpu_pass_ms_per_step"] = {{"timed_steps", g.steps},
                               {"sort", per_step_ms(g.sort_s, timed)},
                               {"density", per_step_ms(g.density_s, timed)},
                               {"forces", per_step_ms(g.forces_s, timed)},
                               {"pressure_solve", per_step_ms(g.pressure_s, timed)},
                               {"bodies", per_step_ms(g.bodies_s, timed)},
                               {"integration", per_step_ms(g.integration_s, timed)},
                               {"reductions", per_step_ms(g.reductions_s, timed)}};
  const StepWork& w = solver.work();
  const double steps = static_cast<double>(std::max<std::uint64_t>(solver.steps(), 1));
  j["gpu_work_per_step"] = {{"dispatches", w.dispatches / steps},
                            {"indirect_dispatches", w.indirect_dispatches / steps},
                            {"barriers", w.barriers / steps},
                            {"submissions", w.submissions / steps},
                            {"host_waits", w.host_waits / steps}};
  j["vulkan_validation"] = {{"enabled", solver.context().validation_enabled()},
                            {"warnings", counts.warnings},
                            {"errors", counts.errors}};
}

}  // namespace

BatchResult run_batch_vulkan(const BatchOptions& o, const VulkanRunOptions& vulkan, std::ostream& progress) {
  VulkanSolverOptions solver_options;
  solver_options.context.validation = vulkan.validation;
  solver_options.context.device = vulkan.device;
  auto make = [&](SimulationModel model) -> std::unique_ptr<Solver> {
    auto solver = std::make_unique<VulkanSolver>(std::move(model), solver_options);
    log::Line(log::Level::info) << "Vulkan device: " << solver->device().name << " (" << solver->device().type << ", "
                                << solver->device().driver << ")";
    return solver;
  };
  auto extra = [](const Solver& solver, config::Json& j) { vulkan_stats(dynamic_cast<const VulkanSolver&>(solver), j); };
  return run_batch_with(o, progress, make, extra);
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
