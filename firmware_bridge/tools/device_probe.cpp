// haptic-device-probe: drives one device through the same driver the 1 kHz loop uses (open_device
// + Device::poll/send) at 1 kHz and reports what it saw: state rate, round-trip latency
// host -> device -> host (command sent until a state echoes its sequence), sequence gaps, bad
// frames, transport errors, faults, and how long the device took to trip its watchdog after the
// host fell silent. For end-to-end tests, hardware-in-the-loop runs and latency benchmarks.
#include <time.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

#include "hapfluid/config/rig.hpp"
#include "hapfluid/device/haptic_arm.hpp"
#include "hapfluid/device/open_device.hpp"

using namespace hapfluid;

namespace {

const char* kUsage = R"(usage: haptic-device-probe [options]
  --rig FILE --device NAME | --transport loopback|socketcan|hid|usb_bulk --address A
  [--framing can|canfd|hid|bulk] [--node N] [--kind haptic_arm|spacemouse]
  --duration S            run time (default 2)
  --force FX,FY,FZ        force to command, N (default 0,0,0)
  --torque TX,TY,TZ       torque to command, N.m (default 0,0,0)
  --enable                set the enable flag (motors on)
  --silent-after S        stop sending commands after S seconds (watchdog test), keep reading
  --clear-faults-at S     send disabled commands with clear_faults from S on
  --estop-at S            request an emergency stop at S
  --out FILE.json         write the report there too (always printed on stdout)
)";

struct Options {
  config::RigDevice device;
  bool from_rig = false;  // the device's INFO is checked against a rig only when one was given
  double duration_s = 2, silent_after_s = -1, clear_faults_at_s = -1, estop_at_s = -1;
  double force[3] = {0, 0, 0}, torque[3] = {0, 0, 0};
  bool enable = false;
  std::string out;
};

void triple(const std::string& text, double v[3], const std::string& what) {
  if (std::sscanf(text.c_str(), "%lf,%lf,%lf", &v[0], &v[1], &v[2]) != 3)
    throw std::invalid_argument(what + " " + text + ": expected three comma-separated numbers");
}

Options parse(int argc, char** argv) {
  Options o;
  o.device.name = "probe";
  std::string rig_file, rig_device;
  for (int i = 1; i < argc; ++i) {
    std::string a = argv[i];
    if (a == "--help" || a == "-h") { std::fputs(kUsage, stdout); std::exit(0); }
    if (a == "--enable") { o.enable = true; continue; }
    if (i + 1 >= argc) throw std::invalid_argument(a + " needs a value (see --help)");
    std::string v = argv[++i];
    if (a == "--rig") rig_file = v;
    else if (a == "--device") rig_device = v;
    else if (a == "--transport") {
      if (v == "loopback") o.device.transport.kind = config::TransportKind::loopback;
      else if (v == "socketcan") o.device.transport.kind = config::TransportKind::socketcan;
      else if (v == "hid") o.device.transport.kind = config::TransportKind::hid;
      else if (v == "usb_bulk") o.device.transport.kind = config::TransportKind::usb_bulk;
      else throw std::invalid_argument("--transport " + v + ": loopback, socketcan, hid or usb_bulk");
    } else if (a == "--address") o.device.transport.address = v;
    else if (a == "--framing") { o.device.transport.framing = v; o.device.transport.can_fd = v == "canfd"; }
    else if (a == "--node") o.device.transport.can_node_id = static_cast<std::uint32_t>(std::atoi(v.c_str()));
    else if (a == "--kind") o.device.kind = v == "spacemouse" ? config::DeviceKind::spacemouse : config::DeviceKind::haptic_arm;
    else if (a == "--duration") o.duration_s = std::atof(v.c_str());
    else if (a == "--force") triple(v, o.force, a);
    else if (a == "--torque") triple(v, o.torque, a);
    else if (a == "--silent-after") o.silent_after_s = std::atof(v.c_str());
    else if (a == "--clear-faults-at") o.clear_faults_at_s = std::atof(v.c_str());
    else if (a == "--estop-at") o.estop_at_s = std::atof(v.c_str());
    else if (a == "--out") o.out = v;
    else throw std::invalid_argument("unknown option " + a + " (see --help)");
  }
  if (!rig_file.empty()) {
    config::Rig rig = config::load_rig(rig_file);
    const config::RigDevice* d = rig.find_device(rig_device);
    if (!d) throw std::invalid_argument(rig_file + ": no device named '" + rig_device + "'");
    o.device = *d;
    o.from_rig = true;
  }
  if (o.device.transport.address.empty()) throw std::invalid_argument("--address (or --rig/--device) is required");
  return o;
}

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return -1;
  std::sort(v.begin(), v.end());
  return v[static_cast<std::size_t>(std::min<double>(v.size() - 1, std::floor(p / 100.0 * v.size())))];
}

