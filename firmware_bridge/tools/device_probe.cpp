// haptic-device-probe: drives one device through the same driver the 1 kHz loop uses (open_device
// + Device::poll/send) at 1 kHz and reports what it saw: state rate, round-trip latency
// host -> device -> host (command sent until a state echoes its sequence), sequence gaps, bad
// frames, transport errors, faults, and how long the device took to trip its watchdog after the
// host fell silent. For end-to-end tests, hardware-in-the-loop runs and latency benchmarks.
// `haptic-device-probe --help` lists the options.
#include <time.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

#include "hapfluid/config/command_line.hpp"
#include "hapfluid/config/json_output.hpp"
#include "hapfluid/config/log.hpp"
#include "hapfluid/config/rig.hpp"
#include "hapfluid/device/haptic_arm.hpp"
#include "hapfluid/device/open_device.hpp"

using namespace hapfluid;

namespace {

struct Options {
  config::RigDevice device;
  bool from_rig = false;  // the device's INFO is checked against a rig only when one was given
  double duration_s = 2, silent_after_s = -1, clear_faults_at_s = -1, estop_at_s = -1;
  double force[3] = {0, 0, 0}, torque[3] = {0, 0, 0};
  bool enable = false;
  std::string out;
};

// Returns -1 to go on with `o`, else the exit code (help or version printed, a usage error said).
int parse(int argc, char** argv, Options& o) {
  o.device.name = "probe";
  std::string rig_file, rig_device, transport = "loopback", kind = "haptic_arm", force = "0,0,0", torque = "0,0,0";
  int node = static_cast<int>(o.device.transport.can_node_id);
  CLI::App app{"Drives one device through the 1 kHz loop's own driver and reports what it saw (JSON on stdout).",
               "haptic-device-probe"};
  config::apply_convention(app);
  CLI::Option* rig_opt = app.add_option("--rig", rig_file, "a rig file: probe its device --device");
  app.add_option("--device", rig_device, "the rig device to probe")->needs(rig_opt);
  rig_opt->needs("--device");
  app.add_option("--transport", transport, "the transport, without a rig")
      ->check(CLI::IsMember({"loopback", "socketcan", "hid", "usb_bulk"}))
      ->capture_default_str();
  app.add_option("--address", o.device.transport.address, "socket path, CAN interface, vid:pid or /dev/hidraw path");
  app.add_option("--framing", o.device.transport.framing, "which wire bytes a loopback transport carries")
      ->check(CLI::IsMember({"can", "canfd", "hid", "bulk"}))
      ->capture_default_str();
  app.add_option("--node", node, "CAN node id")->check(CLI::Range(1, 15))->capture_default_str();
  app.add_option("--kind", kind, "device kind")->check(CLI::IsMember({"haptic_arm", "spacemouse"}))->capture_default_str();
  app.add_option("--duration", o.duration_s, "run time, s")->check(config::non_negative_number("seconds"))->capture_default_str();
  app.add_option("--force", force, "force to command, N")->check(config::three_numbers())->capture_default_str();
  app.add_option("--torque", torque, "torque to command, N.m")->check(config::three_numbers())->capture_default_str();
  app.add_flag("--enable", o.enable, "set the enable flag (motors on)");
  app.add_option("--silent-after", o.silent_after_s, "stop sending commands after S seconds (watchdog test), keep reading")
      ->check(config::non_negative_number("seconds"));
  app.add_option("--clear-faults-at", o.clear_faults_at_s, "send disabled commands with clear_faults from S on")
      ->check(config::non_negative_number("seconds"));
  app.add_option("--estop-at", o.estop_at_s, "request an emergency stop at S")->check(config::non_negative_number("seconds"));
  app.add_option("--out", o.out, "write the report there too (always printed on stdout)");
  if (const int code = config::parse_command_line(app, argc, argv); code >= 0) return code;
  o.device.transport.kind = transport == "socketcan" ? config::TransportKind::socketcan
                            : transport == "hid"      ? config::TransportKind::hid
                            : transport == "usb_bulk" ? config::TransportKind::usb_bulk
                                                      : config::TransportKind::loopback;
  o.device.transport.can_fd = o.device.transport.framing == "canfd";
  o.device.transport.can_node_id = static_cast<std::uint32_t>(node);
  o.device.kind = kind == "spacemouse" ? config::DeviceKind::spacemouse : config::DeviceKind::haptic_arm;
  config::parse_three_numbers(force, o.force);
  config::parse_three_numbers(torque, o.torque);
  if (!rig_file.empty()) {
    config::Rig rig = config::load_rig(rig_file);
    const config::RigDevice* d = rig.find_device(rig_device);
    if (!d) throw std::invalid_argument(rig_file + ": no device named '" + rig_device + "'");
    o.device = *d;
    o.from_rig = true;
  }
  if (o.device.transport.address.empty()) {
    log::error("--address (or --rig with --device) is required (haptic-device-probe --help for usage)");
    return config::kUsageExitCode;
  }
  return -1;
}

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return -1;
  std::sort(v.begin(), v.end());
  return v[static_cast<std::size_t>(std::min<double>(v.size() - 1, std::floor(p / 100.0 * v.size())))];
}

