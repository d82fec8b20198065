// haptic-fake-device: the firmware of a protocol-v1 haptic arm (or a SpaceMouse), emulated at
// 1 kHz on a real transport, with a scripted or interactive hand, its own command watchdog,
// fault injection and a CSV log of what it received and what the hand felt. See --help.
#include <linux/can.h>
#include <linux/can/error.h>
#include <signal.h>
#include <time.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "fake_firmware.hpp"
#include "functionfs_transport.hpp"
#include "hand.hpp"
#include "hidg_transport.hpp"
#include "hapfluid/config/command_line.hpp"
#include "hapfluid/config/json_output.hpp"
#include "hapfluid/config/log.hpp"
#include "hapfluid/config/rig.hpp"
#include "hapfluid/device/hid_descriptors.hpp"
#include "hapfluid/device/open_device.hpp"
#include "hapfluid/device/usb_transports.hpp"
#include "uhid_transport.hpp"

using namespace hapfluid;

namespace {

volatile sig_atomic_t g_stop = 0;
volatile sig_atomic_t g_inject = 0;
void on_signal(int) { g_stop = 1; }
void on_inject_signal(int) { g_inject = 1; }

struct Options {
  config::RigDevice device;
  std::string kind = "haptic_arm";
  std::string motion = "hold";
  double duration_s = 0, rate_hz = 1000;
  std::string log_path, summary_path;
  double drop_probability = 0;
  int corrupt_every = 0;
  double delay_ms = 0;
  double out_interval_ms = 0;
  double silent_after_s = -1, stop_answering_after_s = -1, bus_off_at_s = -1, bus_off_ms = 200;
  unsigned seed = 1;
  bool inject_on_signal = false;
};

bool is_gadget_hid(const Options& o) { return o.device.transport.address.rfind("/dev/hidg", 0) == 0; }

void print_hid_descriptor(const std::string& kind) {
  const bool mouse = kind == "spacemouse";
  const std::uint8_t* d = mouse ? device::kSpaceMouseHidDescriptor : device::kHapfluidHidDescriptor;
  const std::size_t n = mouse ? sizeof device::kSpaceMouseHidDescriptor : sizeof device::kHapfluidHidDescriptor;
  for (std::size_t i = 0; i < n; ++i) std::printf("%02x", d[i]);
  std::printf("\n");
}

// Parses the command line into `o` (CLI11, the tools' shared convention). Returns -1 when the
// device should run, else the exit code (--help, --version, --hid-report-descriptor: 0; a usage
// error: 2). Checks that need the rig file or several options together throw invalid_argument.
int parse(int argc, char** argv, Options& o) {
  o.device.name = "fake";
  o.device.transport.kind = config::TransportKind::loopback;
  std::string rig_file, rig_device, transport = "loopback", framing, hid_descriptor;
  int node = 1;
  const std::vector<std::string> kinds{"haptic_arm", "spacemouse"};
  CLI::App app{"A fake haptic device speaking the real wire protocol (loopback socket, SocketCAN, hidraw through "
               "uhid or a USB gadget, or USB bulk through FunctionFS), with scripted hand motion and fault "
               "injection.",
               "haptic-fake-device"};
  config::apply_convention(app);
  app.add_option("--rig", rig_file, "take transport, node, watchdog and limits from a rig file (with --device)");
  app.add_option("--device", rig_device, "the rig device NAME");
  app.add_option("--transport", transport, "the link")
      ->check(CLI::IsMember({"loopback", "socketcan", "hid", "usb_bulk"}))
      ->capture_default_str();
  app.add_option("--address", o.device.transport.address,
                 "loopback socket path | CAN interface | hid: VID:PID presented through /dev/uhid (default "
                 "1209:4846, SpaceMouse 256f:c635), or the /dev/hidgN node of a USB gadget's hid function | "
                 "usb_bulk: the directory where the gadget's FunctionFS instance is mounted");
  app.add_option("--framing", framing, "loopback wire format (socketcan: can or canfd)")
      ->check(CLI::IsMember({"can", "canfd", "hid", "bulk"}));
  app.add_option("--node", node, "CAN node id")->check(CLI::Range(1, 15))->capture_default_str();
  app.add_option("--kind", o.kind, "the device")->check(CLI::IsMember(kinds))->capture_default_str();
  app.add_option("--motion", o.motion, "hold|stir|pour|spin|tilt|interactive|scene:FILE:DEVICE")->capture_default_str();
  app.add_option("--duration", o.duration_s, "run time in seconds; 0: until SIGINT/SIGTERM")
      ->check(config::non_negative_number("seconds"))
      ->capture_default_str();
  app.add_option("--rate-hz", o.rate_hz, "state rate")->check(config::number_in(1, 1e6))->capture_default_str();
  app.add_option("--watchdog-ms", o.device.watchdogs.device_watchdog_ms, "command watchdog (default 20, or the rig's)")
      ->check(config::number_in(1, 1e6));
  app.add_option("--max-force-n", o.device.limits.max_force_n, "motor force limit, N")
      ->check(config::non_negative_number("N"))
      ->capture_default_str();
  app.add_option("--max-torque-nm", o.device.limits.max_torque_nm, "motor torque limit, N.m")
      ->check(config::non_negative_number("N.m"))
      ->capture_default_str();
  app.add_option("--log", o.log_path,
                 "per-tick CSV: command received, force applied, hand force, pose, and on CLOCK_MONOTONIC the "
                 "tick, the STATE it sent, the commands it took");
  app.add_option("--summary", o.summary_path, "statistics at exit as JSON (also printed on stdout)");
  const std::string faults = "Fault injection";
  app.add_option("--drop-probability", o.drop_probability, "drop each outgoing STATE with this probability")
      ->check(config::number_in(0, 1))
      ->group(faults);
  app.add_option("--corrupt-every", o.corrupt_every, "corrupt the CRC of every Nth outgoing STATE")
      ->check(CLI::NonNegativeNumber)
      ->group(faults);
  app.add_option("--delay-ms", o.delay_ms, "delay every outgoing message by MS")
      ->check(config::non_negative_number("ms"))
      ->group(faults);
  app.add_option("--silent-after", o.silent_after_s, "send nothing after S seconds (still receives)")
      ->check(config::non_negative_number("seconds"))
      ->group(faults);
  app.add_option("--stop-answering-after", o.stop_answering_after_s,
                 "stop reading commands after S seconds (still sends state)")
      ->check(config::non_negative_number("seconds"))
      ->group(faults);
  app.add_option("--bus-off-at", o.bus_off_at_s, "CAN: report bus-off at S seconds, silent for --bus-off-ms, restart")
      ->check(config::non_negative_number("seconds"))
      ->group(faults);
  app.add_option("--bus-off-ms", o.bus_off_ms, "how long a bus-off lasts")
      ->check(config::non_negative_number("ms"))
      ->capture_default_str()
      ->group(faults);
  app.add_option("--seed", o.seed, "random seed for --drop-probability")->capture_default_str()->group(faults);
  app.add_flag("--inject-on-signal", o.inject_on_signal,
               "the faults above begin at SIGUSR1 instead of at the start (their times count from it); the tick it "
               "began is printed on stderr")
      ->group(faults);
  app.add_option("--out-interval-ms", o.out_interval_ms,
                 "a slow USB device (gadget hid or usb_bulk): take host->device transfers only every MS, so the "
                 "host's writes wait for the device")
      ->check(config::non_negative_number("ms"))
      ->group(faults);
  app.add_option("--hid-report-descriptor", hid_descriptor,
                 "print the HID report descriptor of this kind as hex, for a gadget's configfs report_desc, and exit")
      ->check(CLI::IsMember(kinds));
  if (const int code = config::parse_command_line(app, argc, argv); code >= 0) return code;
  if (!hid_descriptor.empty()) return print_hid_descriptor(hid_descriptor), 0;

  if (transport == "socketcan") o.device.transport.kind = config::TransportKind::socketcan;
  else if (transport == "hid") o.device.transport.kind = config::TransportKind::hid;
  else if (transport == "usb_bulk") o.device.transport.kind = config::TransportKind::usb_bulk;
  if (!framing.empty()) o.device.transport.framing = framing, o.device.transport.can_fd = framing == "canfd";
  o.device.transport.can_node_id = static_cast<std::uint32_t>(node);
  if (!rig_file.empty()) {
    config::Rig rig = config::load_rig(rig_file);
    const config::RigDevice* d = rig.find_device(rig_device);
    if (!d) throw std::invalid_argument(rig_file + ": no device named '" + rig_device + "' (--device)");
    const double watchdog = o.device.watchdogs.device_watchdog_ms;
    o.device = *d;
    if (app.count("--watchdog-ms") > 0) o.device.watchdogs.device_watchdog_ms = watchdog;
    o.kind = d->kind == config::DeviceKind::spacemouse ? "spacemouse" : "haptic_arm";
  }
  if (o.device.transport.kind == config::TransportKind::hid && o.device.transport.address.empty())
    o.device.transport.address = o.kind == "spacemouse" ? "256f:c635" : "1209:4846";
  if (o.device.transport.address.empty()) throw std::invalid_argument("--address (or --rig/--device) is required");
  if (o.device.transport.kind == config::TransportKind::socketcan && o.device.transport.framing != "can" &&
      o.device.transport.framing != "canfd")
    throw std::invalid_argument("--framing " + o.device.transport.framing + ": SocketCAN carries can or canfd");
  const bool slow_capable = o.device.transport.kind == config::TransportKind::usb_bulk ||
                            (o.device.transport.kind == config::TransportKind::hid && is_gadget_hid(o));
  if (o.out_interval_ms > 0 && !slow_capable)
    throw std::invalid_argument("--out-interval-ms needs a USB link whose transfers the device takes: "
                                "--transport usb_bulk, or hid with --address /dev/hidgN (uhid only queues them)");
  return -1;
}

std::uint64_t now_ns() {
  timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::uint64_t>(ts.tv_sec) * 1'000'000'000ull + static_cast<std::uint64_t>(ts.tv_nsec);
}

// Outgoing messages held back by --delay-ms.
struct DelayQueue {
  static constexpr int kSize = 4096;
  hf_message messages[kSize];
  double due_s[kSize];
  int head = 0, tail = 0;
  bool push(const hf_message& m, double due) {
    if (head - tail >= kSize) return false;
    messages[head % kSize] = m;
    due_s[head % kSize] = due;
    ++head;
    return true;
  }
};

void send_spacemouse_reports(device::Transport& transport, const config::PoseTwist& hand) {
  // 3Dconnexion rate reports: deflection proportional to the hand's velocity (0.1 m/s and
  // 1 rad/s at full deflection, +-350 counts), report 1 translation, report 2 rotation.
  auto counts = [](double v, double full) {
    double c = std::round(v / full * 350.0);
    return static_cast<std::int16_t>(c > 350 ? 350 : c < -350 ? -350 : c);
  };
  const double t[3] = {hand.linear_velocity_m_s.x, hand.linear_velocity_m_s.y, hand.linear_velocity_m_s.z};
  const double r[3] = {hand.angular_velocity_rad_s.x, hand.angular_velocity_rad_s.y, hand.angular_velocity_rad_s.z};
  for (int id = 1; id <= 2; ++id) {
    device::WireFrame f;
    f.length = 7;
    f.data[0] = static_cast<std::uint8_t>(id);
    for (int i = 0; i < 3; ++i) {
      std::int16_t c = counts(id == 1 ? t[i] : r[i], id == 1 ? 0.1 : 1.0);
      f.data[1 + 2 * i] = static_cast<std::uint8_t>(c);
      f.data[2 + 2 * i] = static_cast<std::uint8_t>(static_cast<std::uint16_t>(c) >> 8);
    }
    transport.send(f);
  }
}

// The device end of the rig's transport. USB is presented for real where the kernel can: HID
// through uhid (the host's hidapi sees a hidraw node) or a gadget's hid function (the host sees a
// USB HID device), bulk through a FunctionFS gadget.
std::unique_ptr<device::MessageLink> open_device_side(const Options& o, fake::UhidTransport** uhid) {
  const config::Transport& t = o.device.transport;
  const auto node = static_cast<std::uint8_t>(t.can_node_id);
  if (t.kind == config::TransportKind::hid && is_gadget_hid(o))
    return std::make_unique<device::MessageLink>(std::make_unique<fake::HidgTransport>(t.address, o.out_interval_ms),
                                                 device::Framing::hid, node, device::Side::device);
  if (t.kind == config::TransportKind::hid) {
    std::uint16_t vendor = 0, product = 0;
    device::parse_vid_pid(t.address, vendor, product);
    const bool mouse = o.kind == "spacemouse";
    auto transport = std::make_unique<fake::UhidTransport>(
        mouse ? device::kSpaceMouseHidDescriptor : device::kHapfluidHidDescriptor,
        mouse ? sizeof device::kSpaceMouseHidDescriptor : sizeof device::kHapfluidHidDescriptor, vendor, product,
        mouse ? "hapfluid fake SpaceMouse" : "hapfluid fake haptic arm");
    *uhid = transport.get();
    return std::make_unique<device::MessageLink>(std::move(transport), device::Framing::hid, node, device::Side::device);
  }
  if (t.kind == config::TransportKind::usb_bulk)
    return std::make_unique<device::MessageLink>(std::make_unique<fake::FunctionFsTransport>(t.address, o.out_interval_ms),
                                                 device::Framing::bulk, node, device::Side::device);
  return device::open_link(t, device::Side::device);
}

int run(const Options& o) {
  const config::RigDevice& d = o.device;
  fake::UhidTransport* uhid = nullptr;
  auto link = open_device_side(o, &uhid);
  fake::DeviceModel model;
  model.watchdog_ms = static_cast<int>(std::lround(d.watchdogs.device_watchdog_ms));
  model.max_force_n = d.limits.max_force_n;
  model.max_torque_nm = d.limits.max_torque_nm;
  // Twice the host's: a host within its own limit never meets the device's, even when two of
  // its commands land in one device tick; a sender bypassing the host does.
  model.max_force_rate_n_per_s = 2 * d.limits.max_force_rate_n_per_s;
  model.max_torque_rate_nm_per_s = 2 * d.limits.max_torque_rate_nm_per_s;
  model.handle_damping_n_s_per_m = d.limits.device_damping_n_s_per_m;

  config::Pose start;
  config::ScriptedMotion motion;
  bool interactive = o.motion == "interactive";
  if (o.motion.rfind("scene:", 0) == 0) {
    std::string rest = o.motion.substr(6);
    auto colon = rest.rfind(':');
    if (colon == std::string::npos) throw std::invalid_argument("--motion scene:FILE:DEVICE needs the device name");
    motion = fake::scene_motion(rest.substr(0, colon), rest.substr(colon + 1));
  } else {
    motion = fake::builtin_motion(interactive ? "hold" : o.motion, start);
  }
  fake::Hand hand(motion, interactive);
  fake::FakeFirmware firmware(model, motion.start, link->sequence_modulus());
  const bool spacemouse = o.kind == "spacemouse";
  if (uhid && !spacemouse) {  // feature report 3: the INFO packet, for tools (protocol.md 4.4)
    hf_message info;
    std::memset(&info, 0, sizeof info);
    info.type = HF_MSG_INFO;
    info.body.info = firmware.info();
    std::uint8_t report[device::kHidReportBytes] = {3};
    if (hf_encode_packet(&info, report + 1, sizeof report - 1) > 0) uhid->set_feature_report(3, report, sizeof report);
  }

  FILE* log = nullptr;
  if (!o.log_path.empty()) {
    log = std::fopen(o.log_path.c_str(), "w");
    if (!log) throw std::runtime_error("cannot write the log " + o.log_path + ": " + std::strerror(errno));
    static char buffer[1 << 16];
    std::setvbuf(log, buffer, _IOFBF, sizeof buffer);
    // t_s is the device's own timeline; tick_ns is the same instant on CLOCK_MONOTONIC (the clock
    // of every *_ns stamp on the machine), rx_ns when this tick took its commands off the link, and
    // state_seq the sequence of the STATE this tick sampled and sent (-1: none left the device).
    std::fputs("t_s,cmd_received,cmd_seq,cmd_fx,cmd_fy,cmd_fz,cmd_tx,cmd_ty,cmd_tz,cmd_flags,"
               "applied_fx,applied_fy,applied_fz,applied_tx,applied_ty,applied_tz,hand_fx,hand_fy,hand_fz,"
               "px,py,pz,qw,qx,qy,qz,status,faults,tick_ns,rx_ns,state_seq\n", log);
  }

  std::printf("haptic-fake-device: ready on %s (framing %s, node %u, watchdog %d ms)\n",
              link->transport().describe().c_str(), device::to_string(link->framing()), d.transport.can_node_id,
              model.watchdog_ms);
  std::fflush(stdout);

  std::mt19937 rng(o.seed);
  std::uniform_real_distribution<double> uniform(0, 1);
  static DelayQueue delayed;
  const std::uint64_t period_ns = static_cast<std::uint64_t>(1e9 / o.rate_hz);
  const double dt = period_ns * 1e-9;
  const std::uint64_t t0 = now_ns();
  std::uint64_t wake = t0;
  std::uint64_t ticks = 0, states_sent = 0, states_dropped = 0, states_corrupted = 0, late_ticks = 0;
  std::uint16_t state_seq = 0, fault_seq = 0, heartbeat_seq = 0, info_seq = 0;
  bool bus_off_reported = false, bus_restarted = false;
  double next_heartbeat_s = 0, next_fault_s = 0;
  bool stopped_answering_logged = false;
  std::uint64_t frames_bad_seen = 0;  // invalid host frames already handed to the firmware
  // The tick from which the injected faults apply (their times count from it): the start, or the
  // tick that saw SIGUSR1, so a test can inject at an instant it chose (the stack engaged). Counted
  // in whole ns like t, so "S after the signal" falls on the tick "S after the start" would.
  std::uint64_t inject_from_ns = t0;
  bool injecting = !o.inject_on_signal;
  double since = 0;  // device time since inject_from_ns
  auto bus_off_now = [&] {
    return injecting && o.bus_off_at_s >= 0 && since >= o.bus_off_at_s && since < o.bus_off_at_s + o.bus_off_ms * 1e-3;
  };

  // false: the message never leaves the device (silent, bus-off, delay queue full, link refused).
  auto transmit = [&](hf_message m, double t) {
    if (injecting && o.silent_after_s >= 0 && since >= o.silent_after_s) return false;
    if (bus_off_now()) return false;
    if (injecting && o.delay_ms > 0) return delayed.push(m, t + o.delay_ms * 1e-3);
    return link->send(m);
  };

  // A real device's MCU never misses a tick. The emulator shares a CPU with everything else, so
  // when it wakes late it runs the missed ticks back to back on the device timeline (states keep
  // their 1 ms spacing in device time); beyond 50 ms behind it re-phases and counts the loss.
  const std::uint64_t catch_up_limit_ns = 50'000'000;
  while (!g_stop) {
    wake += period_ns;
    timespec ts{static_cast<time_t>(wake / 1'000'000'000ull), static_cast<long>(wake % 1'000'000'000ull)};
    // (a signal cuts the sleep short: SIGUSR1 must not run a tick early)
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR && !g_stop) {
    }
    const std::uint64_t now = now_ns();
    if (now > wake + catch_up_limit_ns) {
      late_ticks += (now - wake) / period_ns;
      wake = now;
    }
    const double t = (wake - t0) * 1e-9;
    if (o.duration_s > 0 && t >= o.duration_s) break;
    ++ticks;
    long state_seq_sent = -1;
    if (!injecting && g_inject) {
      injecting = true;
      inject_from_ns = wake;
      log::notice("fault injection begins at t=%.3f s, tick_ns %llu (SIGUSR1)", t,
                  static_cast<unsigned long long>(wake));
    }
    since = (wake - inject_from_ns) * 1e-9;

    // 1. receive (unless the firmware hangs or the controller is bus-off)
    firmware.begin_tick();
    const bool in_bus_off = bus_off_now();
    const bool answering = !injecting || o.stop_answering_after_s < 0 || since < o.stop_answering_after_s;
    if (!answering && !stopped_answering_logged) {
      log::notice("fault injection: stopped answering at t=%.3f s", t);
      stopped_answering_logged = true;
    }
    bool info_requested = false;
    if (answering && !in_bus_off) {
      hf_message m;
      int budget = device::kDrainUnitBudget;  // a flood from the bus cannot stall the firmware's tick
      while (link->receive(m, budget) == device::Io::ok) info_requested = firmware.receive(m, t) || info_requested;
      firmware.reject_frames(static_cast<std::uint32_t>(link->frames_bad() - frames_bad_seen), t);
      frames_bad_seen = link->frames_bad();
    }
    const std::uint64_t received_ns = now_ns();  // after the drain: no command counts as taken before it left the host
    // 2. bus-off injection: error frames exactly as a CAN controller reports them
    if (in_bus_off && !bus_off_reported && link->framing() != device::Framing::hid &&
        link->framing() != device::Framing::bulk) {
      device::WireFrame e;
      e.can_id = CAN_ERR_FLAG | CAN_ERR_BUSOFF;
      e.length = 8;
      link->transport().send(e);
      bus_off_reported = true;
      log::notice("fault injection: bus-off at t=%.3f s", t);
    }
    if (bus_off_reported && !in_bus_off && !bus_restarted) {
      device::WireFrame e;
      e.can_id = CAN_ERR_FLAG | CAN_ERR_RESTARTED;
      e.length = 8;
      link->transport().send(e);
      bus_restarted = true;
    }
    // 3. physics and watchdog
    const config::PoseTwist target = hand.target(t);
    firmware.step(t, dt, target);
    if (firmware.watchdog_trip_s() == t)
      log::warning("watchdog: no valid command for %.1f ms, motors off at t=%.3f s",
                   (t - firmware.watchdog_trip_last_command_s()) * 1e3, t);

    // 4. transmit
    if (spacemouse) {
      if (!(injecting && o.silent_after_s >= 0 && since >= o.silent_after_s))
        send_spacemouse_reports(link->transport(), target);
    } else {
      hf_message m;
      std::memset(&m, 0, sizeof m);
      if (info_requested) {
        m.type = HF_MSG_INFO;
        m.seq = info_seq++;
        m.body.info = firmware.info();
        transmit(m, t);
      }
      if (firmware.take_new_fault() || (firmware.faults() && t >= next_fault_s)) {
        m.type = HF_MSG_FAULT;
        m.seq = fault_seq++;
        m.body.fault = firmware.fault_report(t);
        transmit(m, t);
        next_fault_s = t + 0.1;
      }
      if (t >= next_heartbeat_s) {
        m.type = HF_MSG_DEVICE_HEARTBEAT;
        m.seq = heartbeat_seq++;
        m.body.heartbeat.uptime_ms = static_cast<std::uint32_t>(t * 1e3);
        m.body.heartbeat.status = firmware.status();
        transmit(m, t);
        next_heartbeat_s = t + 0.1;
      }
      m.type = HF_MSG_STATE;
      m.seq = state_seq++;
      m.body.state = firmware.state(static_cast<std::uint32_t>(static_cast<std::uint64_t>(t * 1e6)));
      if (injecting && o.drop_probability > 0 && uniform(rng) < o.drop_probability) {
        ++states_dropped;
      } else {
        if (injecting && o.corrupt_every > 0 && m.seq % o.corrupt_every == 0) {
          link->corrupt_next(1);
          ++states_corrupted;
        }
        if (transmit(m, t)) state_seq_sent = m.seq;
        ++states_sent;
      }
      while (delayed.tail < delayed.head && delayed.due_s[delayed.tail % DelayQueue::kSize] <= t) {
        link->send(delayed.messages[delayed.tail % DelayQueue::kSize]);
        ++delayed.tail;
      }
    }
    // 5. log
    if (log) {
      const fake::TickRecord& r = firmware.record();
      hf_state s = firmware.state(0);
      std::fprintf(log, "%.6f,%d,%u,%.4f,%.4f,%.4f,%.5f,%.5f,%.5f,%u,%.4f,%.4f,%.4f,%.5f,%.5f,%.5f,%.4f,%.4f,%.4f,"
                        "%.6f,%.6f,%.6f,%.6f,%.6f,%.6f,%.6f,%u,%u,%llu,%llu,%ld\n",
                   t, r.command_received ? 1 : 0, r.command_seq, r.command.force_n[0], r.command.force_n[1],
                   r.command.force_n[2], r.command.torque_nm[0], r.command.torque_nm[1], r.command.torque_nm[2],
                   r.command.flags, r.applied_force_n[0], r.applied_force_n[1], r.applied_force_n[2],
                   r.applied_torque_nm[0], r.applied_torque_nm[1], r.applied_torque_nm[2], r.hand_force_n[0],
                   r.hand_force_n[1], r.hand_force_n[2], s.position_m[0], s.position_m[1], s.position_m[2],
                   s.orientation[0], s.orientation[1], s.orientation[2], s.orientation[3], r.status, r.faults,
                   static_cast<unsigned long long>(wake), static_cast<unsigned long long>(received_ns), state_seq_sent);
    }
  }
  if (log) std::fclose(log);

