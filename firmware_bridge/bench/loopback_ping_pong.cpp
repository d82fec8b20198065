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
#include <cstdio>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

#include "hapfluid/device/loopback.hpp"
#include "hapfluid/device/message_link.hpp"

using namespace hapfluid::device;

namespace {

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
  std::string out;
  int iterations = 20000;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (std::string(argv[i]) == "--out") out = argv[i + 1];
    else if (std::string(argv[i]) == "--iterations") iterations = std::atoi(argv[i + 1]);
  }
  if (out.empty()) {
    std::fprintf(stderr, "usage: %s --out FILE.json [--iterations N]\n", argv[0]);
    return 2;
  }
  std::string json = "[";
  for (Framing f : {Framing::can, Framing::canfd, Framing::hid, Framing::bulk}) {
    std::vector<double> r = run(f, iterations);
    auto pct = [&](double p) { return r.empty() ? -1.0 : r[std::min(r.size() - 1, static_cast<std::size_t>(p * r.size()))]; };
    std::fprintf(stderr, "loopback ping-pong %-5s p50 %.1f us, p99 %.1f us (%zu samples)\n", to_string(f), pct(0.5),
                 pct(0.99), r.size());
    char record[512];
    std::snprintf(record, sizeof record,
                  "%s{\"bench\": \"firmware_bridge_loopback_ping_pong\", \"params\": {\"framing\": \"%s\", "
                  "\"iterations\": %d}, \"metrics\": {\"rtt_p50_us\": %.2f, \"rtt_p99_us\": %.2f, \"samples\": %zu}}",
                  json.size() > 1 ? ", " : "", to_string(f), iterations, pct(0.5), pct(0.99), r.size());
    json += record;
  }
  json += "]\n";
  FILE* f = std::fopen(out.c_str(), "w");
  if (!f) {
    std::perror(out.c_str());
    return 1;
  }
  std::fputs(json.c_str(), f);
  std::fclose(f);
  return 0;
}
