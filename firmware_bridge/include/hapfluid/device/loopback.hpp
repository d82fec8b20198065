// The loopback transport: a Unix SOCK_SEQPACKET socket carrying the exact wire bytes — `struct
// can_frame` (16 bytes) or `struct canfd_frame` (72 bytes) for CAN, 64-byte HID reports, bulk
// packets — so the real codec and drivers run end to end where the kernel has no CAN or USB.
//
// The device side binds and listens on the socket path and acts as the bus: every peer connects
// to it, each peer's frames are relayed to the other peers (so a monitor sees host traffic too)
// and its own frames go to all of them. Connections (not datagrams) because Linux limits an
// unconnected datagram queue to net.unix.max_dgram_qlen (often 10) frames, which a loaded machine
// overflows within milliseconds; connected sockets are bounded by their buffers instead.
#pragma once

#include <memory>
#include <string>

#include "hapfluid/device/transport.hpp"

namespace hapfluid::device {

enum class LoopbackRole { bus, peer };
enum class LoopbackFormat { can, hid, bulk };  // how datagrams map to WireFrame

class LoopbackTransport final : public Transport {
 public:
  // bus: binds `path` (replacing a stale socket file) and accepts peers. peer: connects to the
  // bus at `path`; while there is none (not started yet, or gone away) it reports kDisconnected
  // and connects by itself when the bus appears (tries at most every 100 ms).
  LoopbackTransport(const std::string& path, LoopbackRole role, LoopbackFormat format);
  ~LoopbackTransport() override;

  Io send(const WireFrame& frame) override;
  Io receive(WireFrame& frame) override;
  int poll_fd() const override { return role_ == LoopbackRole::bus ? epoll_fd_ : fd_; }
  std::uint32_t error_flags() const override { return errors_; }
  void clear_error_flags() override { errors_ = 0; }
  std::uint32_t reconnects() const override { return reconnects_; }
  std::string describe() const override;
  int peer_count() const { return peers_; }

 private:
  static constexpr int kMaxPeers = 8;
  void accept_peers();
  void drop_peer(int index);
  bool reconnect();
  std::size_t encode(const WireFrame& frame, std::uint8_t* bytes) const;
  bool decode(const std::uint8_t* bytes, std::size_t length, WireFrame& frame);

  std::string path_;
  LoopbackRole role_;
  LoopbackFormat format_;
  int fd_ = -1;        // bus: the listening socket; peer: the connection
  int epoll_fd_ = -1;  // bus: listening socket + peers, for poll_fd()
  std::uint32_t errors_ = 0;
  std::uint64_t next_reconnect_ns_ = 0;
  std::uint32_t reconnects_ = 0;
  int peer_fd_[kMaxPeers] = {};
  int peers_ = 0;
  int next_peer_ = 0;  // round robin, so one chatty peer cannot starve the others
};

}  // namespace hapfluid::device
