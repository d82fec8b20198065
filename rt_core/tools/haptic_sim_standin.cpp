// haptic-sim-standin: a stand-in for haptic-sim that writes /<prefix>.sim_samples through
// hapfluid_shm with a scripted wrench, for rt_core's multi-process tests and for fault injection
// (a hostile sim writer, a stalled sim). It does no physics.
//   haptic-sim-standin [--shm-prefix NAME] [--rate HZ] [--duration S] [--devices N]
//       [--pattern constant|sine|step|nan|huge|random] [--force FX,FY,FZ] [--torque TX,TY,TZ]
//       [--stiffness N_PER_M] [--damping N_S_PER_M] [--stall-after S] [--on-signal PATTERN]
// --on-signal: SIGUSR1 switches to PATTERN (a hostile sample at an instant a test chose); the
// publish_ns of the first such sample is printed on stderr.
// Coupling model: x0/v0 are the device's pose/twist read from /<prefix>.device_states when
// haptic-rt runs (else zero), so coupling-mode devices feel F0 - K (x - x0) + D (v0 - v).
#include <signal.h>
#include <time.h>

#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <memory>
#include <random>
#include <string>

#include "hapfluid/shm/channel.hpp"

using namespace hapfluid;

namespace {
std::atomic<bool> g_stop{false};
std::atomic<bool> g_switch{false};
void on_signal(int) { g_stop.store(true); }
void on_switch_signal(int) { g_switch.store(true); }

bool parse_vec3(const char* text, double out[3]) {
  return std::sscanf(text, "%lf,%lf,%lf", &out[0], &out[1], &out[2]) == 3;
}
}  // namespace

