// hil-loop-io-check: the 1 kHz loop's real-time rules held against a real device on a real
// kernel transport (hidraw through hidapi, USB bulk through libusb, SocketCAN) in the HIL guest,
// where device_check tests what the driver does and this tests what it costs the loop.
//
// It opens the device as haptic-rt does (open_link + HapticArm with the INFO handshake), waits
// until the device applies our commands, then runs the loop's device work, poll then send (a
// disabled zero command: its sequence number is what the device echoes back), on an absolute-
// time grid of --period-us for --seconds, on a SCHED_FIFO thread as haptic-rt's loop is. On that
// thread it records each tick's busy time (wake to the end of send) and the age of the command
// each fresh state says the device applied, and counts allocations and lock calls
// (tests/rt_core/thread_counters.hpp); a further second counts its system calls.
//
// Checks; each prints a line, any failure exits 1:
//   rules        no allocation, no lock call, no system call but the loop's clock. --allow-syscalls
//                names the ones that are the transport's own non-blocking device I/O (SocketCAN's
//                read and write on an O_NONBLOCK socket, also checked here); they pass uncounted.
//   --cyclictest cyclictest runs beside the loop through the window at the same priority and
//                period, and bounds the longest tick: on one CPU, whatever keeps the loop from
//                running (emulator stalls, interrupts, other threads) for a time T also delays a
//                cyclictest wake-up (one is due every period) by at least T - period; a loop
//                busy for T itself holds off cyclictest (same FIFO priority) as long. A tick may
//                take its own work (under one period) plus such a delay, so no tick may exceed
//                cyclictest's longest latency + 2 periods. Only a tick that sleeps in a system
//                call, which cyclictest does not feel, can; and the median tick must fit in one
//                period (the loop keeps its rate, not only its worst case).
//   --max-command-age-transfers N   the median age of the command the device reports applied
//                (from the loop's send to the state that echoes it) is at most N times the
//                median interval at which the device took commands (its echo moving on): with a
//                slow device the newest command reaches it, not a backlog (which would make the
//                age grow with every command queued ahead).
//   --expect-send-errors     the device's queue is full: sends must fail (and, by the checks
//                above, return at once).
#include <fcntl.h>
#include <sched.h>
#include <spawn.h>
#include <sys/mman.h>
#include <sys/wait.h>
#include <time.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "hapfluid/device/haptic_arm.hpp"
#include "hapfluid/device/open_device.hpp"
#include "thread_counters.hpp"

extern char** environ;

using namespace hapfluid;

