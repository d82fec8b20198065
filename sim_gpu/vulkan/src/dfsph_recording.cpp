// Recording of the incompressible solver's step (DfsphSolver::step, pass by pass). Every solve
// runs to its end inside the submission: each iteration's passes are recorded up to the
// iteration cap, and a one-workgroup check after each error pass sets the group count of the
// iterating passes that follow (indirect dispatches) to zero once the solve has converged. No
// host round trip per iteration; the iterations that were not needed cost an empty dispatch
// and a barrier each, so each solve records only its budget (iteration_budget.hpp).
#include <functional>

#include "hapfluid/sim_vulkan/vulkan_solver.hpp"
#include "recording.hpp"

namespace hapfluid::sim::vulkan {

void VulkanSolver::record_dfsph_initial(VkCommandBuffer cb) {
  // As DfsphSolver's constructor after settling: sort, density, and this order made persistent.
  const ComputeProgram& p = *program_;
  const std::uint32_t g = groups(fluid_count_, 64);
  record_sort(cb);
  p.dispatch(cb, Pass::dfsph_gather, g);
  program_->barrier(cb, Barrier::compute);
  p.dispatch(cb, Pass::dfsph_density, g);
  program_->barrier(cb, Barrier::compute);
  p.dispatch(cb, Pass::adopt_sorted, g);
  p.dispatch(cb, Pass::dfsph_adopt, g);
  program_->barrier(cb, Barrier::compute);
}

void VulkanSolver::record_pressure_solve(VkCommandBuffer cb, bool density, int budget) {
  const ComputeProgram& p = *program_;
  const std::uint32_t g = groups(fluid_count_, 64), mode = density ? 2 : 0, flag = density ? 1 : 0;
  const Buffer& args = dfsph_solve_buffer();
  p.dispatch(cb, Pass::dfsph_rate, g, {mode, 0, 0, 0});
  program_->barrier(cb, Barrier::compute_and_indirect);
  p.dispatch(cb, Pass::dfsph_apply, g);
  program_->barrier(cb, Barrier::compute);
  for (int it = 0; it < budget; ++it) {
    p.dispatch_indirect(cb, Pass::dfsph_rate, args, 0, {mode + 1, 0, 0, 0});
    program_->barrier(cb, Barrier::compute);
    p.dispatch(cb, Pass::dfsph_check, 1, {static_cast<std::uint32_t>(it), flag, 0, 0});
    program_->barrier(cb, Barrier::compute_and_indirect);
    p.dispatch_indirect(cb, Pass::dfsph_apply, args, 0);
    program_->barrier(cb, Barrier::compute);
  }
  p.dispatch(cb, Pass::dfsph_solve_end, g, {flag, static_cast<std::uint32_t>(budget), 0, 0});
  program_->barrier(cb, Barrier::compute);
}

void VulkanSolver::record_viscosity_solve(VkCommandBuffer cb, int budget) {
  const ComputeProgram& p = *program_;
  const std::uint32_t g = groups(fluid_count_, 64);
  const Buffer& args = dfsph_solve_buffer();
  p.dispatch(cb, Pass::dfsph_visc_rhs, g);
  program_->barrier(cb, Barrier::compute);
  p.dispatch(cb, Pass::dfsph_visc_check, 1);
  program_->barrier(cb, Barrier::compute_and_indirect);
  for (int it = 0; it < budget; ++it) {
    const std::uint32_t i = static_cast<std::uint32_t>(it);
    p.dispatch_indirect(cb, Pass::dfsph_cg_apply, args, 0);
    program_->barrier(cb, Barrier::compute);
    p.dispatch(cb, Pass::dfsph_cg_alpha, 1, {i, 0, 0, 0});
    program_->barrier(cb, Barrier::compute_and_indirect);
    p.dispatch_indirect(cb, Pass::dfsph_cg_update, args, 0);
    program_->barrier(cb, Barrier::compute);
    p.dispatch(cb, Pass::dfsph_cg_check, 1, {i, 0, 0, 0});
    program_->barrier(cb, Barrier::compute_and_indirect);
    p.dispatch_indirect(cb, Pass::dfsph_cg_direction, args, 0);
    program_->barrier(cb, Barrier::compute);
  }
  p.dispatch(cb, Pass::dfsph_visc_end, g, {static_cast<std::uint32_t>(budget), 0, 0, 0});
  program_->barrier(cb, Barrier::compute);
}

void VulkanSolver::record_dfsph_step(VkCommandBuffer cb, const std::function<void()>& stamp) {
  const ComputeProgram& p = *program_;
  const std::uint32_t g = groups(fluid_count_, 64);
  record_sort(cb);
  p.dispatch(cb, Pass::dfsph_gather, g);
  program_->barrier(cb, Barrier::compute);
  stamp();
  p.dispatch(cb, Pass::dfsph_density, g);
  program_->barrier(cb, Barrier::compute);
  stamp();
  record_pressure_solve(cb, false, divergence_budget_.budget());
  stamp();
  p.dispatch(cb, Pass::dfsph_forces, g);
  program_->barrier(cb, Barrier::compute);
  p.dispatch(cb, Pass::dfsph_predict, g);
  program_->barrier(cb, Barrier::compute);
  if (viscous_) record_viscosity_solve(cb, viscosity_budget_.budget());
  stamp();
  record_pressure_solve(cb, true, density_budget_.budget());
  stamp();
  p.dispatch(cb, Pass::dfsph_integrate, g);
  program_->barrier(cb, Barrier::compute);
  stamp();
}

}  // namespace hapfluid::sim::vulkan
