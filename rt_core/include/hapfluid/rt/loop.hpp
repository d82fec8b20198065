// The 1 kHz coupling loop of haptic-rt. Everything it touches is allocated in the constructor;
// tick() does no allocation, takes no lock and makes no syscall other than the devices' own I/O
// (proved by tests/rt_core/test_loop_allocations.cpp and the strace test).
//
// Per tick: poll every device -> read the newest sim sample -> render each device's wrench
// (interpolate or coupling mode) -> safety layer -> send -> publish device states -> trace record
// (shared trace ring + private flight recorder). run() paces tick() with absolute-time
// clock_nanosleep and re-phases after overruns instead of bursting to catch up.
//
// Threads: the RT thread runs run()/tick(). A non-RT Supervisor (supervisor.hpp) attaches and
// re-attaches the sim channel, dumps the flight recorder on faults and speaks sd_notify; they
// share only the atomics below.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <vector>

#include "hapfluid/config/rig.hpp"
#include "hapfluid/device/device.hpp"
#include "hapfluid/rt/rt_setup.hpp"
#include "hapfluid/rt/workspace.hpp"
#include "hapfluid/rt/wrench_render.hpp"
#include "hapfluid/safety/safety_layer.hpp"
#include "hapfluid/shm/channel.hpp"
#include "hapfluid/shm/layouts.hpp"

namespace hapfluid::rt {

// Share of ticks with a fresh valid frame, and the longest run of ticks without one.
struct LinkQuality {
  std::uint64_t ticks = 0;
  std::uint64_t fresh_ticks = 0;
  std::uint32_t miss_run = 0;
  std::uint32_t longest_miss_run = 0;
  std::uint64_t round_trips = 0;      // commands whose echo came back (devices that echo them)
  double round_trip_ms = 0;           // the newest of them
  double longest_round_trip_ms = 0;
  double fresh_share() const { return ticks ? double(fresh_ticks) / double(ticks) : 0.0; }
};

// A sim_samples mapping handed from the supervisor to the RT thread.
struct SimAttachment {
  shm::LatestReader reader;
  std::uint64_t epoch = 0;
};

struct LoopOptions {
  std::string shm_prefix;          // empty: the rig's rt.shm.prefix
  bool publish_trace = true;       // create the shared trace ring
};

class RtLoop {
 public:
  RtLoop(const config::Rig& rig, std::vector<std::unique_ptr<device::Device>> devices, LoopOptions options = {});
  ~RtLoop();
  RtLoop(const RtLoop&) = delete;
  RtLoop& operator=(const RtLoop&) = delete;

  // One tick of loop work (no sleeping): `scheduled_ns` is the wake time asked for, `wake_ns` when
  // the thread actually ran. Allocation-free.
  void tick(std::uint64_t scheduled_ns, std::uint64_t wake_ns);
  // Paces tick() at rt.period_ns until stop() or `duration_ns` (0: forever).
  void run(std::uint64_t duration_ns);
  void stop() { running_.store(false, std::memory_order_relaxed); }

  // ---- shared with the supervisor thread (atomics only) ----
  // Supervisor publishes a new sim mapping; the RT thread acknowledges the epoch it uses.
  void offer_sim(SimAttachment* attachment) { sim_offer_.store(attachment, std::memory_order_release); }
  std::uint64_t sim_epoch_in_use() const { return sim_epoch_ack_.load(std::memory_order_acquire); }
  std::uint64_t ticks() const { return tick_count_.load(std::memory_order_acquire); }
  std::uint64_t overruns() const { return overruns_.load(std::memory_order_relaxed); }
  void request_estop() { estop_request_.store(true, std::memory_order_relaxed); }
  void request_estop_reset() { estop_reset_request_.store(true, std::memory_order_relaxed); }
  // Set by the RT thread on a fault rising edge: the tick it happened (0: none pending).
  std::uint64_t take_fault_tick() { return fault_tick_.exchange(0, std::memory_order_acq_rel); }
  std::uint32_t last_fault_bits() const { return fault_bits_.load(std::memory_order_relaxed); }
  void set_degraded_flags(std::uint32_t flags) { degraded_flags_ = flags; }

