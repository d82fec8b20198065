// hil-device-check: the host side of a HIL test, through the same Device interface the 1 kHz
// loop uses (open_device on a rig-style device description), against haptic-fake-device on a
// real kernel transport (SocketCAN, hidraw via hidapi, USB bulk via libusb).
//
// Phases, each a functional requirement with a generous limit (guest time under TCG is slow, so
// no timing figure here means anything; only whether things happen):
//   0. --plug-cmd (the host starts first, as a rig's services do at boot before the arm is
//                powered): the device is not there at open; open_device must still return it,
//                disconnected (a link fault, never an exit), and the start-up hint must say it
//                is waited for; the driver is polled and commanded like the 1 kHz loop does for
//                --absent-s, then --plug-cmd makes the device appear (run alongside, the polling
//                goes on) and the same Device must take it up by itself; the phases below follow.
//   1. states:   N valid states arrive, sequence numbers advance, no bad frames.
//   2. commands: clear faults, then stream enable + a force; the device must echo the command
//                sequence, report motors enabled and no fault (it applied the commands).
//   3. --expect watchdog: stop commanding; the device must report the command-watchdog fault
//                with motors off (it must never keep pushing on a hand after the host died).
//      --expect bus-off:  the device's bus-off error frames must reach health().transport_errors,
//                and states must flow again after the controller restarts.
//      --expect unplug:   run --unplug-cmd; the driver must report disconnected; run
//                --replug-cmd; then, with --recover self, the same Device must recover by
//                itself (what haptic-rt relies on: it opens its devices once): states flow,
//                health().connected again, and a clear-faults command is applied; with
//                --recover reopen (default) a supervisor drops the device and reopening by the
//                same address must give states again.
//   spacemouse (--kind spacemouse): states from 3Dconnexion reports; the pose must move 2 mm.
#include <spawn.h>
#include <sys/wait.h>
#include <time.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>

#include "hapfluid/device/open_device.hpp"
#include "hapfluid/device/transport.hpp"
#include "hapfluid/wire/codec.h"

extern char** environ;

using namespace hapfluid;

