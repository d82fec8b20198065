// Recording of the step: the passes of one substep in order, with a barrier between passes and
// timestamps between pass groups. Recorded once per substep count and re-submitted.
#include "hapfluid/sim_vulkan/vulkan_solver.hpp"

#include <functional>

#include "recording.hpp"

namespace hapfluid::sim::vulkan {

void VulkanSolver::record_sort(VkCommandBuffer cb) {
  const ComputeProgram& p = *program_;
  // Counts are zero here: they start zeroed and scan_add clears each count after reading it.
  p.dispatch(cb, Pass::hash_fluid, groups(fluid_count_, 64), {fluid_count_, 0, 0, 0});
  program_->barrier(cb, Barrier::compute);
  p.dispatch(cb, Pass::scan_local, scan_blocks_, {cell_count_, 0, 0, 0});
  program_->barrier(cb, Barrier::compute);
  p.dispatch(cb, Pass::scan_blocks, 1, {cell_count_, 0, 0, 0});
  program_->barrier(cb, Barrier::compute);
  p.dispatch(cb, Pass::scan_add, groups(cell_count_, 256), {cell_count_, 0, 0, 0});
  program_->barrier(cb, Barrier::compute);
  p.dispatch(cb, Pass::scatter, groups(fluid_count_, 64), {fluid_count_, 0, 0, 0});
  program_->barrier(cb, Barrier::compute);
  p.dispatch(cb, Pass::order_cells, groups(cell_count_, 64), {cell_count_, 0, 0, 0});
  program_->barrier(cb, Barrier::compute);
  p.dispatch(cb, Pass::gather_fluid, groups(fluid_count_, 64));
  program_->barrier(cb, Barrier::compute);
}

void VulkanSolver::record_body_sort(VkCommandBuffer cb) {
  // The same counting sort on the body particles: second half of the count/start/order arrays.
  const ComputeProgram& p = *program_;
  const std::uint32_t nb = body_particle_count_, nf = fluid_count_;
  p.dispatch(cb, Pass::hash_bodies, groups(nb, 64), {nb, nf, cell_count_, 0});
  program_->barrier(cb, Barrier::compute);
  p.dispatch(cb, Pass::scan_local, scan_blocks_, {cell_count_, cell_count_, body_start_base_, 0});
  program_->barrier(cb, Barrier::compute);
  p.dispatch(cb, Pass::scan_blocks, 1, {cell_count_, cell_count_, body_start_base_, 0});
  program_->barrier(cb, Barrier::compute);
  p.dispatch(cb, Pass::scan_add, groups(cell_count_, 256), {cell_count_, cell_count_, body_start_base_, 0});
  program_->barrier(cb, Barrier::compute);
  p.dispatch(cb, Pass::scatter, groups(nb, 64), {nb, nf, body_start_base_, 0});
  program_->barrier(cb, Barrier::compute);
  p.dispatch(cb, Pass::order_cells, groups(cell_count_, 64), {cell_count_, nf, body_start_base_, 0});
  program_->barrier(cb, Barrier::compute);
  p.dispatch(cb, Pass::gather_bodies, groups(nb, 64));
  program_->barrier(cb, Barrier::compute);
}

void VulkanSolver::record_body_step(VkCommandBuffer head, VkCommandBuffer tail, bool with_maxima) {
  // Head: everything up to the per-body sums the host needs to integrate the bodies.
  const ComputeProgram& p = *program_;
  const std::uint32_t bodies = static_cast<std::uint32_t>(m_.bodies.size());
  std::uint32_t query = 0;
  auto stamp = [&](VkCommandBuffer cb) {
    if (body_queries_) vkCmdWriteTimestamp(cb, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, body_queries_, query);
    ++query;
  };
  VkCommandBufferBeginInfo begin{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
  if (head) note_recorded(head, [&] {
    check(vkBeginCommandBuffer(head, &begin), "vkBeginCommandBuffer");
    if (body_queries_) vkCmdResetQueryPool(head, body_queries_, 0, kBodyStepQueries);
    program_->barrier(head, Barrier::host_to_compute);
    stamp(head);
    record_sort(head);
    record_body_sort(head);
    stamp(head);
    p.dispatch(head, Pass::density_cells, groups(cell_count_, 64));
    p.dispatch(head, Pass::body_contact_pressure, groups(body_particle_count_, 64));
    program_->barrier(head, Barrier::compute);
    stamp(head);
    p.dispatch(head, Pass::fluid_forces_cells, groups(cell_count_, 64));
    p.dispatch(head, Pass::body_forces, groups(body_particle_count_, 64));
    program_->barrier(head, Barrier::compute);
    stamp(head);
    p.dispatch(head, Pass::body_sums, body_chunk_count_);
    program_->barrier(head, Barrier::compute);
    p.dispatch(head, Pass::body_sums_final, bodies, {body_chunk_count_, 0, 0, 0});
    program_->barrier(head, Barrier::compute);
    stamp(head);
    program_->barrier(head, Barrier::compute_to_host);
    check(vkEndCommandBuffer(head), "vkEndCommandBuffer");
  });
  query = 5;

  // Tail: after the host wrote the new body states, eq. 14 and the fluid leap-frog.
  note_recorded(tail, [&] {
    check(vkBeginCommandBuffer(tail, &begin), "vkBeginCommandBuffer");
    program_->barrier(tail, Barrier::host_to_compute);
    stamp(tail);
    p.dispatch(tail, Pass::body_update, groups(body_particle_count_, 64));
    program_->barrier(tail, Barrier::compute);
    stamp(tail);
    p.dispatch(tail, Pass::integrate_fluid, groups(fluid_count_, 64));
    program_->barrier(tail, Barrier::compute);
    stamp(tail);
    // The CFL inputs are needed once per frame: only the last substep's tail computes them.
    if (with_maxima) {
      record_maxima(tail);
      program_->barrier(tail, Barrier::compute);
    }
    stamp(tail);
    program_->barrier(tail, Barrier::compute_to_host);
    check(vkEndCommandBuffer(tail), "vkEndCommandBuffer");
  });
}

void VulkanSolver::record_maxima(VkCommandBuffer cb) {
  const ComputeProgram& p = *program_;
  p.dispatch(cb, Pass::max_speed, max_groups_);
  program_->barrier(cb, Barrier::compute);
  p.dispatch(cb, Pass::max_speed_final, 1, {max_groups_, 0, 0, 0});
}

void VulkanSolver::record_steps(VkCommandBuffer cb, int substeps) {
  VkCommandBufferBeginInfo begin{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
  check(vkBeginCommandBuffer(cb, &begin), "vkBeginCommandBuffer");
  const bool timing = substeps > 0 && timed(substeps);
  std::uint32_t query = 0;
  const std::function<void()> stamp = [&] {
    if (timing) vkCmdWriteTimestamp(cb, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, queries_, query++);
  };
  if (timing) vkCmdResetQueryPool(cb, queries_, 0, queries_per_step_ * static_cast<std::uint32_t>(substeps) + 2);
  program_->barrier(cb, Barrier::host_to_compute);
  stamp();
  const ComputeProgram& p = *program_;
  if (substeps == 0 && dfsph_) {
    record_dfsph_initial(cb);
  } else if (substeps == 0) {
    // The initial state (as CpuSolver's constructor): particles in cell order with their
    // density and pressure, for a frame exported before the first step.
    record_sort(cb);
    if (body_particle_count_ > 0) record_body_sort(cb);
    p.dispatch(cb, Pass::density_cells, groups(cell_count_, 64));
    program_->barrier(cb, Barrier::compute);
    p.dispatch(cb, Pass::adopt_sorted, groups(fluid_count_, 64));
    program_->barrier(cb, Barrier::compute);
  }
  for (int s = 0; s < substeps && dfsph_; ++s) record_dfsph_step(cb, stamp);
  for (int s = 0; s < substeps && !dfsph_; ++s) {
    record_sort(cb);
    stamp();
    p.dispatch(cb, Pass::density_cells, groups(cell_count_, 64));
    program_->barrier(cb, Barrier::compute);
    stamp();
    p.dispatch(cb, Pass::fluid_forces_cells, groups(cell_count_, 64));
    program_->barrier(cb, Barrier::compute);
    stamp();
    p.dispatch(cb, Pass::integrate_fluid, groups(fluid_count_, 64));
    program_->barrier(cb, Barrier::compute);
    stamp();
  }
  record_maxima(cb);
  program_->barrier(cb, Barrier::compute);
  stamp();
  program_->barrier(cb, Barrier::compute_to_host);
  check(vkEndCommandBuffer(cb), "vkEndCommandBuffer");
}

}  // namespace hapfluid::sim::vulkan
