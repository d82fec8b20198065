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
#include <vector>

#include "hapfluid/config/command_line.hpp"
#include "hapfluid/config/log.hpp"
#include "hapfluid/shm/channel.hpp"

using namespace hapfluid;

namespace {
std::atomic<bool> g_stop{false};
std::atomic<bool> g_switch{false};
void on_signal(int) { g_stop.store(true); }
void on_switch_signal(int) { g_switch.store(true); }

}  // namespace

int main(int argc, char** argv) {
  std::string prefix = "hapfluid", pattern = "constant", signal_pattern;
  double rate_hz = 100, duration_s = 0, stall_after_s = -1, stiffness = 0, damping = 0;
  double force[3] = {0, 0, 2}, torque[3] = {0, 0, 0};
  int devices = 1;
  const std::vector<std::string> patterns{"constant", "sine", "step", "nan", "huge", "random"};
  std::string force_text = "0,0,2", torque_text = "0,0,0";
  CLI::App app{"A stand-in sim writer for tests and fault injection: publishes sim samples of a chosen pattern.",
               "haptic-sim-standin"};
  config::apply_convention(app);
  app.add_option("--shm-prefix", prefix, "the shared-memory prefix")->capture_default_str();
  app.add_option("--rate", rate_hz, "samples per second")->check(config::positive_number("samples per second"))->capture_default_str();
  app.add_option("--duration", duration_s, "stop after this many seconds (0: on SIGINT/SIGTERM)")
      ->check(config::non_negative_number("seconds"))
      ->capture_default_str();
  app.add_option("--devices", devices, "devices per sample")->check(CLI::Range(1, static_cast<int>(shm::kMaxDevices)))
      ->capture_default_str();
  app.add_option("--pattern", pattern, "the wrench pattern")->check(CLI::IsMember(patterns))->capture_default_str();
  app.add_option("--force", force_text, "F0, N")->check(config::three_numbers())->capture_default_str();
  app.add_option("--torque", torque_text, "tau0, N.m")->check(config::three_numbers())->capture_default_str();
  app.add_option("--stiffness", stiffness, "K of the local model, N/m")->capture_default_str();
  app.add_option("--damping", damping, "D of the local model, N.s/m")->capture_default_str();
  app.add_option("--stall-after", stall_after_s, "stop publishing (stay alive) after S seconds")
      ->check(config::non_negative_number("seconds"));
  app.add_option("--on-signal", signal_pattern, "SIGUSR1 switches to this pattern")->check(CLI::IsMember(patterns));
  if (const int code = config::parse_command_line(app, argc, argv); code >= 0) return code;
  config::parse_three_numbers(force_text, force);
  config::parse_three_numbers(torque_text, torque);
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
    log::error("%s", e.what());
    return 2;
  }
  shm::LatestReader device_states;
  log::info("publishing %s wrench at %g Hz to /%s.sim_samples", pattern.c_str(),
            rate_hz, prefix.c_str());

  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> u(-1, 1);
  auto sample = std::make_unique<shm::SimSample>();
  std::snprintf(sample->backend, sizeof sample->backend, "standin");
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
    sample->pose_lead_s = pattern == "random" ? u(rng) : pattern == "huge" ? 1e300 : 0.0;
    sample->device_count = static_cast<std::uint32_t>(devices);
    for (int d = 0; d < devices; ++d) {
      shm::CouplingModel& m = sample->couplings[d];
      m = {};
      m.valid = 1;
      for (int i = 0; i < 3; ++i) {
        m.force_n[i] = scale * force[i];
        m.torque_nm[i] = scale * torque[i];
        // The anchor's twist too: the loop moves the spring's anchor on by it between samples.
        if (pattern == "huge")
          m.force_n[i] = 1e12 * (i + 1), m.torque_nm[i] = -1e9, m.vref_m_s[i] = 1e12, m.wref_rad_s[i] = -1e9;
        if (pattern == "random")
          m.force_n[i] = 1e3 * u(rng), m.torque_nm[i] = 10 * u(rng), m.vref_m_s[i] = 1e3 * u(rng),
          m.wref_rad_s[i] = 1e3 * u(rng);
        if (have_states) {
          m.x0_m[i] = states.devices[d].position_m[i];
          m.v0_m_s[i] = states.devices[d].linear_velocity_m_s[i];
          m.w0_rad_s[i] = states.devices[d].angular_velocity_rad_s[i];
        }
      }
      if (pattern == "nan") m.force_n[step % 3] = std::numeric_limits<double>::quiet_NaN();
      if (pattern == "nan" && step % 2) (step % 4 == 1 ? m.vref_m_s : m.wref_rad_s)[step % 3] = std::numeric_limits<double>::infinity();
      for (int i = 0; i < 4; ++i) m.q0[i] = have_states ? states.devices[d].orientation[i] : (i == 0 ? 1.0 : 0.0);
      m.stiffness_n_per_m = stiffness;
      m.damping_n_s_per_m = damping;
      if (pattern == "huge" || pattern == "random") m.angular_stiffness_nm_per_rad = 0.5 * stiffness;
    }
    bool stalled = stall_after_s >= 0 && t >= stall_after_s;
    if (!stalled) {
      sample->publish_ns = shm::monotonic_ns();
      writer.publish(*sample);
    }
    if (switching) {
      switched = true;
      if (!stalled)
        log::info("SIGUSR1: publishing %s wrench from publish_ns %llu", pattern.c_str(),
                  static_cast<unsigned long long>(sample->publish_ns));
    }
    next += period_ns;
    timespec ts{static_cast<time_t>(next / 1'000'000'000ull), static_cast<long>(next % 1'000'000'000ull)};
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR && !g_stop.load()) {
    }  // (SIGUSR1 must not publish early)
  }
  writer.close();
  log::info("stopped");
  return 0;
}