namespace {

[[noreturn]] void fail(const std::string& what) {
  std::printf("FAIL: %s\n", what.c_str());
  std::exit(1);
}

double now_s() {
  timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return t.tv_sec + t.tv_nsec * 1e-9;
}

void sleep_ms(double ms) {
  timespec t{0, static_cast<long>(ms * 1e6)};
  nanosleep(&t, nullptr);
}

struct Options {
  config::RigDevice device;
  int states = 200;
  double command_s = 1.0;
  double force_n = 1.5;
  std::string expect;
  std::string plug_cmd, unplug_cmd, replug_cmd;
  double absent_s = 1.0;
  std::string recover = "reopen";
  double limit_s = 30;
};

std::unique_ptr<device::Device> open_within(const config::RigDevice& d, double limit_s) {
  const double end = now_s() + limit_s;
  std::string last;
  for (;;) {
    try {
      return device::open_device(d);
    } catch (const std::exception& e) {
      if (last != e.what()) std::printf("open: %s (retrying)\n", e.what());
      last = e.what();
    }
    if (now_s() > end) fail("could not open " + d.transport.address + " within " + std::to_string(limit_s) + " s: " + last);
    sleep_ms(100);
  }
}

// Polls like the 1 kHz loop (every 1 ms) until `done` or the limit; returns false on timeout.
template <class Done>
bool run_until(device::Device& dev, device::DeviceState& s, double limit_s, Done done,
               const device::DeviceCommand* command = nullptr) {
  const double end = now_s() + limit_s;
  while (now_s() < end) {
    bool updated = dev.poll(s);
    if (command) dev.send(*command);
    if (done(updated)) return true;
    sleep_ms(1);
  }
  return false;
}

void print_state(const char* tag, const device::DeviceState& s, const device::DeviceHealth& h) {
  std::printf("%s: seq %u, p = (%.4f, %.4f, %.4f) m, q = (%.3f, %.3f, %.3f, %.3f), status 0x%02x, fault 0x%02x, "
              "echo %u | frames ok %llu bad %llu gaps %llu, commands %llu (send errors %llu), transport 0x%x, %s\n",
              tag, s.sequence, s.position_m[0], s.position_m[1], s.position_m[2], s.orientation[0], s.orientation[1],
              s.orientation[2], s.orientation[3], s.status, s.fault, s.command_echo,
              (unsigned long long)h.frames_ok, (unsigned long long)h.frames_bad, (unsigned long long)h.sequence_gaps,
              (unsigned long long)h.commands_sent, (unsigned long long)h.send_errors, h.transport_errors,
              h.connected ? "connected" : "not connected");
}

// The STATE sequence modulus on this link: classic CAN carries the low 8 bits, everything else
// 16 (protocol.md 3). Comparing 16-bit numbers modulo 256 would call a forward jump of 128..255
// (states dropped while nobody read, e.g. the FIFO a device flushes after a replug) "backwards".
std::uint32_t g_sequence_modulus = 65536;

int receive_states(device::Device& dev, device::DeviceState& s, int n, double limit_s, const char* phase) {
  int got = 0, backwards = 0;
  std::uint16_t last = 0;
  bool have = false;
  run_until(dev, s, limit_s, [&](bool updated) {
    if (updated) {
      const std::uint32_t ahead = (s.sequence - last + g_sequence_modulus) % g_sequence_modulus;
      if (have && (ahead == 0 || ahead >= g_sequence_modulus / 2)) {
        std::printf("%s: state sequence %u after %u\n", phase, s.sequence, last);
        ++backwards;
      }
      last = s.sequence;
      have = true;
      ++got;
    }
    return got >= n;
  });
  if (got < n) fail(std::string(phase) + ": only " + std::to_string(got) + " of " + std::to_string(n) + " states");
  if (backwards) fail(std::string(phase) + ": state sequence went backwards " + std::to_string(backwards) + " times");
  return got;
}

// `sh -c command` started alongside (the caller keeps polling); its pid.
pid_t spawn_shell(const std::string& command) {
  const char* argv[] = {"/bin/sh", "-c", command.c_str(), nullptr};
  pid_t pid = 0;
  if (posix_spawn(&pid, "/bin/sh", nullptr, nullptr, const_cast<char**>(argv), environ) != 0)
    fail("cannot start /bin/sh for: " + command);
  return pid;
}

// Phase 0: the device is absent at open, the driver waits for it, and takes it up when it appears.
void check_absent_then_plugged(device::Device& dev, const Options& o) {
  const device::DeviceHealth h = dev.health();
  print_state("absent", device::DeviceState{}, h);
  if (h.connected || !(h.transport_errors & device::kDisconnected))
    fail("the device is not there yet, but the driver does not report it disconnected");
  const std::string hint = device::silent_device_hint(o.device, h);
  std::printf("start-up hint: %s\n", hint.c_str());
  const bool waited_for = o.device.transport.kind == config::TransportKind::loopback
                              ? hint.find("no bus there yet") != std::string::npos
                              : hint.find("is not connected: ") != std::string::npos &&
                                    hint.find("waiting for it") != std::string::npos;
  if (!waited_for) fail("the start-up hint does not say the device is waited for: " + hint);
  // The loop meanwhile: poll and a zero, disabled command every tick, at a link fault.
  device::DeviceState s;
  const device::DeviceCommand zero;
  int ticks = 0;
  double longest_ms = 0;
  const double absent_end = now_s() + o.absent_s;
  while (now_s() < absent_end) {
    const double t0 = now_s();
    dev.poll(s);
    dev.send(zero);
    longest_ms = std::fmax(longest_ms, (now_s() - t0) * 1e3);
    ++ticks;
    sleep_ms(1);
  }
  if (dev.health().connected) fail("the absent device was reported connected");
  if (ticks < 100) fail("the driver was polled only " + std::to_string(ticks) + " times in " + std::to_string(o.absent_s) + " s");
  std::printf("PHASE absent: open_device returned the absent device disconnected; %d ticks of poll + send in %.1f s "
              "(longest %.1f ms), still disconnected\n", ticks, o.absent_s, longest_ms);
  std::printf("plug: %s\n", o.plug_cmd.c_str());
  const pid_t plug = spawn_shell(o.plug_cmd);
  int status = 0;
  bool plugged = false;
  if (!run_until(dev, s, o.limit_s, [&](bool) {
        if (!plugged && waitpid(plug, &status, WNOHANG) == plug) {
          plugged = true;
          if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) fail("plug command failed: " + o.plug_cmd);
        }
        return dev.health().connected;
      }, &zero))
    fail("the device appeared but the driver never took it up (health().connected stays false, transport 0x" +
         std::to_string(dev.health().transport_errors) + ")");
  if (!plugged && (waitpid(plug, &status, 0) != plug || !WIFEXITED(status) || WEXITSTATUS(status) != 0))
    fail("plug command failed: " + o.plug_cmd);
  print_state("appeared", s, dev.health());
  std::printf("PHASE appeared: the same driver took the device up by itself\n");
}

