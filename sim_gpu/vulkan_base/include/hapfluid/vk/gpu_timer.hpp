// Timestamp queries between the passes of a command buffer: where a frame's or a step's time
// goes (lavapipe executes a command buffer pass by pass on its worker threads, so these are real
// per-pass costs there too).
#pragma once

#include <array>
#include <cstdint>

#include "hapfluid/vk/context.hpp"

namespace hapfluid::vk {

class GpuTimer {
 public:
  static constexpr uint32_t capacity = 8;
  explicit GpuTimer(Context& ctx);
  GpuTimer(const GpuTimer&) = delete;
  GpuTimer& operator=(const GpuTimer&) = delete;
  ~GpuTimer();
  void begin(VkCommandBuffer cmd);      // resets the pool and writes stamp 0
  void stamp(VkCommandBuffer cmd);      // writes the next stamp after all previous work
  // Milliseconds between consecutive stamps of the last completed frame; false if not available.
  bool intervals_ms(std::array<double, capacity - 1>& out, uint32_t& count) const;

 private:
  Context& ctx_;
  VkQueryPool pool_ = VK_NULL_HANDLE;
  uint32_t written_ = 0;
};

}  // namespace hapfluid::vk