int run(const Options& o) {
  auto dev = device::open_device(o.device, o.from_rig ? device::RigFitCheck::enforce : device::RigFitCheck::skip);
  if (!dev->health().connected) log::warning("%s", device::silent_device_hint(o.device, dev->health()).c_str());
  auto* arm = dynamic_cast<device::HapticArm*>(dev.get());
  const std::size_t max_ticks = static_cast<std::size_t>(o.duration_s * 1000) + 16;
  std::vector<double> rtt_us;
  rtt_us.reserve(max_ticks);
  std::uint64_t sent_ns[256] = {};
  std::uint64_t states = 0, estop_seen_ns = 0, watchdog_seen_ns = 0, first_state_ns = 0, last_state_ns = 0;
  std::uint16_t last_echo = 0xFFFF;
  std::uint32_t faults_seen = 0, status_seen = 0, max_transport_errors = 0;
  device::DeviceState state, last_state;
  const std::uint64_t t0 = device::monotonic_ns();
  std::uint64_t wake = t0, silence_start_ns = 0;
  double sum_pos[3] = {0, 0, 0};
  // states are counted by sequence progress: poll() keeps only the newest of a tick's states
  const std::uint32_t modulus = arm ? arm->link().sequence_modulus() : 65536u;
  std::uint64_t progressed = 0;
  double longest_gap_ms = 0, max_abs_position_m = 0;
  std::uint64_t late_half = 0;
  while (true) {
    wake += 1'000'000;
    timespec ts{static_cast<time_t>(wake / 1'000'000'000ull), static_cast<long>(wake % 1'000'000'000ull)};
    clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr);
    const std::uint64_t now = device::monotonic_ns();
    if (now > wake + 1'000'000) wake = now;
    const double t = (now - t0) * 1e-9;
    if (t >= o.duration_s) break;
    dev->poll(state);  // drains everything pending, keeps the newest state
    if (state.host_receive_ns && state.host_receive_ns != last_state.host_receive_ns) {
      ++states;
      if (first_state_ns) {
        progressed += (state.sequence - last_state.sequence + modulus) % modulus;
        longest_gap_ms = std::max(longest_gap_ms, (state.host_receive_ns - last_state.host_receive_ns) * 1e-6);
      }
      if (!first_state_ns) first_state_ns = state.host_receive_ns;
      last_state_ns = state.host_receive_ns;
      faults_seen |= state.fault;
      status_seen |= state.status;
      // only a trip after the deliberate silence counts (a starved host may trip it earlier)
      if ((state.status & HF_STATUS_WATCHDOG_TRIPPED) && !watchdog_seen_ns && silence_start_ns)
        watchdog_seen_ns = state.host_receive_ns;
      if ((state.status & HF_STATUS_ESTOP_LATCHED) && !estop_seen_ns) estop_seen_ns = state.host_receive_ns;
      std::uint16_t echo = state.command_echo & 0xFF;
      if (echo != last_echo && sent_ns[echo] && state.host_receive_ns > sent_ns[echo]) {
        rtt_us.push_back((state.host_receive_ns - sent_ns[echo]) * 1e-3);
      }
      last_echo = echo;
      for (int i = 0; i < 3; ++i) max_abs_position_m = std::max(max_abs_position_m, std::fabs(state.position_m[i]));
      if (t > o.duration_s / 2) {
        ++late_half;
        for (int i = 0; i < 3; ++i) sum_pos[i] += state.position_m[i];
      }
      last_state = state;
    }
    max_transport_errors |= dev->health().transport_errors;
    const bool silent = o.silent_after_s >= 0 && t >= o.silent_after_s;
    if (silent) {
      if (!silence_start_ns) silence_start_ns = now;
      continue;
    }
    device::DeviceCommand c;
    std::memcpy(c.force_n, o.force, sizeof o.force);
    std::memcpy(c.torque_nm, o.torque, sizeof o.torque);
    c.enable = o.enable;
    if (o.clear_faults_at_s >= 0 && t >= o.clear_faults_at_s) { c.enable = false; c.clear_faults = true; }
    c.estop = o.estop_at_s >= 0 && t >= o.estop_at_s;
    dev->send(c);
    sent_ns[dev->health().last_command_sequence & 0xFF] = device::monotonic_ns();
  }
  device::DeviceHealth h = dev->health();
  const double span_s = (last_state_ns - first_state_ns) * 1e-9;
  namespace config = hapfluid::config;
  config::Json report;
  report["build_id"] = config::build_id();
  report["device"] = dev->name();
  report["duration_s"] = o.duration_s;
  report["states"] = states;
  report["state_rate_hz"] = span_s > 0 ? progressed / span_s : 0.0;
  report["longest_state_gap_ms"] = longest_gap_ms;
  report["last_state_age_ms"] = last_state_ns ? (device::monotonic_ns() - last_state_ns) * 1e-6 : -1.0;
  report["rtt_samples"] = rtt_us.size();
  report["rtt_p50_us"] = percentile(rtt_us, 50);
  report["rtt_p99_us"] = percentile(rtt_us, 99);
  report["rtt_max_us"] = percentile(rtt_us, 100);
  report["frames_ok"] = h.frames_ok;
  report["frames_bad"] = h.frames_bad;
  report["sequence_gaps"] = h.sequence_gaps;
  report["commands_sent"] = h.commands_sent;
  report["send_errors"] = h.send_errors;
  report["transport_errors"] = max_transport_errors;
  report["transport_errors_now"] = h.transport_errors;
  report["connected"] = h.connected;
  report["faults_seen"] = faults_seen;
  report["status_seen"] = status_seen;
  report["final_faults"] = last_state.fault;
  report["final_status"] = last_state.status;
  report["mean_position_late_half_m"] = {late_half ? sum_pos[0] / late_half : 0, late_half ? sum_pos[1] / late_half : 0,
                                         late_half ? sum_pos[2] / late_half : 0};
  report["max_abs_position_m"] = max_abs_position_m;
  report["watchdog_seen_after_silence_ms"] =
      watchdog_seen_ns && silence_start_ns ? (static_cast<double>(watchdog_seen_ns) - silence_start_ns) * 1e-6 : -1.0;
  report["estop_seen_after_request_ms"] =
      estop_seen_ns && o.estop_at_s >= 0 ? (estop_seen_ns - t0) * 1e-6 - o.estop_at_s * 1e3 : -1.0;
  report["info"] = nullptr;
  if (arm && arm->has_info())
    report["info"] = {{"vendor_id", arm->info().vendor_id}, {"product_id", arm->info().product_id},
                      {"watchdog_ms", arm->info().watchdog_ms}, {"max_force_n", arm->info().max_force_n}};
  std::fputs((config::json_line(report) + "\n").c_str(), stdout);
  if (!o.out.empty()) config::write_json_atomically(o.out, report);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    Options o;
    if (const int code = parse(argc, argv, o); code >= 0) return code;
    return run(o);
  } catch (const std::exception& e) {
    log::error("%s", e.what());
    return 2;
  }
}
