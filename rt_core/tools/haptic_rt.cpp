// haptic-rt: the 1 kHz coupling process (rt_core/README.md).
//   haptic-rt --rig FILE [--duration S] [--simulated-devices] [--trace FILE]
//             [--flight-dir DIR] [--shm-prefix NAME]
// Signals: SIGINT/SIGTERM stop cleanly; SIGUSR1 latches the e-stop; SIGUSR2 resets it.
// Exit codes: 0 ok, 2 bad arguments/config/shm or a device that can never open as configured (one
// that is not there yet is waited for at a link fault), 3 refused by rt.policy = enforce.
#include <signal.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "hapfluid/config/errors.hpp"
#include "hapfluid/config/rig.hpp"
#include "hapfluid/rt/device_seam.hpp"
#include "hapfluid/rt/loop.hpp"
#include "hapfluid/rt/rt_setup.hpp"
#include "hapfluid/rt/supervisor.hpp"
#include "hapfluid/safety/flags.hpp"

using namespace hapfluid;

namespace {

rt::RtLoop* g_loop = nullptr;

void on_signal(int signal) {
  if (!g_loop) return;
  if (signal == SIGUSR1) g_loop->request_estop();
  else if (signal == SIGUSR2) g_loop->request_estop_reset();
  else g_loop->stop();
}

void usage() {
  std::fprintf(stderr,
               "usage: haptic-rt --rig FILE [--duration S] [--simulated-devices] [--trace FILE]\n"
               "                 [--flight-dir DIR] [--shm-prefix NAME]\n"
               "  --simulated-devices  use in-process simulated handles instead of the rig's transports\n"
               "  --trace FILE         drain the trace ring to FILE (CSV) from a non-RT thread\n"
               "  --flight-dir DIR     where fault post-mortems go (default $TMPDIR/hapfluid-flight)\n");
}

struct Args {
  std::string rig, trace, flight_dir, prefix;
  double duration_s = 0;
  bool simulated = false;
};

bool parse(int argc, char** argv, Args& a) {
  for (int i = 1; i < argc; ++i) {
    std::string arg = argv[i];
    auto value = [&](const char* name) -> const char* {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "haptic-rt: %s needs a value\n", name);
        return nullptr;
      }
      return argv[++i];
    };
    const char* v = nullptr;
    if (arg == "--rig" && (v = value("--rig"))) a.rig = v;
    else if (arg == "--trace" && (v = value("--trace"))) a.trace = v;
    else if (arg == "--flight-dir" && (v = value("--flight-dir"))) a.flight_dir = v;
    else if (arg == "--shm-prefix" && (v = value("--shm-prefix"))) a.prefix = v;
    else if (arg == "--duration" && (v = value("--duration"))) {
      char* end = nullptr;
      a.duration_s = std::strtod(v, &end);
      if (*end || a.duration_s < 0) {
        std::fprintf(stderr, "haptic-rt: --duration %s: must be seconds >= 0\n", v);
        return false;
      }
    } else if (arg == "--simulated-devices") a.simulated = true;
    else if (arg == "--help" || arg == "-h") return usage(), false;
    else {
      if (!v) std::fprintf(stderr, "haptic-rt: unknown or incomplete argument \"%s\"\n", arg.c_str());
      return usage(), false;
    }
  }
  if (a.rig.empty()) {
    std::fprintf(stderr, "haptic-rt: --rig FILE is required\n");
    return usage(), false;
  }
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  Args args;
  if (!parse(argc, argv, args)) return 2;
  config::Rig rig;
  try {
    rig = config::load_rig(args.rig);
  } catch (const config::ConfigError& e) {
    std::fprintf(stderr, "haptic-rt: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "haptic-rt: %s\n", e.what());
    return 2;
  }
  if (!args.prefix.empty()) rig.rt.shm.prefix = args.prefix;
  if (args.flight_dir.empty()) {
    const char* tmp = std::getenv("TMPDIR");
    args.flight_dir = std::string(tmp && *tmp ? tmp : "/tmp") + "/hapfluid-flight";
  }

  std::fprintf(stderr, "haptic-rt: rig \"%s\" (%s): period %lld ns, SCHED_FIFO %d, cpu %d, policy %s, shm /%s.*\n",
               rig.name.c_str(), args.rig.c_str(), (long long)rig.rt.period_ns, rig.rt.priority, rig.rt.cpu,
               config::to_string(rig.rt.policy), rig.rt.shm.prefix.c_str());
  std::vector<std::unique_ptr<device::Device>> devices;
  for (const auto& d : rig.devices) {
    std::fprintf(stderr, "haptic-rt: device \"%s\": wrench_mode %s, safety limits:\n%s", d.name.c_str(),
                 config::to_string(d.wrench_mode), safety::describe(safety::make_safety_config(d, rig.rt.period_ns)).c_str());
    std::string error;
    auto device = rt::open_rig_device(d, args.simulated ? rt::DeviceBackend::simulated : rt::DeviceBackend::driver, error);
    if (!device) {
      std::fprintf(stderr, "haptic-rt: %s\n", error.c_str());
      return 2;
    }
    if (args.simulated) std::fprintf(stderr, "haptic-rt: device \"%s\": SIMULATED handle (no hardware)\n", d.name.c_str());
    else if (!device->health().connected)
      std::fprintf(stderr, "haptic-rt: %s; meanwhile the loop holds it at a link fault with zero wrench\n",
                   rt::silent_device_hint(d, device->health(), args.rig).c_str());
    devices.push_back(std::move(device));
  }

  std::unique_ptr<rt::RtLoop> loop;
  std::unique_ptr<rt::Supervisor> supervisor;
  try {
    loop = std::make_unique<rt::RtLoop>(rig, std::move(devices));
    rt::SupervisorOptions options;
    options.sim_segment = shm::segment_name(rig.rt.shm.prefix, shm::ChannelKind::sim_samples);
    options.flight_dir = args.flight_dir;
    options.trace_path = args.trace;
    supervisor = std::make_unique<rt::Supervisor>(*loop, options);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "haptic-rt: %s\n", e.what());
    return 2;
  }
  g_loop = loop.get();
  struct sigaction action {};
  action.sa_handler = on_signal;
  for (int s : {SIGINT, SIGTERM, SIGUSR1, SIGUSR2}) sigaction(s, &action, nullptr);

  // The supervisor starts first so it inherits neither SCHED_FIFO nor the loop's CPU.
  supervisor->start();
  rt::RtSetupReport report = rt::setup_realtime(rig.rt);
  if (report.refused) {
    std::fprintf(stderr, "haptic-rt: rt.policy = enforce and the real-time set-up failed; refusing to run:\n%s",
                 report.messages.c_str());
    supervisor->stop();
    return 3;
  }
  if (report.degraded_flags & rt::kDegradedMask)
    std::fprintf(stderr,
                 "haptic-rt: WARNING ************************************************************\n"
                 "haptic-rt: WARNING running DEGRADED (rt.policy = ignore); every trace record is marked:\n%s"
                 "haptic-rt: WARNING ************************************************************\n",
                 report.messages.c_str());
  else if (!report.messages.empty())
    std::fprintf(stderr, "haptic-rt: note: %s", report.messages.c_str());
  if (!(report.degraded_flags & rt::loop_no_affinity)) {
    int moved = rt::keep_other_threads_off_cpu(rig.rt.cpu);
    if (moved) std::fprintf(stderr, "haptic-rt: %d helper thread(s) kept off the loop's CPU %d\n", moved, rig.rt.cpu);
  }
  rt::prefault_heap(8u << 20);
  rt::prefault_stack(256u << 10);
  loop->set_degraded_flags(report.degraded_flags);
  std::fprintf(stderr, "haptic-rt: loop thread tid %ld running%s\n", (long)syscall(SYS_gettid),
               args.duration_s > 0 ? (" for " + std::to_string(args.duration_s) + " s").c_str() : "");

  loop->run(static_cast<std::uint64_t>(args.duration_s * 1e9));

  supervisor->stop();
  std::fprintf(stderr, "haptic-rt: stopped after %llu ticks, %llu overruns, %llu flight-recorder dumps\n",
               (unsigned long long)loop->ticks(), (unsigned long long)loop->overruns(),
               (unsigned long long)supervisor->flight_dumps());
  for (std::size_t i = 0; i < loop->device_count(); ++i) {
    const auto& q = loop->link_quality(i);
    std::fprintf(stderr, "haptic-rt: device \"%s\": link quality %.4f fresh (%llu/%llu ticks), longest miss run %u ticks\n",
                 loop->device_name(i), q.fresh_share(), (unsigned long long)q.fresh_ticks, (unsigned long long)q.ticks,
                 q.longest_miss_run);
  }
  g_loop = nullptr;
  return 0;
}