int main(int argc, char** argv) {
  std::string prefix = "hapfluid", pattern = "constant", signal_pattern;
  double rate_hz = 100, duration_s = 0, stall_after_s = -1, stiffness = 0, damping = 0;
  double force[3] = {0, 0, 2}, torque[3] = {0, 0, 0};
  int devices = 1;
  for (int i = 1; i < argc; ++i) {
    std::string a = argv[i];
    if (i + 1 >= argc) {
      std::fprintf(stderr, "haptic-sim-standin: %s needs a value\n", a.c_str());
      return 2;
    }
    const char* v = argv[++i];
    bool ok = true;
    if (a == "--shm-prefix") prefix = v;
    else if (a == "--rate") ok = (rate_hz = std::atof(v)) > 0;
    else if (a == "--duration") duration_s = std::atof(v);
    else if (a == "--devices") ok = (devices = std::atoi(v)) >= 1 && devices <= shm::kMaxDevices;
    else if (a == "--pattern") pattern = v;
    else if (a == "--force") ok = parse_vec3(v, force);
    else if (a == "--torque") ok = parse_vec3(v, torque);
    else if (a == "--stiffness") stiffness = std::atof(v);
    else if (a == "--damping") damping = std::atof(v);
    else if (a == "--stall-after") stall_after_s = std::atof(v);
    else if (a == "--on-signal") signal_pattern = v;
    else {
      std::fprintf(stderr, "haptic-sim-standin: unknown argument \"%s\"\n", a.c_str());
      return 2;
    }
    if (!ok) {
      std::fprintf(stderr, "haptic-sim-standin: %s %s: invalid value\n", a.c_str(), v);
      return 2;
    }
  }
  auto unknown = [](const char* option, const std::string& name) {
    static const std::string patterns[] = {"constant", "sine", "step", "nan", "huge", "random"};
    for (const auto& p : patterns)
      if (p == name) return false;
    std::fprintf(stderr, "haptic-sim-standin: %s %s: must be constant, sine, step, nan, huge or random\n", option,
                 name.c_str());
    return true;
  };
  if (unknown("--pattern", pattern) || (!signal_pattern.empty() && unknown("--on-signal", signal_pattern))) return 2;
  struct sigaction action {};
  action.sa_handler = on_signal;
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
  if (!signal_pattern.empty()) {
    struct sigaction switch_action {};
    switch_action.sa_handler = on_switch_signal;
    sigaction(SIGUSR1, &switch_action, nullptr);
  }

  shm::LatestWriter writer;
  try {
    writer = shm::LatestWriter::create(shm::segment_name(prefix, shm::ChannelKind::sim_samples),
                                       shm::ChannelKind::sim_samples, sizeof(shm::SimSample));
  } catch (const shm::ShmError& e) {
    std::fprintf(stderr, "haptic-sim-standin: %s\n", e.what());
    return 2;
  }
  shm::LatestReader device_states;
  std::fprintf(stderr, "haptic-sim-standin: publishing %s wrench at %g Hz to /%s.sim_samples\n", pattern.c_str(),
               rate_hz, prefix.c_str());

  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> u(-1, 1);
  auto sample = std::make_unique<shm::SimSample>();
  shm::DeviceStatesRecord states{};
  const std::uint64_t period_ns = static_cast<std::uint64_t>(1e9 / rate_hz);
  const std::uint64_t start = shm::monotonic_ns();
  std::uint64_t next = start;
  bool switched = false;
  for (std::uint64_t step = 1; !g_stop.load(); ++step) {
    double t = double(next - start) * 1e-9;
    const bool switching = !switched && g_switch.load();
    if (switching) pattern = signal_pattern;
    if (duration_s > 0 && t >= duration_s) break;
    if (!device_states.valid()) {
      try {
        device_states = shm::LatestReader::attach(shm::segment_name(prefix, shm::ChannelKind::device_states),
                                                  shm::ChannelKind::device_states, sizeof(shm::DeviceStatesRecord));
      } catch (const shm::ShmError&) {
      }
    }
    bool have_states = device_states.valid() && device_states.try_read(states) == shm::ReadResult::ok;
    double scale = 1.0;
    if (pattern == "sine") scale = std::sin(2 * M_PI * 1.0 * t);
    if (pattern == "step") scale = std::fmod(t, 1.0) < 0.5 ? 0.0 : 1.0;
    sample->sequence = step;
    sample->sim_time_s = t;
    sample->device_tick = have_states ? states.tick : 0;
    sample->device_count = static_cast<std::uint32_t>(devices);
    for (int d = 0; d < devices; ++d) {
      shm::CouplingModel& m = sample->couplings[d];
      m = {};
      m.valid = 1;
      for (int i = 0; i < 3; ++i) {
        m.force_n[i] = scale * force[i];
        m.torque_nm[i] = scale * torque[i];
        if (pattern == "huge") m.force_n[i] = 1e12 * (i + 1), m.torque_nm[i] = -1e9;
        if (pattern == "random") m.force_n[i] = 1e3 * u(rng), m.torque_nm[i] = 10 * u(rng);
        if (have_states) {
          m.x0_m[i] = states.devices[d].position_m[i];
          m.v0_m_s[i] = states.devices[d].linear_velocity_m_s[i];
          m.w0_rad_s[i] = states.devices[d].angular_velocity_rad_s[i];
        }
      }
      if (pattern == "nan") m.force_n[step % 3] = std::numeric_limits<double>::quiet_NaN();
      for (int i = 0; i < 4; ++i) m.q0[i] = have_states ? states.devices[d].orientation[i] : (i == 0 ? 1.0 : 0.0);
      m.stiffness_n_per_m = stiffness;
      m.damping_n_s_per_m = damping;
    }
    bool stalled = stall_after_s >= 0 && t >= stall_after_s;
    if (!stalled) {
      sample->publish_ns = shm::monotonic_ns();
      writer.publish(*sample);
    }
    if (switching) {
      switched = true;
      if (!stalled)
        std::fprintf(stderr, "haptic-sim-standin: SIGUSR1: publishing %s wrench from publish_ns %llu\n", pattern.c_str(),
                     static_cast<unsigned long long>(sample->publish_ns));
    }
    next += period_ns;
    timespec ts{static_cast<time_t>(next / 1'000'000'000ull), static_cast<long>(next % 1'000'000'000ull)};
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR && !g_stop.load()) {
    }  // (SIGUSR1 must not publish early)
  }
  writer.close();
  std::fprintf(stderr, "haptic-sim-standin: stopped\n");
  return 0;
}