  const double reaction_ms = firmware.watchdog_trip_s() >= 0
                                 ? (firmware.watchdog_trip_s() - firmware.watchdog_trip_last_command_s()) * 1e3 : -1;
  namespace config = hapfluid::config;
  config::Json summary;
  summary["build_id"] = config::build_id();
  summary["ticks"] = ticks;
  summary["ticks_lost"] = late_ticks;
  summary["states_sent"] = states_sent;
  summary["states_dropped"] = states_dropped;
  summary["states_corrupted"] = states_corrupted;
  summary["commands_applied"] = firmware.commands_applied();
  summary["command_sequence_gaps"] = firmware.command_sequence_gaps();
  summary["frames_bad"] = link->frames_bad();
  summary["faults"] = firmware.faults();
  summary["watchdog_trip_s"] = firmware.watchdog_trip_s();
  summary["last_command_s"] = firmware.last_command_s();
  summary["watchdog_reaction_ms"] = reaction_ms;
  std::fputs((config::json_line(summary) + "\n").c_str(), stdout);
  if (!o.summary_path.empty()) config::write_json_atomically(o.summary_path, summary);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  struct sigaction sa {};
  sa.sa_handler = on_signal;
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
  try {
    Options options;
    if (const int code = parse(argc, argv, options); code >= 0) return code;
    if (options.inject_on_signal) {
      struct sigaction inject {};
      inject.sa_handler = on_inject_signal;
      sigaction(SIGUSR1, &inject, nullptr);
    }
    return run(options);
  } catch (const std::exception& e) {
    log::error("%s", e.what());
    return 2;
  }
}
