// haptic-rt's non-RT helper thread (SCHED_OTHER, never pinned to the loop's CPU). It does every
// slow thing the loop must not: attaching and re-attaching the sim_samples segment (a restarted
// sim creates a new one), freeing the old mapping once the loop has moved off it, sd_notify
// READY/WATCHDOG driven by loop progress, flight-recorder dumps after a fault, and optionally
// draining the trace ring to a CSV file. A crash or stall here never blocks the loop: the loop
// only reads atomics it sets.
#pragma once

#include <atomic>
#include <cstdio>
#include <memory>
#include <string>
#include <thread>

#include "hapfluid/rt/loop.hpp"
#include "hapfluid/rt/sd_notify.hpp"

namespace hapfluid::rt {

struct SupervisorOptions {
  std::string sim_segment;        // "/<prefix>.sim_samples"
  std::string flight_dir;         // where flight-recorder dumps go
  std::string trace_path;         // empty: no in-process trace drain
  unsigned poll_ms = 10;
};

class Supervisor {
 public:
  Supervisor(RtLoop& loop, SupervisorOptions options);
  ~Supervisor();
  void start();
  // Stops the thread, then drains the rest of the trace and any pending dump.
  void stop();
  std::uint64_t flight_dumps() const { return dumps_; }

 private:
  void run();
  void step(bool final);
  void manage_sim();
  void dump_flight_recorder(std::uint64_t fault_tick, std::uint32_t fault_bits);
  void drain_trace();

  RtLoop& loop_;
  SupervisorOptions options_;
  SdNotifier notifier_;
  std::thread thread_;
  std::atomic<bool> running_{false};

  std::unique_ptr<SimAttachment> sim_current_, sim_retired_;
  std::uint64_t sim_epoch_ = 0;
  std::uint64_t next_sim_check_ns_ = 0;
  std::string last_sim_message_;   // the writer's status last said
  std::string last_attach_error_;  // why attaching failed, last said

  bool ready_sent_ = false;
  std::uint64_t last_ping_ns_ = 0, last_ping_tick_ = 0;
  std::uint64_t pending_fault_tick_ = 0;
  std::uint32_t pending_fault_bits_ = 0;
  std::uint64_t dumps_ = 0;
  std::uint64_t last_dump_ns_ = 0;

  std::FILE* trace_file_ = nullptr;
  shm::RingReader trace_reader_;
};

}  // namespace hapfluid::rt