int check_arm(std::unique_ptr<device::Device>& owned, const Options& o) {
  device::Device& dev = *owned;
  device::DeviceState s;
  receive_states(dev, s, o.states, o.limit_s, "states");
  device::DeviceHealth h = dev.health();
  print_state("states", s, h);
  if (!h.connected) fail("states arrive but health().connected is false");
  if (h.frames_bad) fail("bad frames on a clean link: " + std::to_string(h.frames_bad));
  std::printf("PHASE states: %d valid states, sequence advancing, no bad frames\n", o.states);

  if (o.expect == "bus-off") {
    // Before any command: the fake device's bus-off (it neither sends nor receives meanwhile)
    // would otherwise trip its command watchdog in the middle of the command phase.
    if (!run_until(dev, s, o.limit_s, [&](bool) { return dev.health().transport_errors & device::kBusOff; }, nullptr))
      fail("bus-off error frames were never reported in health().transport_errors");
    std::printf("PHASE bus-off: health().transport_errors = 0x%x (bus-off reported)\n", dev.health().transport_errors);
    receive_states(dev, s, 50, o.limit_s, "after bus-off");
    print_state("after bus-off", s, dev.health());
    std::printf("PHASE bus-off: states flow again after the controller restarted\n");
  }

  // Commands: faults latched from before the host started (the watchdog trips while nobody
  // commands) are cleared explicitly with enable off, then force is commanded.
  device::DeviceCommand clear;
  clear.clear_faults = true;
  if (!run_until(dev, s, o.limit_s, [&](bool) { return s.fault == 0; }, &clear))
    fail("clear_faults did not clear the device faults (fault 0x" + std::to_string(s.fault) + ")");
  const std::uint64_t send_errors_before = dev.health().send_errors;  // while it was absent, if it was
  device::DeviceCommand cmd;
  cmd.enable = true;
  cmd.force_n[0] = o.force_n;
  cmd.force_n[2] = -0.5 * o.force_n;
  int echoed = 0;
  const double start = now_s();
  run_until(dev, s, o.limit_s, [&](bool updated) {
    if (updated && (s.status & HF_STATUS_MOTORS_ENABLED) && s.fault == 0 && s.command_echo != 0) ++echoed;
    return now_s() - start >= o.command_s && echoed >= 50;
  }, &cmd);
  h = dev.health();
  print_state("commands", s, h);
  if (echoed < 50) fail("the device never applied the commands: " + std::to_string(echoed) + " states with motors enabled");
  if (h.send_errors > send_errors_before)
    fail(std::to_string(h.send_errors - send_errors_before) + " send errors while commanding");
  // The device echoes the newest command it applied: once the host stops sending, the echo must
  // reach the last command sent (how long that takes under emulation means nothing).
  const std::uint8_t sent_low = static_cast<std::uint8_t>(h.last_command_sequence & 0xFF);
  if (!run_until(dev, s, o.limit_s, [&](bool) { return static_cast<std::uint8_t>(s.command_echo & 0xFF) == sent_low; }))
    fail("the device never echoed the last command sent (seq low byte " + std::to_string(sent_low) + ", echo " +
         std::to_string(s.command_echo & 0xFF) + ")");
  std::printf("PHASE commands: %llu commands sent (force %.2f N x, %.2f N z, enable), %d states with motors enabled, "
              "the last command (seq low byte %u) echoed by the device\n",
              (unsigned long long)h.commands_sent, o.force_n, -0.5 * o.force_n, echoed, sent_low);

  if (o.expect == "watchdog") {
    // The host goes silent: poll only. The device must switch its motors off on its own.
    if (!run_until(dev, s, o.limit_s, [&](bool) {
          return (s.fault & HF_FAULT_COMMAND_WATCHDOG) && (s.status & HF_STATUS_WATCHDOG_TRIPPED) &&
                 !(s.status & HF_STATUS_MOTORS_ENABLED);
        }))
      fail("the device did not report its command watchdog after the host stopped commanding");
    print_state("watchdog", s, dev.health());
    std::printf("PHASE watchdog: device reported HF_FAULT_COMMAND_WATCHDOG with motors off after the host went silent\n");
  } else if (o.expect == "unplug") {
    std::printf("unplug: %s\n", o.unplug_cmd.c_str());
    if (std::system(o.unplug_cmd.c_str()) != 0) fail("unplug command failed: " + o.unplug_cmd);
    if (!run_until(dev, s, o.limit_s, [&](bool) {
          auto hh = dev.health();
          return (hh.transport_errors & device::kDisconnected) || !hh.connected;
        }, &cmd))
      fail("the driver never reported the unplugged device (transport_errors / connected)");
    print_state("unplugged", s, dev.health());
    std::printf("PHASE unplug: driver reported the device gone\n");
    if (o.recover == "self") {
      std::printf("replug: %s\n", o.replug_cmd.c_str());
      if (std::system(o.replug_cmd.c_str()) != 0) fail("replug command failed: " + o.replug_cmd);
      // The loop keeps polling (and commanding nothing) the same Device.
      if (!run_until(dev, s, o.limit_s, [&](bool) { return dev.health().connected; }))
        fail("the driver did not recover by itself after the replug (health().connected stays false, transport 0x" +
             std::to_string(dev.health().transport_errors) + ")");
      receive_states(dev, s, 50, o.limit_s, "after replug");
      // Commands reach the device again: a watchdog fault latched while unplugged is cleared, and
      // the device echoes the last command the recovered driver sent.
      if (!run_until(dev, s, o.limit_s, [&](bool) { return s.fault == 0; }, &clear))
        fail("after the replug the device never applied clear_faults (fault 0x" + std::to_string(s.fault) + ")");
      const std::uint8_t last_low = static_cast<std::uint8_t>(dev.health().last_command_sequence & 0xFF);
      if (!run_until(dev, s, o.limit_s, [&](bool) { return static_cast<std::uint8_t>(s.command_echo & 0xFF) == last_low; }))
        fail("after the replug the device never echoed the last command (seq low byte " + std::to_string(last_low) +
             ", echo " + std::to_string(s.command_echo & 0xFF) + ")");
      print_state("replugged", s, dev.health());
      std::printf("PHASE replug: the same driver recovered by itself: states flow, commands applied\n");
      return 0;
    }
    // Recovery as a supervisor does it: drop the dead device, then open the address again.
    owned.reset();
    std::printf("PHASE unplug: the unplugged device closed cleanly\n");
    std::printf("replug: %s\n", o.replug_cmd.c_str());
    if (std::system(o.replug_cmd.c_str()) != 0) fail("replug command failed: " + o.replug_cmd);
    owned = open_within(o.device, o.limit_s);
    receive_states(*owned, s, 50, o.limit_s, "after replug");
    print_state("replugged", s, owned->health());
    std::printf("PHASE replug: reopened %s, states flow again\n", o.device.transport.address.c_str());
  } else if (!o.expect.empty() && o.expect != "bus-off") {
    fail("unknown --expect " + o.expect);
  }
  return 0;
}

