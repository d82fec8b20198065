#include "hapfluid/rt/stack_observer.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <nlohmann/json.hpp>

#include "hapfluid/rt/rt_setup.hpp"
#include "hapfluid/safety/flags.hpp"

namespace hapfluid::rt {
namespace {

constexpr std::uint64_t kWindowNs = 1'000'000'000;  // link quality and sim rates: the last second

// A channel's writer as the reader concluded it; a writer that is gone (or a name that now holds
// a new segment) is let go, to be attached again when it returns.
bool gone(shm::WriterStatus s) {
  return s == shm::WriterStatus::closed || s == shm::WriterStatus::dead || s == shm::WriterStatus::replaced ||
         s == shm::WriterStatus::corrupt;
}

std::string status_text(shm::WriterStatus s) {
  return s == shm::WriterStatus::not_attached ? "waiting" : shm::to_string(s);
}

template <class T>
nlohmann::json vec3(const T (&v)[3]) {
  return nlohmann::json::array({double(v[0]), double(v[1]), double(v[2])});
}

// A device name from a segment: at most its field, printable, whatever the writer put there.
std::string safe_name(const char (&raw)[shm::kDeviceNameBytes]) {
  std::string s;
  for (char c : raw) {
    if (c == '\0') break;
    s += (c >= 0x20 && c < 0x7f) ? c : '?';
  }
  return s;
}

double finite_or_zero(double v) { return std::isfinite(v) ? v : 0.0; }

}  // namespace

void LatencyHistogram::add(std::int64_t latency_ns) {
  if (latency_ns < 0) latency_ns = 0;
  ++total_;
  max_ns_ = std::max(max_ns_, latency_ns);
  const std::int64_t bin = latency_ns / 1000;
  if (bin >= kBins) ++over_;
  else ++counts_[static_cast<std::size_t>(bin)];
}

double LatencyHistogram::percentile_us(double p) const {
  if (total_ == 0) return 0;
  const double want = p * double(total_);
  double seen = 0;
  for (int b = 0; b < kBins; ++b) {
    seen += double(counts_[b]);
    if (seen >= want) return double(b + 1);
  }
  return max_us();
}

std::vector<std::uint64_t> LatencyHistogram::coarse(int bins, double upto_us) const {
  std::vector<std::uint64_t> out(static_cast<std::size_t>(std::max(bins, 1)), 0);
  const double width = upto_us / double(out.size() - 1);
  for (int b = 0; b < kBins; ++b) {
    const std::size_t k = std::min(out.size() - 1, static_cast<std::size_t>(double(b) / width));
    out[k] += counts_[b];
  }
  out.back() += over_;
  return out;
}

struct StackObserver::Trace {
  shm::RingAttachment ring;
  shm::RingReader reader;
};

StackObserver::StackObserver(std::string prefix) : prefix_(std::move(prefix)) {}
StackObserver::~StackObserver() = default;

void StackObserver::poll(std::uint64_t now_ns) {
  poll_trace(now_ns);
  poll_states(now_ns);
  poll_sim(now_ns);
}

void StackObserver::poll_trace(std::uint64_t now_ns) {
  if (!trace_) {
    try {
      auto t = std::make_unique<Trace>();
      t->ring = shm::RingAttachment::attach(shm::segment_name(prefix_, shm::ChannelKind::trace),
                                            shm::ChannelKind::trace, sizeof(shm::TraceRecord));
      t->reader = t->ring.reader_from_oldest();
      trace_ = std::move(t);
    } catch (const shm::ShmError&) {
      if (loop_.status == "live" || loop_.status == "stale") loop_.status = "stopped";
      return;
    }
    const std::uint64_t incarnation = trace_->ring.segment().layout().incarnation;
    if (incarnation != trace_incarnation_) {  // a new loop run: its own statistics
      trace_incarnation_ = incarnation;
      loop_ = ObservedLoop{};
      previous_scheduled_ns_ = previous_tick_ = period_ns_ = 0;
      for (auto& w : fresh_window_) w.clear();
    }
  }
  shm::TraceRecord r{};
  while (trace_->reader.next(r)) on_record(r);
  loop_.lost = trace_->reader.lost();
  const shm::WriterStatus s = trace_->ring.check_liveness(now_ns, kObserverStaleNs);
  loop_.status = status_text(s);
  if (gone(s)) trace_.reset();
}

void StackObserver::on_record(const shm::TraceRecord& r) {
  ++loop_.records;
  loop_.tick = r.tick;
  loop_.overruns = r.overruns;
  loop_.loop_flags = r.loop_flags;
  if (r.wake_ns >= r.scheduled_ns) loop_.latency.add(static_cast<std::int64_t>(r.wake_ns - r.scheduled_ns));
  else loop_.latency.add(0);
  if (previous_tick_ && r.tick == previous_tick_ + 1 && r.scheduled_ns > previous_scheduled_ns_)
    period_ns_ = r.scheduled_ns - previous_scheduled_ns_;
  previous_tick_ = r.tick, previous_scheduled_ns_ = r.scheduled_ns;
  // A deadline miss: this tick's commands left after the next tick was due.
  if (period_ns_ && r.send_ns > r.scheduled_ns + period_ns_) ++loop_.deadline_misses;
  const std::uint32_t n = std::min<std::uint32_t>(r.device_count, shm::kMaxDevices);
  if (devices_.size() < n) devices_.resize(n);
  for (std::uint32_t i = 0; i < n; ++i) {
    const shm::TraceDevice& t = r.devices[i];
    ObservedDevice& d = devices_[i];
    const std::uint32_t rising = t.faults & ~d.faults;
    if (rising) d.last_fault = safety::fault_names(rising), d.last_fault_ns = r.scheduled_ns;
    d.faults = t.faults;
    d.flags = t.safety_flags;
    d.miss_run = t.link_miss_run;
    for (int k = 0; k < 3; ++k)
      d.command_force_n[k] = std::isfinite(t.force_n[k]) ? t.force_n[k] : 0.0f,
      d.command_torque_nm[k] = std::isfinite(t.torque_nm[k]) ? t.torque_nm[k] : 0.0f;
    auto& w = fresh_window_[i];
    w.push_back(t.fresh != 0);
    // The window holds a second of ticks at the loop's period (1 kHz: 1,000).
    const std::size_t keep = period_ns_ ? std::max<std::size_t>(1, kWindowNs / period_ns_) : 1000;
    while (w.size() > keep) w.pop_front();
    d.fresh_share = double(std::count(w.begin(), w.end(), true)) / double(w.size());
  }
}

void StackObserver::poll_states(std::uint64_t now_ns) {
  if (!states_.valid()) {
    try {
      states_ = shm::LatestReader::attach(shm::segment_name(prefix_, shm::ChannelKind::device_states),
                                          shm::ChannelKind::device_states, sizeof(shm::DeviceStatesRecord));
    } catch (const shm::ShmError&) {
      if (states_status_ != "waiting") states_status_ = "stopped";
      return;
    }
  }
  shm::DeviceStatesRecord rec{};
  if (states_.try_read(rec) == shm::ReadResult::ok) {
    const std::uint32_t n = std::min<std::uint32_t>(rec.device_count, shm::kMaxDevices);
    if (devices_.size() < n) devices_.resize(n);
    for (std::uint32_t i = 0; i < n; ++i) {
      const shm::DeviceStateEntry& e = rec.devices[i];
      ObservedDevice& d = devices_[i];
      d.name = safe_name(e.name);
      d.present = e.present == 1;
      d.buttons = e.buttons;
      for (int k = 0; k < 3; ++k) {
        d.position_m[k] = finite_or_zero(e.position_m[k]);
        d.hand_force_n[k] = finite_or_zero(e.force_n[k]);
        d.hand_torque_nm[k] = finite_or_zero(e.torque_nm[k]);
      }
    }
  }
  const shm::WriterStatus s = states_.check_liveness(now_ns, kObserverStaleNs);
  states_status_ = status_text(s);
  if (gone(s)) states_ = {};
}

void StackObserver::poll_sim(std::uint64_t now_ns) {
  if (!samples_.valid()) {
    try {
      samples_ = shm::LatestReader::attach(shm::segment_name(prefix_, shm::ChannelKind::sim_samples),
                                           shm::ChannelKind::sim_samples, sizeof(shm::SimSample));
    } catch (const shm::ShmError&) {
      if (sim_.status != "waiting") sim_.status = "stopped";
      for (auto& d : devices_) d.sim_valid = false;
      return;
    }
  }
  if (!particles_.valid()) {
    try {  // the frame's size is the sim's choice: only its header is read
      particles_ = shm::LatestReader::attach(shm::segment_name(prefix_, shm::ChannelKind::particles),
                                             shm::ChannelKind::particles, 0);
    } catch (const shm::ShmError&) {
    }
  }
  const std::uint64_t incarnation = samples_.segment().layout().incarnation;
  if (incarnation != sample_incarnation_) {
    sample_incarnation_ = incarnation;
    sample_window_.clear();
    sim_ = ObservedSim{};
  }
  static_assert(sizeof(shm::SimSample) < 4096);
  shm::SimSample s;
  std::memset(&s, 0, sizeof s);
  if (samples_.try_read(s) == shm::ReadResult::ok) {
    s.backend[sizeof s.backend - 1] = '\0';
    sim_.backend.clear();
    for (const char* c = s.backend; *c; ++c) sim_.backend += (*c >= 0x20 && *c < 0x7f) ? *c : '?';
    sim_.fluid_particles = s.fluid_particles;
    sim_.threads_active = s.threads_active;
    sim_.sequence = s.sequence;
    sim_.sim_time_s = finite_or_zero(s.sim_time_s);
    sim_.sample_age_ms = s.publish_ns <= now_ns ? double(now_ns - s.publish_ns) * 1e-6 : 0.0;
    if (sample_window_.empty() || s.sequence != sample_window_.back().sequence)
      sample_window_.push_back({s.publish_ns, s.sequence, sim_.sim_time_s});
    while (sample_window_.size() > 2 && sample_window_.back().publish_ns - sample_window_.front().publish_ns > kWindowNs)
      sample_window_.pop_front();
    const SamplePoint &a = sample_window_.front(), &b = sample_window_.back();
    if (b.publish_ns > a.publish_ns && b.sequence >= a.sequence) {
      const double wall_s = double(b.publish_ns - a.publish_ns) * 1e-9;
      sim_.steps_per_s = double(b.sequence - a.sequence) / wall_s;
      sim_.real_time_factor = (b.sim_time_s - a.sim_time_s) / wall_s;
    }
    const std::uint32_t n = std::min<std::uint32_t>(s.device_count, shm::kMaxDevices);
    for (std::uint32_t i = 0; i < n && i < devices_.size(); ++i) {
      const shm::CouplingModel& c = s.couplings[i];
      devices_[i].sim_valid = c.valid == 1;
      for (int k = 0; k < 3; ++k)
        devices_[i].sim_force_n[k] = finite_or_zero(c.force_n[k]),
        devices_[i].sim_torque_nm[k] = finite_or_zero(c.torque_nm[k]);
    }
  }
  if (particles_.valid()) {
    shm::ParticleFrameHeader h{};
    if (particles_.try_read(&h, sizeof h) == shm::ReadResult::ok && !s.fluid_particles)
      sim_.fluid_particles = h.particle_count;
    if (gone(particles_.check_liveness(now_ns, kObserverStaleNs))) particles_ = {};
  }
  const shm::WriterStatus st = samples_.check_liveness(now_ns, kObserverStaleNs);
  sim_.status = status_text(st);
  if (gone(st)) {
    samples_ = {};
    for (auto& d : devices_) d.sim_valid = false;
  }
}

std::string StackObserver::snapshot_json(std::uint64_t now_ns) const {
  nlohmann::json j;
  j["now_ns"] = now_ns;
  j["prefix"] = prefix_;
  const LatencyHistogram& h = loop_.latency;
  j["loop"] = {{"status", loop_.status},
               {"tick", loop_.tick},
               {"overruns", loop_.overruns},
               {"deadline_misses", loop_.deadline_misses},
               {"records", loop_.records},
               {"records_lost", loop_.lost},
               {"period_us", double(period_ns_) * 1e-3},
               {"degraded", (loop_.loop_flags & kDegradedMask) != 0},
               {"wake_latency_us",
                {{"p50", h.percentile_us(0.5)},
                 {"p99", h.percentile_us(0.99)},
                 {"p99.9", h.percentile_us(0.999)},
                 {"max", h.max_us()},
                 {"n", h.count()},
                 {"histogram_upto_us", 200},
                 {"histogram", h.coarse(41, 200.0)}}}};
  j["device_states"] = states_status_;
  j["sim"] = {{"status", sim_.status},
              {"backend", sim_.backend},
              {"fluid_particles", sim_.fluid_particles},
              {"threads_active", sim_.threads_active},
              {"steps", sim_.sequence},
              {"sim_time_s", sim_.sim_time_s},
              {"steps_per_s", sim_.steps_per_s},
              {"real_time_factor", sim_.real_time_factor},
              {"sample_age_ms", sim_.sample_age_ms}};
  nlohmann::json devices = nlohmann::json::array();
  for (const ObservedDevice& d : devices_) {
    const bool hard_zero = (d.flags & safety::flag_hard_zero) != 0;
    devices.push_back({{"name", d.name},
                       {"faults", d.faults ? safety::fault_names(d.faults) : ""},
                       {"flags", d.flags ? safety::flag_names(d.flags) : ""},
                       {"last_fault", d.last_fault},
                       {"last_fault_age_s", d.last_fault_ns && now_ns > d.last_fault_ns
                                                ? double(now_ns - d.last_fault_ns) * 1e-9
                                                : -1.0},
                       {"link_ok", (d.faults & (safety::fault_link_timeout | safety::fault_link_invalid |
                                                safety::fault_device_not_listening | safety::fault_link_latency)) == 0},
                       {"fresh_share", d.fresh_share},
                       {"miss_run", d.miss_run},
                       {"engage", hard_zero                                 ? "off"
                                  : d.flags & safety::flag_waiting_to_engage ? "waiting"
                                  : d.flags & safety::flag_engaging          ? "engaging"
                                                                             : "engaged"},
                       {"estop", (d.faults & safety::fault_estop) != 0},
                       {"deadman", (d.buttons & 1u) != 0},
                       {"position_m", vec3(d.position_m)},
                       {"command_force_n", vec3(d.command_force_n)},
                       {"command_torque_nm", vec3(d.command_torque_nm)},
                       {"hand_force_n", vec3(d.hand_force_n)},
                       {"hand_torque_nm", vec3(d.hand_torque_nm)},
                       {"sim_valid", d.sim_valid},
                       {"sim_force_n", vec3(d.sim_force_n)},
                       {"sim_torque_nm", vec3(d.sim_torque_nm)}});
  }
  j["devices"] = devices;
  return j.dump();
}

}  // namespace hapfluid::rt
