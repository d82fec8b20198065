// Fuzz target: the host side of a haptic arm (HapticArm on a MessageLink on the real loopback
// transport) fed whatever a broken or hostile device puts on the wire, on one framing
// (FUZZ_FRAMING: can, canfd, hid or bulk; built once per framing). The harness is the bus end of
// the loopback socket and sends the input's datagrams byte for byte, so the transport's decoding
// of units (struct can_frame / canfd_frame, error frames, HID reports, bulk packets) is fuzzed
// with the framing and the driver above it. The input is a list of operations:
//   op % 4 == 0: a datagram: [length u8][length bytes] (length 0 is sent as 1: an empty datagram
//                reads as the bus closing, and what follows depends on a reconnect timer)
//   op % 4 == 1: arm.poll()
//   op % 4 == 2: arm.send() a zero command (op bits 2-4: enable, estop, clear_faults)
//   op % 4 == 3: one 1 kHz tick: poll, then send a disabled zero command
// then the arm polls until the link is drained. Every input gets a fresh driver (framing state,
// sequence tracking, echo accounting) over the same connection, so no socket is made per input.
// Properties: every state the driver reports is finite, and it never counts more valid messages
// and bad units than datagrams it was sent.
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>

#include "fuzz_target.h"
#include "hapfluid/device/haptic_arm.hpp"
#include "hapfluid/device/loopback.hpp"

using namespace hapfluid;
using device::Framing;

namespace {

constexpr Framing kFraming = device::Framing::FUZZ_FRAMING;
constexpr std::uint8_t kNode = 3;

device::LoopbackFormat format_of(Framing f) {
  return f == Framing::hid    ? device::LoopbackFormat::hid
         : f == Framing::bulk ? device::LoopbackFormat::bulk
                              : device::LoopbackFormat::can;
}

// Lends the one long-lived transport to each input's MessageLink (which owns its transport).
class Borrowed final : public device::Transport {
 public:
  explicit Borrowed(device::Transport& t) : t_(t) {}
  device::Io send(const device::WireFrame& f) override { return t_.send(f); }
  device::Io receive(device::WireFrame& f) override { return t_.receive(f); }
  int poll_fd() const override { return t_.poll_fd(); }
  std::uint32_t error_flags() const override { return t_.error_flags(); }
  void clear_error_flags() override { t_.clear_error_flags(); }
  std::uint32_t reconnects() const override { return t_.reconnects(); }
  std::string describe() const override { return t_.describe(); }

 private:
  device::Transport& t_;
};

void fail(const char* what) {
  std::perror(what);
  std::exit(1);
}

// The bus end (a plain SOCK_SEQPACKET listener, so any bytes can be sent) and the host's
// transport connected to it, for the whole run.
struct Bus {
  std::string path = "/tmp/hapfluid-fuzz-arm-" + std::to_string(::getpid()) + ".sock";
  int listener = -1;
  int connection = -1;
  std::unique_ptr<device::LoopbackTransport> host;
  std::uint32_t reconnects = 0;

  Bus() {
    listener = ::socket(AF_UNIX, SOCK_SEQPACKET | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
    sockaddr_un address{};
    address.sun_family = AF_UNIX;
    std::snprintf(address.sun_path, sizeof address.sun_path, "%s", path.c_str());
    ::unlink(path.c_str());
    if (listener < 0 || ::bind(listener, reinterpret_cast<const sockaddr*>(&address), sizeof address) != 0 ||
        ::listen(listener, 4) != 0)
      fail("fuzz: loopback bus");
    host = std::make_unique<device::LoopbackTransport>(path, device::LoopbackRole::peer, format_of(kFraming));
    accept_host();
  }
  ~Bus() {
    host.reset();
    ::close(connection);
    ::close(listener);
    ::unlink(path.c_str());
  }
  void accept_host() {
    const int fd = ::accept4(listener, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC);
    if (fd < 0) fail("fuzz: accepting the host's connection");
    int buffer = 1 << 20;
    ::setsockopt(fd, SOL_SOCKET, SO_SNDBUF, &buffer, sizeof buffer);
    if (connection >= 0) ::close(connection);
    connection = fd;
  }
  // Between inputs: the same connection, no error flags, nothing queued either way.
  void reset() {
    if (host->reconnects() != reconnects) {
      reconnects = host->reconnects();
      accept_host();
    }
    host->clear_error_flags();
    discard_sent();
    device::WireFrame frame;
    for (int i = 0; i < 4096 && host->receive(frame) == device::Io::ok; ++i) {
    }
  }
  // What the host sent (commands, heartbeats): read so that its sends never fill the socket.
  void discard_sent() const {
    std::uint8_t sink[128];
    while (::recv(connection, sink, sizeof sink, MSG_DONTWAIT) >= 0) {
    }
  }
  bool send(const std::uint8_t* bytes, std::size_t length) const {
    return ::send(connection, bytes, length, MSG_DONTWAIT | MSG_NOSIGNAL) == static_cast<ssize_t>(length);
  }
};

void check_state(const device::DeviceState& s) {
  for (double v : s.position_m)
    if (!std::isfinite(v)) hapfluid_fuzz_violated("a non-finite position");
  for (double v : s.orientation)
    if (!std::isfinite(v)) hapfluid_fuzz_violated("a non-finite orientation");
  for (double v : s.linear_velocity_m_s)
    if (!std::isfinite(v)) hapfluid_fuzz_violated("a non-finite linear velocity");
  for (double v : s.angular_velocity_rad_s)
    if (!std::isfinite(v)) hapfluid_fuzz_violated("a non-finite angular velocity");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static Bus bus;
  bus.reset();
  device::HapticArm arm("fuzz",
                        std::make_unique<device::MessageLink>(std::make_unique<Borrowed>(*bus.host), kFraming, kNode,
                                                              device::Side::host),
                        0);
  device::DeviceState state;
  std::uint64_t datagrams = 0;
  auto poll = [&] {
    if (arm.poll(state)) check_state(state);
  };
  for (std::size_t at = 0; at < size;) {
    const std::uint8_t op = data[at++];
    switch (op % 4) {
      case 0: {
        if (at >= size) break;
        std::size_t length = data[at++];
        if (length > size - at) length = size - at;
        const std::uint8_t empty_stand_in = 0;
        const bool sent = length > 0 ? bus.send(data + at, length) : bus.send(&empty_stand_in, 1);
        if (sent) ++datagrams;
        at += length;
        break;
      }
      case 1: poll(); break;
      case 2: {
        device::DeviceCommand command;
        command.enable = op & 4;
        command.estop = op & 8;
        command.clear_faults = op & 16;
        arm.send(command);
        bus.discard_sent();
        break;
      }
      case 3:
        poll();
        arm.send(device::DeviceCommand{});
        bus.discard_sent();
        break;
    }
  }
  // A poll reads at most kDrainUnitBudget units: poll until one ends with the link empty.
  for (std::uint64_t drain = 0;; ++drain) {
    const std::uint64_t cut_short = arm.health().drains_cut_short;
    poll();
    if (arm.health().drains_cut_short == cut_short) break;
    if (drain > datagrams / device::kDrainUnitBudget + 1) hapfluid_fuzz_violated("the link does not drain");
  }
  const device::DeviceHealth health = arm.health();
  if (health.frames_ok + health.frames_bad > datagrams)
    hapfluid_fuzz_violated("more valid messages and bad units counted than datagrams sent");
  if (health.frames_ok + health.foreign_commands > 0) ++hapfluid_fuzz_accepted;
  return 0;
}
