// firmware_bridge_loopback_ping_pong: what the transport and codec themselves cost, without the
// 1 ms tick alignment that dominates the host -> device -> host round trip at 1 kHz. A device
// thread answers every COMMAND with a STATE echoing it, as fast as it can; the host side encodes,
// sends, waits (poll) and decodes. Per framing: round-trip p50/p99 in microseconds.
// Usage: firmware_bridge_loopback_ping_pong --out FILE.json [--iterations N]
#include <poll.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

#include "hapfluid/config/command_line.hpp"
#include "hapfluid/config/json_output.hpp"
#include "hapfluid/config/log.hpp"
#include "hapfluid/device/loopback.hpp"
#include "hapfluid/device/message_link.hpp"

using namespace hapfluid::device;

namespace {

namespace log = hapfluid::log;

std::uint64_t now_ns() {
  timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::uint64_t>(ts.tv_sec) * 1'000'000'000ull + static_cast<std::uint64_t>(ts.tv_nsec);
}

LoopbackFormat format_of(Framing f) {
  return f == Framing::hid ? LoopbackFormat::hid : f == Framing::bulk ? LoopbackFormat::bulk : LoopbackFormat::can;
}

bool wait(Transport& t, int ms) {
  pollfd p{t.poll_fd(), POLLIN, 0};
  return ::poll(&p, 1, ms) > 0;
}

std::vector<double> run(Framing framing, int iterations) {
  const std::string path = "/tmp/hapfluid-pingpong-" + std::to_string(::getpid()) + ".sock";
  MessageLink device(std::make_unique<LoopbackTransport>(path, LoopbackRole::bus, format_of(framing)), framing, 1,
                     Side::device);
  MessageLink host(std::make_unique<LoopbackTransport>(path, LoopbackRole::peer, format_of(framing)), framing, 1,
                   Side::host);
  std::atomic<bool> stop{false};
  std::thread echo([&] {
    hf_message m, state;
    std::memset(&state, 0, sizeof state);
    state.type = HF_MSG_STATE;
    state.body.state.orientation[0] = 1;
    while (!stop) {
      if (!wait(device.transport(), 50)) continue;
      for (int budget = kDrainUnitBudget; device.receive(m, budget) == Io::ok;) {
        if (m.type != HF_MSG_COMMAND) continue;
        state.body.state.command_echo = static_cast<std::uint8_t>(m.seq);
        state.seq = m.seq;
        device.send(state);
      }
    }
  });
  std::vector<double> rtt_us;
  rtt_us.reserve(static_cast<std::size_t>(iterations));
  hf_message command, reply;
  std::memset(&command, 0, sizeof command);
  command.type = HF_MSG_COMMAND;
  command.body.command.force_n[0] = 1.0;
  for (int i = 0; i < iterations + 100; ++i) {
    command.seq = static_cast<std::uint16_t>(i);
    const std::uint64_t t0 = now_ns();
    host.send(command);
    bool got = false;
    while (!got && wait(host.transport(), 100))
      for (int budget = kDrainUnitBudget; host.receive(reply, budget) == Io::ok;)
        got = got || (reply.type == HF_MSG_STATE && reply.body.state.command_echo == (i & 0xFF));
    if (got && i >= 100) rtt_us.push_back((now_ns() - t0) * 1e-3);  // the first 100 warm up
  }
  stop = true;
  echo.join();
  std::sort(rtt_us.begin(), rtt_us.end());
  return rtt_us;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Round trip of the transport and codec alone, per framing; JSON records to --out.",
               "firmware_bridge_loopback_ping_pong"};
  hapfluid::config::apply_convention(app);
  std::string out;
  int iterations = 20000;
  app.add_option("--out", out, "JSON records (a list) to this file")->required();
  app.add_option("--iterations", iterations, "round trips timed per framing")->check(CLI::Range(1, 100000000));
  if (const int code = hapfluid::config::parse_command_line(app, argc, argv); code >= 0) return code;
  std::vector<hapfluid::config::Json> records;
  for (Framing f : {Framing::can, Framing::canfd, Framing::hid, Framing::bulk}) {
    std::vector<double> r = run(f, iterations);
    // No sample (every reply lost): NaN, which the JSON writes null.
    auto pct = [&](double p) {
      return r.empty() ? std::nan("") : r[std::min(r.size() - 1, static_cast<std::size_t>(p * r.size()))];
    };
    log::info("loopback ping-pong %-5s p50 %.1f us, p99 %.1f us (%zu samples)", to_string(f), pct(0.5),
              pct(0.99), r.size());
    records.push_back(hapfluid::config::bench_record("firmware_bridge_loopback_ping_pong",
                                                     {{"framing", to_string(f)}, {"iterations", iterations}},
                                                     {{"rtt_p50_us", pct(0.5)}, {"rtt_p99_us", pct(0.99)},
                                                      {"samples", r.size()}}));
  }
  try {
    hapfluid::config::write_json_atomically(out, records);
  } catch (const std::exception& e) {
    log::error("%s", e.what());
    return 1;
  }
  return 0;
}
