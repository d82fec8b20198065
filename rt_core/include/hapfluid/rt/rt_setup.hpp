// Real-time set-up of the haptic-rt process, done once before the loop starts: mlockall,
// prefaulted stack and heap, SCHED_FIFO priority, CPU affinity, and a check of the kernel
// (/sys/kernel/realtime). Each step reports success or an errno-specific reason with the fix.
// rt.policy = enforce: any failure refuses to run; ignore: warn once, loudly, run degraded and
// mark every trace record.
#pragma once

#include <cstdint>
#include <string>

#include "hapfluid/config/rig.hpp"

namespace hapfluid::rt {

enum LoopFlag : std::uint32_t {
  loop_no_fifo = 1u << 0,          // not SCHED_FIFO (degraded)
  loop_no_mlock = 1u << 1,         // memory not locked (degraded)
  loop_no_affinity = 1u << 2,      // not pinned to the configured CPU (degraded)
  loop_not_preempt_rt = 1u << 3,   // kernel is not PREEMPT_RT
  loop_overrun = 1u << 4,          // this tick started late by more than a period
  loop_sim_not_attached = 1u << 5, // no usable sim_samples segment mapped (none, or a corrupt one)
  loop_sim_read_busy = 1u << 6,    // the sim sample could not be read consistently this tick
  loop_new_sim_sample = 1u << 7,   // a new sim sample arrived this tick
};
inline constexpr std::uint32_t kDegradedMask = loop_no_fifo | loop_no_mlock | loop_no_affinity;

struct RtSetupReport {
  std::uint32_t degraded_flags = 0;  // LoopFlag bits that hold for the whole run
  std::string messages;              // one line per problem, with errno reason and fix
  bool refused = false;              // enforce policy and something failed
};

// Applies the rig's rt settings to the calling thread/process.
RtSetupReport setup_realtime(const config::RtSettings& rt);
// Touches `bytes` of stack so no page fault happens inside the loop.
void prefault_stack(std::size_t bytes);
// Disables heap trimming and mmap for malloc, and touches `bytes` of heap once.
void prefault_heap(std::size_t bytes);
// Moves every other thread of this process (device reopen workers, the supervisor, library
// threads) off `cpu`, so none of their syscalls, which a non-PREEMPT_RT kernel does not preempt,
// sits on the loop's CPU when it wakes. Call from the loop thread after pinning it; returns how
// many threads were moved (0 when cpu < 0 or the machine has one CPU).
int keep_other_threads_off_cpu(int cpu);
// "PREEMPT_RT" or "not PREEMPT_RT (...)" from /sys/kernel/realtime.
bool kernel_is_preempt_rt();

}  // namespace hapfluid::rt
