// haptic-rt: the 1 kHz coupling process (rt_core/README.md).
//   haptic-rt --rig FILE [--duration S] [--simulated-devices] [--trace FILE]
//             [--flight-dir DIR] [--shm-prefix NAME]   (--help, --version)
// Signals: SIGINT/SIGTERM stop cleanly; SIGUSR1 latches the e-stop; SIGUSR2 resets it.
// Exit codes: 0 ok, 2 bad arguments/config/shm or a device that can never open as configured (one
// that is not there yet is waited for at a link fault), 3 refused by rt.policy = enforce.
#include <signal.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <string>

#include "hapfluid/config/command_line.hpp"
#include "hapfluid/config/errors.hpp"
#include "hapfluid/config/log.hpp"
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

struct Args {
  std::string rig, trace, flight_dir, prefix;
  double duration_s = 0;
  bool simulated = false;
};

}  // namespace

int main(int argc, char** argv) {
  Args args;
  CLI::App app{"The 1 kHz coupling process: devices, the safety layer and the sim's wrench (rt_core/README.md).",
               "haptic-rt"};
  config::apply_convention(app);
  app.add_option("--rig", args.rig, "the rig file (TOML)")->required();
  app.add_option("--duration", args.duration_s, "stop after this many seconds (0: until SIGINT/SIGTERM)")
      ->check(config::non_negative_number("seconds"))
      ->capture_default_str();
  app.add_flag("--simulated-devices", args.simulated, "use in-process simulated handles instead of the rig's transports");
  app.add_option("--trace", args.trace, "drain the trace ring to this CSV file from a non-real-time thread");
  app.add_option("--flight-dir", args.flight_dir, "where fault post-mortems go (default $TMPDIR/hapfluid-flight)");
  app.add_option("--shm-prefix", args.prefix, "the shared-memory prefix (default: the rig's rt.shm.prefix)");
  app.footer("Signals: SIGINT/SIGTERM stop cleanly; SIGUSR1 latches the e-stop; SIGUSR2 resets it.\n"
             "Exit codes: 0 ok, 2 bad arguments/config/shm or a device that can never open as configured, "
             "3 refused by rt.policy = enforce.");
  if (const int code = config::parse_command_line(app, argc, argv); code >= 0) return code;
  config::Rig rig;
  try {
    rig = config::load_rig(args.rig);
  } catch (const config::ConfigError& e) {
    log::error("%s", e.what());
    return 2;
  } catch (const std::exception& e) {
    log::error("%s", e.what());
    return 2;
  }
  if (!args.prefix.empty()) rig.rt.shm.prefix = args.prefix;
  if (args.flight_dir.empty()) {
    const char* tmp = std::getenv("TMPDIR");
    args.flight_dir = std::string(tmp && *tmp ? tmp : "/tmp") + "/hapfluid-flight";
  }

  log::info("rig \"%s\" (%s): period %lld ns, SCHED_FIFO %d, cpu %d, policy %s, shm /%s.*",
            rig.name.c_str(), args.rig.c_str(), (long long)rig.rt.period_ns, rig.rt.priority, rig.rt.cpu,
            config::to_string(rig.rt.policy), rig.rt.shm.prefix.c_str());
  std::vector<std::unique_ptr<device::Device>> devices;
  for (const auto& d : rig.devices) {
    log::info("device \"%s\": wrench_mode %s, safety limits:\n%s", d.name.c_str(), config::to_string(d.wrench_mode),
              safety::describe(safety::make_safety_config(d, rig.rt.period_ns)).c_str());
    std::string error;
    auto device = rt::open_rig_device(d, args.simulated ? rt::DeviceBackend::simulated : rt::DeviceBackend::driver, error);
    if (!device) {
      log::error("%s", error.c_str());
      return 2;
    }
    if (args.simulated) log::notice("device \"%s\": SIMULATED handle (no hardware)", d.name.c_str());
    else if (!device->health().connected)
      log::warning("%s; meanwhile the loop holds it at a link fault with zero wrench",
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
    log::error("%s", e.what());
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
    log::error("rt.policy = enforce and the real-time set-up failed; refusing to run:\n%s",
               report.messages.c_str());
    supervisor->stop();
    return 3;
  }
  if (report.degraded_flags & rt::kDegradedMask)
    log::warning("WARNING ************************************************************\n"
                 "WARNING running DEGRADED (rt.policy = ignore); every trace record is marked:\n%s"
                 "WARNING ************************************************************",
                 report.messages.c_str());
  else if (!report.messages.empty())
    log::notice("note: %s", report.messages.c_str());
  if (!(report.degraded_flags & rt::loop_no_affinity)) {
    int moved = rt::keep_other_threads_off_cpu(rig.rt.cpu);
    if (moved) log::info("%d helper thread(s) kept off the loop's CPU %d", moved, rig.rt.cpu);
  }
  rt::prefault_heap(8u << 20);
  rt::prefault_stack(256u << 10);
  loop->set_degraded_flags(report.degraded_flags);
  log::info("loop thread tid %ld running%s", (long)syscall(SYS_gettid),
            args.duration_s > 0 ? (" for " + std::to_string(args.duration_s) + " s").c_str() : "");

  loop->run(static_cast<std::uint64_t>(args.duration_s * 1e9));

  supervisor->stop();
  log::info("stopped after %llu ticks, %llu overruns, %llu flight-recorder dumps",
            (unsigned long long)loop->ticks(), (unsigned long long)loop->overruns(),
            (unsigned long long)supervisor->flight_dumps());
  for (std::size_t i = 0; i < loop->device_count(); ++i) {
    const auto& q = loop->link_quality(i);
    log::info("device \"%s\": link quality %.4f fresh (%llu/%llu ticks), longest miss run %u ticks%s",
              loop->device_name(i), q.fresh_share(), (unsigned long long)q.fresh_ticks, (unsigned long long)q.ticks,
              q.longest_miss_run,
              q.round_trips ? (", command round trip " + std::to_string(q.round_trip_ms) + " ms (longest " +
                               std::to_string(q.longest_round_trip_ms) + " ms)").c_str()
                            : "");
  }
  g_loop = nullptr;
  return 0;
}