namespace {

[[noreturn]] void fail(const std::string& what) {
  std::printf("FAIL: %s\n", what.c_str());
  std::exit(1);
}

std::uint64_t now_ns() {
  timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return static_cast<std::uint64_t>(t.tv_sec) * 1'000'000'000ull + static_cast<std::uint64_t>(t.tv_nsec);
}

void sleep_ns(std::uint64_t ns) {
  timespec t{static_cast<time_t>(ns / 1'000'000'000ull), static_cast<long>(ns % 1'000'000'000ull)};
  nanosleep(&t, nullptr);
}

struct Options {
  config::RigDevice device;
  double seconds = 3;
  std::uint64_t period_ns = 1'000'000;
  int priority = 80;
  bool cyclictest = false;
  double max_command_age_transfers = -1;
  bool expect_send_errors = false;
  std::vector<std::string> allowed_syscalls;
};

std::vector<std::string> split(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream in(text);
  for (std::string item; std::getline(in, item, ',');)
    if (!item.empty()) out.push_back(item);
  return out;
}

Options parse(int argc, char** argv) {
  Options o;
  o.device.name = "hil";
  o.device.transport.can_node_id = 1;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--cyclictest") { o.cyclictest = true; continue; }
    if (a == "--expect-send-errors") { o.expect_send_errors = true; continue; }
    if (i + 1 >= argc) fail(a + " needs a value");
    const std::string v = argv[++i];
    if (a == "--transport") {
      if (v == "hid") o.device.transport.kind = config::TransportKind::hid;
      else if (v == "usb_bulk") o.device.transport.kind = config::TransportKind::usb_bulk;
      else if (v == "socketcan") o.device.transport.kind = config::TransportKind::socketcan;
      else if (v == "loopback") o.device.transport.kind = config::TransportKind::loopback;
      else fail("--transport " + v + ": hid, usb_bulk, socketcan or loopback");
    } else if (a == "--address") o.device.transport.address = v;
    else if (a == "--framing") { o.device.transport.framing = v; o.device.transport.can_fd = v == "canfd"; }
    else if (a == "--node") o.device.transport.can_node_id = static_cast<std::uint32_t>(std::stoul(v));
    else if (a == "--seconds") o.seconds = std::stod(v);
    else if (a == "--period-us") o.period_ns = static_cast<std::uint64_t>(std::stod(v) * 1000);
    else if (a == "--priority") o.priority = std::stoi(v);
    else if (a == "--max-command-age-transfers") o.max_command_age_transfers = std::stod(v);
    else if (a == "--allow-syscalls") o.allowed_syscalls = split(v);
    else fail("unknown option " + a);
  }
  const auto kind = o.device.transport.kind;
  if (o.device.transport.address.empty()) fail("--transport and --address are required");
  if (kind == config::TransportKind::hid) o.device.transport.framing = "hid";
  if (kind == config::TransportKind::usb_bulk) o.device.transport.framing = "bulk";
  return o;
}