  // ---- read after run() returns (or from tests) ----
  const shm::RingWriter& flight_recorder() const { return flight_recorder_; }
  const shm::RingWriter& trace_ring() const { return trace_; }
  const LinkQuality& link_quality(std::size_t device) const { return devices_[device]->link; }
  const shm::TraceRecord& last_trace() const { return last_trace_; }
  std::size_t device_count() const { return devices_.size(); }
  const config::Rig& rig() const { return rig_; }
  const char* device_name(std::size_t i) const { return rig_.devices[i].name.c_str(); }
  std::uint32_t flight_recorder_ticks() const { return rig_.rt.flight_recorder_ticks; }

 private:
  struct PerDevice {
    PerDevice(const config::RigDevice& rig_device, std::int64_t period_ns);
    std::unique_ptr<device::Device> device;
    Workspace workspace;
    safety::SafetyLayer safety;
    InterpolatingRenderer interpolator;
    config::WrenchMode mode;
    CouplingCaps caps;
    device::DeviceState state;
    device::DeviceCommand command;
    LinkQuality link;
    bool fresh = false;
    std::uint32_t device_restarts = 0;  // health().device_restarts already taken as a link loss
    std::uint64_t foreign_commands = 0; // health().foreign_commands already latched
    std::uint64_t commands_lost = 0;    // health().commands_lost already counted
    std::uint64_t echo_round_trips = 0; // health().echo_round_trips already handed to the safety layer
    bool sim_restarted = false;    // a new sim incarnation's first sample, not yet seen by the safety layer
    safety::Wrench scene_wrench;
  };

  void read_sim(std::uint64_t now_ns, std::uint32_t& loop_flags);
  void render_device(PerDevice& d, std::size_t index, std::uint64_t now_ns, bool new_sample);
  double sim_age_ms(std::uint64_t now_ns) const;
  double pose_age_s(const shm::SimSample& sample, double cap_s) const;
  void track_sim_pace(const shm::SimSample& next, bool first);
  void publish(std::uint64_t tick, std::uint64_t scheduled_ns);

  config::Rig rig_;
  std::vector<std::unique_ptr<PerDevice>> devices_;
  shm::LatestWriter device_states_;
  shm::RingWriter trace_;
  shm::RingWriter flight_recorder_;
  shm::DeviceStatesRecord states_record_{};
  shm::TraceRecord last_trace_{};

  // Sim sample state (RT thread only).
  SimAttachment* sim_ = nullptr;
  shm::SimSample sample_{};
  shm::SimSample scratch_{};  // reads land here first: a busy read never tears sample_
  std::uint64_t sample_generation_ = 0;
  std::uint64_t sample_incarnation_ = 0;
  std::uint64_t last_new_sample_ns_ = 0;
  bool have_sample_ = false;
  // When each recent tick polled its devices (slot tick % kPollTimes): the age of the device pose
  // a sim sample was computed from, which the coupling's local model moves its anchor on by.
  static constexpr std::uint64_t kPollTimes = 256;
  std::uint64_t poll_ns_[kPollTimes] = {};
  std::uint64_t current_tick_ = 0;
  double sim_pace_ = 0.0;  // simulated seconds per wall second of the sample stream, at most 1
  double pace_sim_s_ = 0.0, pace_wall_s_ = 0.0;  // averaged intervals between samples

  std::atomic<SimAttachment*> sim_offer_{nullptr};
  std::atomic<std::uint64_t> sim_epoch_ack_{0};
  std::atomic<std::uint64_t> tick_count_{0};
  std::atomic<std::uint64_t> overruns_{0};
  std::atomic<bool> running_{true};
  std::atomic<bool> estop_request_{false};
  std::atomic<bool> estop_reset_request_{false};
  std::atomic<std::uint64_t> fault_tick_{0};
  std::atomic<std::uint32_t> fault_bits_{0};
  std::uint32_t previous_faults_ = 0;
  std::uint32_t degraded_flags_ = 0;
  std::uint32_t overrun_flag_ = 0;
};

}  // namespace hapfluid::rt
