// haptic-trace: drains haptic-rt's trace ring (/<prefix>.trace) to a CSV file (trace_csv.hpp)
// as a separate non-RT process. Stops when haptic-rt closes the ring or dies, on SIGINT/SIGTERM,
// or after --duration. Records it was too slow to read are counted, never waited for.
//   haptic-trace --out FILE [--shm-prefix NAME] [--duration S] [--wait S]   (--help, --version)
#include <signal.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <string>
#include <thread>

#include "hapfluid/config/command_line.hpp"
#include "hapfluid/config/log.hpp"
#include "hapfluid/rt/trace_csv.hpp"
#include "hapfluid/shm/channel.hpp"

using namespace hapfluid;

namespace {
std::atomic<bool> g_stop{false};
void on_signal(int) { g_stop.store(true); }
}  // namespace

int main(int argc, char** argv) {
  std::string out_path, prefix = "hapfluid";
  double duration_s = 0, wait_s = 10;
  CLI::App app{"Drains haptic-rt's trace ring to a CSV file, as a separate non-real-time process.", "haptic-trace"};
  config::apply_convention(app);
  app.add_option("--out", out_path, "the CSV file to write")->required();
  app.add_option("--shm-prefix", prefix, "the shared-memory prefix of the haptic-rt to follow")->capture_default_str();
  app.add_option("--duration", duration_s, "stop after this many seconds (0: when haptic-rt stops)")
      ->check(config::non_negative_number("seconds"))
      ->capture_default_str();
  app.add_option("--wait", wait_s, "seconds to wait for haptic-rt's trace ring to appear")
      ->check(config::non_negative_number("seconds"))
      ->capture_default_str();
  if (const int code = config::parse_command_line(app, argc, argv); code >= 0) return code;
  struct sigaction action {};
  action.sa_handler = on_signal;
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);

  const std::string name = shm::segment_name(prefix, shm::ChannelKind::trace);
  shm::RingAttachment ring;
  auto give_up = std::chrono::steady_clock::now() + std::chrono::duration<double>(wait_s);
  for (;;) {
    try {
      ring = shm::RingAttachment::attach(name, shm::ChannelKind::trace, sizeof(shm::TraceRecord));
      break;
    } catch (const shm::ShmError& e) {
      if (g_stop || std::chrono::steady_clock::now() > give_up) {
        log::error("%s", e.what());
        return 2;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
  }
  std::FILE* out = std::fopen(out_path.c_str(), "w");
  if (!out) {
    log::error("--out %s: cannot create the file", out_path.c_str());
    return 2;
  }
  rt::write_trace_header(out, shm::kMaxDevices);
  // Start at the oldest record still in the ring: haptic-trace may start after haptic-rt.
  shm::RingReader reader = ring.reader_from_oldest();
  std::uint64_t rows = 0;
  auto end = duration_s > 0 ? std::chrono::steady_clock::now() + std::chrono::duration<double>(duration_s)
                            : std::chrono::steady_clock::time_point::max();
  shm::TraceRecord record{};
  std::uint64_t last_check = 0;
  for (;;) {
    while (reader.next(record)) {
      rt::write_trace_row(out, record, shm::kMaxDevices);
      ++rows;
    }
    std::fflush(out);
    if (g_stop || std::chrono::steady_clock::now() > end) break;
    std::uint64_t now = shm::monotonic_ns();
    if (now - last_check > 200'000'000ull) {
      last_check = now;
      shm::WriterStatus s = ring.check_liveness(now, 0);
      if (s != shm::WriterStatus::live) {
        while (reader.next(record)) rt::write_trace_row(out, record, shm::kMaxDevices), ++rows;
        log::notice("trace ring %s", shm::to_string(s));
        break;
      }
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  std::fclose(out);
  log::info("wrote %llu records to %s, %llu lost (reader too slow)",
            (unsigned long long)rows, out_path.c_str(), (unsigned long long)reader.lost());
  return 0;
}