int check_spacemouse(device::Device& dev, const Options& o) {
  device::DeviceState s, first;
  receive_states(dev, s, 1, o.limit_s, "spacemouse");
  first = s;
  double moved = 0;
  run_until(dev, s, o.limit_s, [&](bool) {
    moved = std::hypot(s.position_m[0] - first.position_m[0], s.position_m[1] - first.position_m[1],
                       s.position_m[2] - first.position_m[2]);
    return moved > 2e-3;
  });
  print_state("spacemouse", s, dev.health());
  if (moved <= 2e-3) fail("the SpaceMouse pose never moved although the hand moves");
  std::printf("PHASE spacemouse: rate reports integrated into a pose that moved %.4f m\n", moved);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  setvbuf(stdout, nullptr, _IOLBF, 0);
  Options o;
  o.device.name = "hil";
  for (int i = 1; i < argc; ++i) {
    std::string a = argv[i];
    if (i + 1 >= argc) fail(a + " needs a value");
    std::string v = argv[++i];
    if (a == "--transport") {
      if (v == "socketcan") o.device.transport.kind = config::TransportKind::socketcan;
      else if (v == "hid") o.device.transport.kind = config::TransportKind::hid;
      else if (v == "usb_bulk") o.device.transport.kind = config::TransportKind::usb_bulk;
      else if (v == "loopback") o.device.transport.kind = config::TransportKind::loopback;
      else fail("--transport " + v);
    } else if (a == "--address") o.device.transport.address = v;
    else if (a == "--fd") o.device.transport.can_fd = v == "1";
    else if (a == "--framing") o.device.transport.framing = v;
    else if (a == "--node") o.device.transport.can_node_id = static_cast<std::uint32_t>(std::atoi(v.c_str()));
    else if (a == "--kind") o.device.kind = v == "spacemouse" ? config::DeviceKind::spacemouse : config::DeviceKind::haptic_arm;
    else if (a == "--states") o.states = std::atoi(v.c_str());
    else if (a == "--command-s") o.command_s = std::atof(v.c_str());
    else if (a == "--force-n") o.force_n = std::atof(v.c_str());
    else if (a == "--expect") o.expect = v;
    else if (a == "--plug-cmd") o.plug_cmd = v;
    else if (a == "--absent-s") o.absent_s = std::atof(v.c_str());
    else if (a == "--unplug-cmd") o.unplug_cmd = v;
    else if (a == "--replug-cmd") o.replug_cmd = v;
    else if (a == "--recover") {
      if (v != "self" && v != "reopen") fail("--recover must be self or reopen, not " + v);
      o.recover = v;
    }
    else if (a == "--limit-s") o.limit_s = std::atof(v.c_str());
    // The rig's idea of the device's command watchdog, checked against its INFO reply at open.
    else if (a == "--device-watchdog-ms") o.device.watchdogs.device_watchdog_ms = std::atof(v.c_str());
    else fail("unknown option " + a);
  }
  if (o.device.transport.kind == config::TransportKind::socketcan && !o.device.transport.can_fd) g_sequence_modulus = 256;
  if (o.device.transport.kind == config::TransportKind::loopback && o.device.transport.framing == "can")
    g_sequence_modulus = 256;
  auto dev = open_within(o.device, o.limit_s);
  std::printf("opened %s\n", dev->name());
  if (!o.plug_cmd.empty()) check_absent_then_plugged(*dev, o);
  int rc = o.device.kind == config::DeviceKind::spacemouse ? check_spacemouse(*dev, o) : check_arm(dev, o);
  std::printf("CHECKS PASSED\n");
  // Closing is part of the contract too: a driver that crashes when the loop shuts down (or when
  // a supervisor drops a device) takes the whole real-time process with it.
  dev.reset();
  std::printf("PHASE close: the device closed cleanly\nPASS\n");
  return rc;
}