// cyclictest beside the loop: same period, same priority, every sample to `path`.
pid_t start_cyclictest(const Options& o, const std::string& path) {
  const std::string interval = std::to_string(o.period_ns / 1000), priority = std::to_string(o.priority);
  const char* argv[] = {"cyclictest", "-v", "-m", "-d", "0", "-i", interval.c_str(), "-p", priority.c_str(), nullptr};
  posix_spawn_file_actions_t files;
  posix_spawn_file_actions_init(&files);
  posix_spawn_file_actions_addopen(&files, 1, path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  pid_t pid = 0;
  if (posix_spawnp(&pid, "cyclictest", &files, nullptr, const_cast<char**>(argv), environ) != 0)
    fail("cannot start cyclictest (rt-tests)");
  posix_spawn_file_actions_destroy(&files);
  return pid;
}

// cyclictest's samples (µs), from its verbose lines "thread: cycle: latency".
std::vector<long> cyclictest_samples(const std::string& path) {
  std::vector<long> out;
  std::ifstream in(path);
  for (std::string line; std::getline(in, line);) {
    long thread = 0, cycle = 0, latency = 0;
    if (std::sscanf(line.c_str(), " %ld: %ld: %ld", &thread, &cycle, &latency) == 3) out.push_back(latency);
  }
  return out;
}

std::string ms(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.1f ms", v);
  return text;
}

// CPU time (s) of each of this process's threads by name, from /proc/self/task/*/stat.
std::map<std::string, double> thread_cpu_s() {
  std::map<std::string, double> out;
  std::error_code ec;
  for (const auto& task : std::filesystem::directory_iterator("/proc/self/task", ec)) {
    std::ifstream in(task.path() / "stat");
    std::string line;
    std::getline(in, line);
    const auto open = line.find('('), close = line.rfind(')');
    if (open == std::string::npos || close == std::string::npos) continue;
    std::istringstream rest(line.substr(close + 2));
    std::string field;
    unsigned long long utime = 0, stime = 0;
    for (int i = 3; i <= 15 && rest >> field; ++i) {
      if (i == 14) utime = std::stoull(field);
      if (i == 15) stime = std::stoull(field);
    }
    out[line.substr(open + 1, close - open - 1)] += (utime + stime) / static_cast<double>(sysconf(_SC_CLK_TCK));
  }
  return out;
}

bool cyclictest_running(const std::string& path) { return !cyclictest_samples(path).empty(); }

template <class T>
T median(std::vector<T> v) {
  if (v.empty()) return T{};
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

// Until the device applies our commands: its echo moves to one we sent. Generous for TCG.
void wait_until_applied(device::HapticArm& arm) {
  device::DeviceState s;
  device::DeviceCommand clear;
  clear.clear_faults = true;  // a watchdog fault latched before we came: cleared while disabled
  const std::uint64_t end = now_ns() + 30'000'000'000ull;
  int echoed = 0;
  while (now_ns() < end) {
    const bool fresh = arm.poll(s);
    arm.send(clear);
    const auto sent = static_cast<std::uint8_t>(arm.health().last_command_sequence);
    if (fresh && static_cast<std::uint8_t>(sent - s.command_echo) < 32 && ++echoed >= 20) return;
    sleep_ns(1'000'000);
  }
  fail("the device never applied our commands (health: transport 0x" +
       std::to_string(arm.health().transport_errors) + ", frames " + std::to_string(arm.health().frames_ok) + ")");
}

struct Window {
  std::vector<std::uint32_t> busy_ns;       // per tick: wake to the end of send
  std::vector<std::uint32_t> age_us;        // per fresh state: the echoed command's age
  std::vector<std::uint32_t> take_us;       // between the device taking one command and the next
  std::uint64_t ticks = 0, overruns = 0, fresh = 0;
  long allocations = 0, locks = 0;
  double loop_cpu_s = 0;
  device::DeviceHealth timed;               // at the end of the timed window
  std::string refused;                      // why the system-call watch could not run
};

constexpr std::uint64_t kSyscallWindowNs = 1'000'000'000;

// The loop: a SCHED_FIFO thread (as haptic-rt's, where the machine allows) on the period grid,
// skipping missed slots as RtLoop::run does. Everything it uses is sized before the window.
void run_loop(const Options& o, device::HapticArm& arm, counters::SyscallWatch& watch, Window& w) {
  const std::size_t capacity = static_cast<std::size_t>(o.seconds * 1e9 / o.period_ns) + 16;
  w.busy_ns.reserve(capacity);
  w.age_us.reserve(capacity);
  w.take_us.reserve(capacity);
  std::uint64_t sent_ns[256] = {};
  int last_echo = -1;
  std::uint64_t last_take_ns = 0;
  std::thread loop([&] {
    sched_param p{};
    p.sched_priority = o.priority;
    if (pthread_setschedparam(pthread_self(), SCHED_FIFO, &p) != 0)
      std::printf("warning: SCHED_FIFO %d refused: the loop runs at normal priority\n", o.priority);
    device::DeviceState s;
    device::DeviceCommand command;
    auto tick = [&](std::uint64_t wake, bool record) {
      const bool fresh = arm.poll(s);
      if (fresh && record) {
        const std::uint64_t now = now_ns();
        const std::uint64_t sent = sent_ns[s.command_echo & 0xFF];
        if (sent) w.age_us.push_back(static_cast<std::uint32_t>((now - sent) / 1000));
        if (s.command_echo != last_echo) {
          if (last_take_ns) w.take_us.push_back(static_cast<std::uint32_t>((now - last_take_ns) / 1000));
          last_echo = s.command_echo;
          last_take_ns = now;
        }
        ++w.fresh;
      }
      const std::uint64_t send_start = now_ns();
      arm.send(command);
      sent_ns[arm.health().last_command_sequence & 0xFF] = send_start;
      if (record) w.busy_ns.push_back(static_cast<std::uint32_t>(now_ns() - wake));
    };
    auto run = [&](std::uint64_t duration_ns, bool record) {
      const std::uint64_t start = now_ns();
      std::uint64_t next = (start / o.period_ns + 1) * o.period_ns;
      const std::uint64_t end = start + duration_ns;
      while (next < end) {
        timespec ts{static_cast<time_t>(next / 1'000'000'000ull), static_cast<long>(next % 1'000'000'000ull)};
        while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
        }
        tick(now_ns(), record);
        if (record) ++w.ticks;
        next += o.period_ns;
        const std::uint64_t after = now_ns();
        if (after >= next) {
          const std::uint64_t missed = (after - next) / o.period_ns + 1;
          next += missed * o.period_ns;
          if (record) w.overruns += missed;
        }
      }
    };
    run(300'000'000, false);  // every path warmed once (first touches, the loop's own first allocations)
    timespec cpu0, cpu1;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &cpu0);
    counters::count_on_this_thread(true);
    run(static_cast<std::uint64_t>(o.seconds * 1e9), true);
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &cpu1);
    counters::count_on_this_thread(false);
    w.timed = arm.health();
    // Then the system calls, in a window of their own: each one the watch sees costs a round trip
    // to its supervisor, which would make the timing above the watch's rather than the loop's.
    if (watch.watch_this_thread(w.refused, o.allowed_syscalls)) {
      counters::count_on_this_thread(true);
      watch.start();
      run(kSyscallWindowNs, false);
      watch.stop();
    }
    counters::count_on_this_thread(false);
    w.loop_cpu_s = (cpu1.tv_sec - cpu0.tv_sec) + (cpu1.tv_nsec - cpu0.tv_nsec) * 1e-9;
    w.allocations = counters::allocations();
    w.locks = counters::locks();
  });
  loop.join();
}

}  // namespace

