// Timestamp queries around each pass of a frame: where the frame time goes (lavapipe executes a
// command buffer pass by pass on its worker threads, so these are real per-pass costs there too).
#pragma once

#include <array>

#include "hapfluid/render/vk_context.hpp"

namespace hapfluid::render {

class GpuTimer {
 public:
  static constexpr uint32_t capacity = 8;
  explicit GpuTimer(VulkanContext& ctx);
  ~GpuTimer();
  void begin(VkCommandBuffer cmd);      // resets the pool and writes stamp 0
  void stamp(VkCommandBuffer cmd);      // writes the next stamp after all previous work
  // Milliseconds between consecutive stamps of the last completed frame; false if not available.
  bool intervals_ms(std::array<double, capacity - 1>& out, uint32_t& count) const;

 private:
  VulkanContext& ctx_;
  VkQueryPool pool_ = VK_NULL_HANDLE;
  uint32_t written_ = 0;
};

}  // namespace hapfluid::render
