// haptic-status: what a running stack is doing, read-only (stack_observer.hpp), as one JSON
// object per line on stdout at --rate Hz: the loop's wake latency, overruns and deadline misses,
// every device's link, faults, engage state and wrenches, the sim's rate and sample age. It maps
// every segment read-only and writes nothing anywhere but stdout; haptic-dashboard serves it.
//   haptic-status [--shm-prefix NAME] [--rate HZ] [--duration S] [--once] [--trust-user NAME]
#include <pwd.h>
#include <signal.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <string>
#include <thread>

#include "hapfluid/config/command_line.hpp"
#include "hapfluid/rt/stack_observer.hpp"

using namespace hapfluid;

namespace {
std::atomic<bool> g_stop{false};
void on_signal(int) { g_stop.store(true); }
}  // namespace

int main(int argc, char** argv) {
  std::string prefix = "hapfluid";
  double rate_hz = 30, duration_s = 0;
  bool once = false;
  std::string trust_user;
  CLI::App app{"Prints what a running hapfluid stack is doing, read-only, as one JSON object per line.",
               "haptic-status"};
  config::apply_convention(app);
  app.add_option("--shm-prefix", prefix, "the shared-memory prefix of the stack to watch")->capture_default_str();
  app.add_option("--rate", rate_hz, "lines per second (at most 30: an operator's view, not a trace)")
      ->check(CLI::Range(0.1, 30.0))
      ->capture_default_str();
  app.add_option("--duration", duration_s, "stop after this many seconds (0: on SIGINT/SIGTERM or a closed stdout)")
      ->check(config::non_negative_number("seconds"))
      ->capture_default_str();
  app.add_flag("--once", once, "print one line after a first look (a tenth of a second) and exit");
  app.add_option("--trust-user", trust_user,
                 "also trust segments of this user (the services' user, when this runs as a user of its own)");
  if (const int code = config::parse_command_line(app, argc, argv); code >= 0) return code;
  if (!trust_user.empty()) {
    const passwd* user = ::getpwnam(trust_user.c_str());
    if (!user) {
      std::fprintf(stderr, "haptic-status: --trust-user %s: no such user\n", trust_user.c_str());
      return 2;
    }
    shm::trust_writer_uid(user->pw_uid);
  }
  struct sigaction action {};
  action.sa_handler = on_signal;
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
  signal(SIGPIPE, SIG_IGN);  // a reader that went away ends the run through the failed write

  rt::StackObserver observer(prefix);
  const auto period = std::chrono::duration<double>(1.0 / rate_hz);
  const auto start = std::chrono::steady_clock::now();
  auto next = start;
  if (once) {
    observer.poll(shm::monotonic_ns());
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  while (!g_stop.load()) {
    const std::uint64_t now = shm::monotonic_ns();
    observer.poll(now);
    const std::string line = observer.snapshot_json(now) + "\n";
    if (std::fwrite(line.data(), 1, line.size(), stdout) != line.size() || std::fflush(stdout) != 0) break;
    if (once) break;
    next += std::chrono::duration_cast<std::chrono::steady_clock::duration>(period);
    if (duration_s > 0 && next - start > std::chrono::duration<double>(duration_s)) break;
    std::this_thread::sleep_until(next);
  }
  return 0;
}
