// Recording of the step: the passes of one substep in order, with a barrier between passes and
// timestamps between pass groups. Recorded once per substep count and re-submitted.
#include "hapfluid/sim_vulkan/vulkan_solver.hpp"

namespace hapfluid::sim::vulkan {
namespace {

std::uint32_t groups(std::uint32_t threads, std::uint32_t local) { return (threads + local - 1) / local; }

void compute_barrier(VkCommandBuffer cb) {
  VkMemoryBarrier barrier{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
  barrier.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_SHADER_READ_BIT;
  barrier.dstAccessMask = VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT;
  vkCmdPipelineBarrier(cb, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, 0, 1, &barrier, 0,
                       nullptr, 0, nullptr);
}

// Host writes (parameters, counters) before the first pass; device writes visible to the host
// after the last one (the fence wait then makes them available to read).
void host_to_compute_barrier(VkCommandBuffer cb) {
  VkMemoryBarrier barrier{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
  barrier.srcAccessMask = VK_ACCESS_HOST_WRITE_BIT;
  barrier.dstAccessMask = VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_UNIFORM_READ_BIT;
  vkCmdPipelineBarrier(cb, VK_PIPELINE_STAGE_HOST_BIT, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, 0, 1, &barrier, 0, nullptr, 0,
                       nullptr);
}

void compute_to_host_barrier(VkCommandBuffer cb) {
  VkMemoryBarrier barrier{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
  barrier.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT;
  barrier.dstAccessMask = VK_ACCESS_HOST_READ_BIT | VK_ACCESS_TRANSFER_READ_BIT;
  vkCmdPipelineBarrier(cb, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_PIPELINE_STAGE_HOST_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT,
                       0, 1, &barrier, 0, nullptr, 0, nullptr);
}

}  // namespace

void VulkanSolver::record_sort(VkCommandBuffer cb) {
  const ComputeProgram& p = *program_;
  // Counts are zero here: they start zeroed and scan_add clears each count after reading it.
  p.dispatch(cb, Pass::hash_fluid, groups(fluid_count_, 64), {fluid_count_, 0, 0, 0});
  compute_barrier(cb);
  p.dispatch(cb, Pass::scan_local, scan_blocks_, {cell_count_, 0, 0, 0});
  compute_barrier(cb);
  p.dispatch(cb, Pass::scan_blocks, 1, {cell_count_, 0, 0, 0});
  compute_barrier(cb);
  p.dispatch(cb, Pass::scan_add, groups(cell_count_, 256), {cell_count_, 0, 0, 0});
  compute_barrier(cb);
  p.dispatch(cb, Pass::scatter, groups(fluid_count_, 64), {fluid_count_, 0, 0, 0});
  compute_barrier(cb);
  p.dispatch(cb, Pass::order_cells, groups(cell_count_, 64), {cell_count_, 0, 0, 0});
  compute_barrier(cb);
  p.dispatch(cb, Pass::gather_fluid, groups(fluid_count_, 64));
  compute_barrier(cb);
}

void VulkanSolver::record_maxima(VkCommandBuffer cb) {
  const ComputeProgram& p = *program_;
  p.dispatch(cb, Pass::max_speed, max_groups_);
  compute_barrier(cb);
  p.dispatch(cb, Pass::max_speed_final, 1, {max_groups_, 0, 0, 0});
}

void VulkanSolver::record_steps(VkCommandBuffer cb, int substeps) {
  VkCommandBufferBeginInfo begin{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
  check(vkBeginCommandBuffer(cb, &begin), "vkBeginCommandBuffer");
  const bool timing = substeps > 0 && timed(substeps);
  std::uint32_t query = 0;
  auto stamp = [&] {
    if (timing) vkCmdWriteTimestamp(cb, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, queries_, query++);
  };
  if (timing) vkCmdResetQueryPool(cb, queries_, 0, queries_per_step_ * static_cast<std::uint32_t>(substeps) + 2);
  host_to_compute_barrier(cb);
  stamp();
  const ComputeProgram& p = *program_;
  for (int s = 0; s < substeps; ++s) {
    record_sort(cb);
    stamp();
    p.dispatch(cb, Pass::density, groups(fluid_count_, 64));
    compute_barrier(cb);
    stamp();
    p.dispatch(cb, Pass::fluid_forces, groups(fluid_count_, 64));
    compute_barrier(cb);
    stamp();
    p.dispatch(cb, Pass::integrate_fluid, groups(fluid_count_, 64));
    compute_barrier(cb);
    stamp();
  }
  record_maxima(cb);
  compute_barrier(cb);
  stamp();
  compute_to_host_barrier(cb);
  check(vkEndCommandBuffer(cb), "vkEndCommandBuffer");
}

}  // namespace hapfluid::sim::vulkan
