// A message link puts protocol messages (hf_message) on a transport with one framing: classic
// CAN frame sets, one CAN FD frame, one 64-byte HID report, or one bulk packet per message. It
// is the only place that knows how messages map onto wire units (protocol.md, "Transports").
// send/receive are non-blocking and allocation-free.
#pragma once

#include <cstdint>
#include <memory>

#include "hapfluid/device/transport.hpp"
#include "hapfluid/wire/codec.h"

namespace hapfluid::device {

enum class Framing { can, canfd, hid, bulk };

// The most wire units one drain (a poll of the 1 kHz loop, a tick of the device) reads: 20 ms of
// a classic-CAN device's traffic (6 units per ms), so a loop that stalled catches up within a
// tick, while a flood of frames (valid, foreign or broken) cannot hold the thread; what is left
// waits for the next drain.
inline constexpr int kDrainUnitBudget = 128;
enum class Side { host, device };

// "can", "canfd", "hid", "bulk"; throws TransportError otherwise.
Framing parse_framing(const char* text);
const char* to_string(Framing);

class MessageLink {
 public:
  MessageLink(std::unique_ptr<Transport> transport, Framing framing, std::uint8_t node, Side side);

  // Encodes and sends; false when the message is not encodable (last_encode_result() says why)
  // or the transport refused a unit.
  bool send(const hf_message& message);
  // Io::ok: `out` holds the next valid message. Io::empty: nothing (more) pending, or
  // `unit_budget` (wire units this drain may still read, decremented per unit) is spent.
  // Io::error: the transport failed. Invalid units are counted in frames_bad() and skipped.
  Io receive(hf_message& out, int& unit_budget);

  Transport& transport() { return *transport_; }
  const Transport& transport() const { return *transport_; }
  Framing framing() const { return framing_; }
  std::uint8_t node() const { return node_; }
  std::uint64_t frames_bad() const { return frames_bad_; }
  int last_bad_result() const { return last_bad_result_; }
  int last_encode_result() const { return last_encode_result_; }
  // Sequence numbers on this framing wrap at this modulus (classic CAN carries 8 bits).
  std::uint32_t sequence_modulus() const { return framing_ == Framing::can ? 256u : 65536u; }

  // Fault injection for the fake device: the next `count` sent units get a flipped CRC bit.
  void corrupt_next(int count) { corrupt_ = count; }

 private:
  bool send_unit(WireFrame& frame);
  int decode(const WireFrame& frame, hf_message& out);

  std::unique_ptr<Transport> transport_;
  Framing framing_;
  std::uint8_t node_;
  Side side_;
  hf_can_assembler assembler_{};
  std::uint64_t frames_bad_ = 0;
  int last_bad_result_ = HF_OK;
  int last_encode_result_ = HF_OK;
  int corrupt_ = 0;
};

}  // namespace hapfluid::device
