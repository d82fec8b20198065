#include "hapfluid/vk/gpu_timer.hpp"

namespace hapfluid::vk {

GpuTimer::GpuTimer(Context& ctx) : ctx_(ctx) {
  if (!ctx.timestamps_supported()) return;
  VkQueryPoolCreateInfo info{VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO};
  info.queryType = VK_QUERY_TYPE_TIMESTAMP;
  info.queryCount = capacity;
  check(vkCreateQueryPool(ctx.device(), &info, nullptr, &pool_), "vkCreateQueryPool");
}

GpuTimer::~GpuTimer() {
  if (pool_) vkDestroyQueryPool(ctx_.device(), pool_, nullptr);
}

void GpuTimer::begin(VkCommandBuffer cmd) {
  written_ = 0;
  if (!pool_) return;
  vkCmdResetQueryPool(cmd, pool_, 0, capacity);
  stamp(cmd);
}

void GpuTimer::stamp(VkCommandBuffer cmd) {
  if (!pool_ || written_ >= capacity) return;
  // The Vulkan 1.0 command, so that compute contexts without synchronization2 time passes too.
  vkCmdWriteTimestamp(cmd, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, pool_, written_++);
}

bool GpuTimer::intervals_ms(std::array<double, capacity - 1>& out, uint32_t& count) const {
  count = 0;
  if (!pool_ || written_ < 2) return false;
  uint64_t ticks[capacity];
  VkResult r = vkGetQueryPoolResults(ctx_.device(), pool_, 0, written_, sizeof ticks, ticks, sizeof(uint64_t),
                                     VK_QUERY_RESULT_64_BIT);
  if (r != VK_SUCCESS) return false;
  const double ms_per_tick = ctx_.properties().limits.timestampPeriod * 1e-6;
  for (uint32_t i = 1; i < written_; ++i) out[count++] = double(ticks[i] - ticks[i - 1]) * ms_per_tick;
  return true;
}

}  // namespace hapfluid::vk