int main(int argc, char** argv) {
  const Options o = parse(argc, argv);
  if (mlockall(MCL_CURRENT | MCL_FUTURE) != 0) std::printf("warning: mlockall refused\n");
  auto link = device::open_link(o.device.transport, device::Side::host);
  device::Transport& transport = link->transport();
  device::HapticArm arm(o.device.name, std::move(link), 200);
  std::printf("device: %s\n", transport.describe().c_str());
  if (!o.allowed_syscalls.empty()) {
    const int fd = transport.poll_fd();
    if (fd < 0 || !(fcntl(fd, F_GETFL) & O_NONBLOCK))
      fail("the transport's system calls are allowed as non-blocking device I/O, but its descriptor is not O_NONBLOCK");
    std::printf("PASS: the transport's descriptor %d is O_NONBLOCK\n", fd);
  }
  if (!o.expect_send_errors) wait_until_applied(arm);
  const device::DeviceHealth before = arm.health();

  const std::string samples_path = "cyclictest.out";
  pid_t cyclictest = 0;
  if (o.cyclictest) {
    cyclictest = start_cyclictest(o, samples_path);
    const std::uint64_t end = now_ns() + 30'000'000'000ull;
    while (!cyclictest_running(samples_path)) {
      if (now_ns() > end) fail("cyclictest printed no sample within 30 s");
      sleep_ns(10'000'000);
    }
  }
  counters::SyscallWatch watch;
  Window w;
  const auto cpu_before = thread_cpu_s();
  run_loop(o, arm, watch, w);
  const auto cpu_after = thread_cpu_s();
  if (cyclictest) {
    kill(cyclictest, SIGINT);
    waitpid(cyclictest, nullptr, 0);
  }
  if (!w.refused.empty()) fail("cannot watch the loop's system calls: " + w.refused);
  const device::DeviceHealth& after = w.timed;

  const double period_us = o.period_ns / 1e3;
  const auto longest = w.busy_ns.empty() ? 0u : *std::max_element(w.busy_ns.begin(), w.busy_ns.end());
  std::printf("loop: period %.0f us, %llu ticks in %.1f s, %llu overruns, tick (wake to end of send) median %.1f us, "
              "longest %.1f us; %llu fresh states; commands sent %llu, send errors %llu, transport 0x%x\n",
              period_us, static_cast<unsigned long long>(w.ticks), o.seconds,
              static_cast<unsigned long long>(w.overruns), median(w.busy_ns) / 1e3, longest / 1e3,
              static_cast<unsigned long long>(w.fresh),
              static_cast<unsigned long long>(after.commands_sent - before.commands_sent),
              static_cast<unsigned long long>(after.send_errors - before.send_errors), after.transport_errors);
  std::string cpu = "loop " + std::to_string(static_cast<int>(w.loop_cpu_s / o.seconds * 100)) + " %";
  for (const auto& [name, seconds] : cpu_after) {
    const auto was = cpu_before.find(name);
    const double used = seconds - (was == cpu_before.end() ? 0 : was->second);
    if (used > 0) cpu += ", " + name + " " + std::to_string(static_cast<int>(used / o.seconds * 100)) + " %";
  }
  std::printf("CPU of this process's threads in the window: %s\n", cpu.c_str());
  bool ok = true;
  auto check = [&](bool pass, const std::string& what) {
    std::printf("%s: %s\n", pass ? "PASS" : "FAIL", what.c_str());
    ok = ok && pass;
  };

  check(w.allocations == 0, "allocations on the loop thread: " + std::to_string(w.allocations));
  check(w.locks == 0, "lock calls on the loop thread: " + std::to_string(w.locks));
  std::string besides = "its clock";
  for (const std::string& name : o.allowed_syscalls) besides += ", " + name;
  const std::string calls = watch.summary();
  check(watch.total() == 0,
        "system calls on the loop thread besides " + besides + ": " + (calls.empty() ? std::string("none") : calls));

  if (o.cyclictest) {
    const std::vector<long> samples = cyclictest_samples(samples_path);
    const long worst = samples.empty() ? 0 : *std::max_element(samples.begin(), samples.end());
    const double bound_us = worst + 2 * period_us;
    const auto late = std::count_if(samples.begin(), samples.end(), [&](long us) { return us >= period_us; });
    std::printf("cyclictest beside the loop: %zu samples, median %ld us, longest %ld us, %ld later than one period\n",
                samples.size(), median(samples), worst, static_cast<long>(late));
    check(samples.size() >= w.ticks / 2, "cyclictest ran through the window");
    check(longest / 1e3 <= bound_us, "longest tick " + std::to_string(longest / 1000) + " us <= cyclictest's longest " +
                                         std::to_string(worst) + " us + 2 periods = " +
                                         std::to_string(static_cast<long>(bound_us)) + " us");
    check(median(w.busy_ns) / 1e3 <= period_us,
          "median tick " + std::to_string(median(w.busy_ns) / 1000) + " us fits in one period");
  }
  if (o.max_command_age_transfers >= 0) {
    const double age_ms = median(w.age_us) / 1e3, take_ms = median(w.take_us) / 1e3;
    const double oldest_ms = w.age_us.empty() ? 0 : *std::max_element(w.age_us.begin(), w.age_us.end()) / 1e3;
    std::printf("commands: the device took one every %.1f ms (median of %zu); the one it applied was %.1f ms old "
                "(median; oldest %.1f ms) over %zu states\n", take_ms, w.take_us.size(), age_ms, oldest_ms,
                w.age_us.size());
    check(!w.age_us.empty() && !w.take_us.empty() && age_ms <= o.max_command_age_transfers * take_ms,
          "median command age " + ms(age_ms) + " <= " + std::to_string(static_cast<int>(o.max_command_age_transfers)) +
              " x the device's interval " + ms(take_ms) + " = " + ms(o.max_command_age_transfers * take_ms));
  }
  if (o.expect_send_errors)
    check(after.send_errors > before.send_errors, "sends failed at once on the full queue: " +
                                                      std::to_string(after.send_errors - before.send_errors));
  std::printf("%s\n", ok ? "PASS: the loop's device I/O kept the real-time rules" : "FAIL: see above");
  return ok ? 0 : 1;
}
