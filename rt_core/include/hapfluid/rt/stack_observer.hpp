// What a read-only observer sees of a running stack (haptic-status, behind haptic-dashboard):
// the loop's trace ring, the device states and the sim samples and particle frames, each mapped
// read-only through the shm readers, which trust nothing in a segment. It never writes a byte of
// any segment and takes no lock a writer takes, so it cannot slow the loop or the sim. Parts may
// start, stop and restart in any order: a channel that is not there is "waiting", one whose
// writer stopped is said so and attached again when its writer returns.
#pragma once

#include <array>
#include <cstdint>
#include <deque>
#include <memory>
#include <string>
#include <vector>

#include "hapfluid/shm/channel.hpp"
#include "hapfluid/shm/layouts.hpp"

namespace hapfluid::rt {

// How long a channel's heartbeat may stand still before its writer counts as stale.
inline constexpr std::uint64_t kObserverStaleNs = 500'000'000;

// Wake latency (wake_ns - scheduled_ns) of every loop tick seen, in 1 us bins up to 5 ms.
class LatencyHistogram {
 public:
  static constexpr int kBins = 5000;
  void add(std::int64_t latency_ns);
  void clear() { counts_.fill(0), total_ = 0, over_ = 0, max_ns_ = 0; }
  std::uint64_t count() const { return total_; }
  double percentile_us(double p) const;  // upper edge of the bin holding percentile p (0..1)
  double max_us() const { return double(max_ns_) * 1e-3; }
  // Counts merged into `bins` equal bins up to `upto_us` (the last one holds all above).
  std::vector<std::uint64_t> coarse(int bins, double upto_us) const;

 private:
  std::array<std::uint64_t, kBins> counts_{};
  std::uint64_t total_ = 0, over_ = 0;
  std::int64_t max_ns_ = 0;
};

struct ObservedDevice {
  std::string name;
  bool present = false;
  std::uint32_t faults = 0, flags = 0, buttons = 0;
  std::string last_fault;              // names of the fault bits that rose last, "" if none yet
  std::uint64_t last_fault_ns = 0;     // when they rose (the tick's scheduled time)
  std::uint32_t miss_run = 0;          // ticks without a fresh frame, now
  double fresh_share = 0;              // of the ticks in the last second
  float command_force_n[3] = {}, command_torque_nm[3] = {};  // sent to the device, device frame
  double hand_force_n[3] = {}, hand_torque_nm[3] = {};       // rendered on the hand, scene frame
  double position_m[3] = {};                                 // handle, scene frame
  bool sim_valid = false;
  double sim_force_n[3] = {}, sim_torque_nm[3] = {};         // the sim's wrench, scene frame
};

struct ObservedLoop {
  std::string status = "waiting";      // of its trace ring: waiting, live, stale, closed, dead, ...
  std::uint64_t tick = 0, overruns = 0, deadline_misses = 0, records = 0, lost = 0;
  std::uint32_t loop_flags = 0;
  LatencyHistogram latency;            // since this loop run began (or the observer attached)
};

struct ObservedSim {
  std::string status = "waiting";
  std::string backend;
  std::uint32_t fluid_particles = 0, threads_active = 0;
  std::uint64_t sequence = 0;
  double sim_time_s = 0, steps_per_s = 0, real_time_factor = 0;
  double sample_age_ms = -1;           // now - the newest sample's publish time; -1: none
};

class StackObserver {
 public:
  explicit StackObserver(std::string prefix);
  ~StackObserver();
  // Attaches what appeared, lets go of what stopped, drains the trace and reads the newest
  // device states and sim sample. Never throws for anything a segment holds.
  void poll(std::uint64_t now_ns);

  const ObservedLoop& loop() const { return loop_; }
  const ObservedSim& sim() const { return sim_; }
  const std::vector<ObservedDevice>& devices() const { return devices_; }
  const std::string& states_status() const { return states_status_; }
  // One JSON object (one line) with all of the above, for haptic-dashboard.
  std::string snapshot_json(std::uint64_t now_ns) const;

 private:
  struct Trace;
  void poll_trace(std::uint64_t now_ns);
  void poll_states(std::uint64_t now_ns);
  void poll_sim(std::uint64_t now_ns);
  void on_record(const shm::TraceRecord& r);

  std::string prefix_;
  std::unique_ptr<Trace> trace_;
  shm::LatestReader states_, samples_, particles_;
  std::string states_status_ = "waiting";
  ObservedLoop loop_;
  ObservedSim sim_;
  std::vector<ObservedDevice> devices_;
  std::uint64_t trace_incarnation_ = 0;
  std::uint64_t previous_scheduled_ns_ = 0, previous_tick_ = 0;
  std::uint64_t period_ns_ = 0;
  // Per device, fresh flags of the last second's ticks, newest last.
  std::array<std::deque<bool>, shm::kMaxDevices> fresh_window_;
  // Sim samples of about the last second: (publish_ns, sequence, sim_time_s).
  struct SamplePoint {
    std::uint64_t publish_ns, sequence;
    double sim_time_s;
  };
  std::deque<SamplePoint> sample_window_;
  std::uint64_t sample_incarnation_ = 0;
};

}  // namespace hapfluid::rt