int run(const Options& o) {
  auto dev = device::open_device(o.device, o.from_rig ? device::RigFitCheck::enforce : device::RigFitCheck::skip);
  if (!dev->health().connected) std::fprintf(stderr, "haptic-device-probe: %s\n", device::silent_device_hint(o.device, dev->health()).c_str());
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
  char text[2048];
  std::snprintf(
      text, sizeof text,
      "{\"device\": \"%s\", \"duration_s\": %.3f, \"states\": %llu, \"state_rate_hz\": %.1f, "
      "\"longest_state_gap_ms\": %.3f, \"last_state_age_ms\": %.3f, "
      "\"rtt_samples\": %zu, \"rtt_p50_us\": %.1f, \"rtt_p99_us\": %.1f, \"rtt_max_us\": %.1f, "
      "\"frames_ok\": %llu, \"frames_bad\": %llu, \"sequence_gaps\": %llu, \"commands_sent\": %llu, "
      "\"send_errors\": %llu, \"transport_errors\": %u, \"transport_errors_now\": %u, \"connected\": %s, "
      "\"faults_seen\": %u, \"status_seen\": %u, \"final_faults\": %u, \"final_status\": %u, "
      "\"mean_position_late_half_m\": [%.6f, %.6f, %.6f], \"max_abs_position_m\": %.6f, "
      "\"watchdog_seen_after_silence_ms\": %.3f, \"estop_seen_after_request_ms\": %.3f, "
      "\"info\": %s}\n",
      dev->name(), o.duration_s, static_cast<unsigned long long>(states), span_s > 0 ? progressed / span_s : 0.0, longest_gap_ms,
      last_state_ns ? (device::monotonic_ns() - last_state_ns) * 1e-6 : -1.0,
      rtt_us.size(), percentile(rtt_us, 50), percentile(rtt_us, 99), percentile(rtt_us, 100),
      static_cast<unsigned long long>(h.frames_ok), static_cast<unsigned long long>(h.frames_bad),
      static_cast<unsigned long long>(h.sequence_gaps), static_cast<unsigned long long>(h.commands_sent),
      static_cast<unsigned long long>(h.send_errors), max_transport_errors, h.transport_errors,
      h.connected ? "true" : "false", faults_seen, status_seen, last_state.fault, last_state.status,
      late_half ? sum_pos[0] / late_half : 0, late_half ? sum_pos[1] / late_half : 0,
      late_half ? sum_pos[2] / late_half : 0, max_abs_position_m,
      watchdog_seen_ns && silence_start_ns ? (static_cast<double>(watchdog_seen_ns) - silence_start_ns) * 1e-6 : -1.0,
      estop_seen_ns && o.estop_at_s >= 0 ? (estop_seen_ns - t0) * 1e-6 - o.estop_at_s * 1e3 : -1.0,
      arm && arm->has_info()
          ? ("{\"vendor_id\": " + std::to_string(arm->info().vendor_id) + ", \"product_id\": " +
             std::to_string(arm->info().product_id) + ", \"watchdog_ms\": " + std::to_string(arm->info().watchdog_ms) +
             ", \"max_force_n\": " + std::to_string(arm->info().max_force_n) + "}").c_str()
          : "null");
  std::fputs(text, stdout);
  if (!o.out.empty()) {
    FILE* f = std::fopen(o.out.c_str(), "w");
    if (!f) throw std::runtime_error("cannot write " + o.out);
    std::fputs(text, f);
    std::fclose(f);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(parse(argc, argv));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "haptic-device-probe: %s\n", e.what());
    return 2;
  }
}
