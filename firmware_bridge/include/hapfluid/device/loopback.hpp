// The loopback transport: a Unix datagram socket carrying the exact wire bytes — `struct
// can_frame` (16 bytes) or `struct canfd_frame` (72 bytes) for CAN, 64-byte HID reports, bulk
// packets — so the real codec and drivers run end to end where the kernel has no CAN or USB.
//
// The device side binds the socket path and acts as the bus: it registers every peer that sends
// to it (a zero-length datagram registers without sending anything), relays each peer's frames to
// the other peers (so a monitor sees host traffic too) and sends its own frames to all of them.
#pragma once

#include <sys/un.h>

#include <memory>
#include <string>

#include "hapfluid/device/transport.hpp"

namespace hapfluid::device {

enum class LoopbackRole { bus, peer };
enum class LoopbackFormat { can, hid, bulk };  // how datagrams map to WireFrame

class LoopbackTransport final : public Transport {
 public:
  // bus: binds `path` (replacing a stale socket file). peer: an abstract autobound socket that
  // registers with the bus at `path`; every datagram it sends registers it again, so a
  // restarted bus learns about it from the next frame.
  LoopbackTransport(const std::string& path, LoopbackRole role, LoopbackFormat format);
  ~LoopbackTransport() override;

  Io send(const WireFrame& frame) override;
  Io receive(WireFrame& frame) override;
  int poll_fd() const override { return fd_; }
  std::uint32_t error_flags() const override { return errors_; }
  void clear_error_flags() override { errors_ = 0; }
  std::string describe() const override;
  int peer_count() const { return peers_; }

 private:
  static constexpr int kMaxPeers = 8;
  bool send_bytes(const void* bytes, std::size_t length, const sockaddr_un& to, socklen_t to_length);
  void relay(const std::uint8_t* bytes, std::size_t length, const sockaddr_un& from, socklen_t from_length);
  void add_peer(const sockaddr_un& address, socklen_t length);
  void drop_peer(int index);

  std::string path_;
  LoopbackRole role_;
  LoopbackFormat format_;
  int fd_ = -1;
  std::uint32_t errors_ = 0;
  sockaddr_un bus_address_{};
  socklen_t bus_length_ = 0;
  sockaddr_un peer_address_[kMaxPeers]{};
  socklen_t peer_length_[kMaxPeers]{};
  int peers_ = 0;
};

}  // namespace hapfluid::device
