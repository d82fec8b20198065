// Framing of protocol messages onto wire units (protocol.md, "Transports").
#include "hapfluid/device/message_link.hpp"

#include <cstring>
#include <string>

#include "hapfluid/device/usb_transports.hpp"

namespace hapfluid::device {

Framing parse_framing(const char* text) {
  const std::string t = text;
  if (t == "can") return Framing::can;
  if (t == "canfd") return Framing::canfd;
  if (t == "hid") return Framing::hid;
  if (t == "bulk") return Framing::bulk;
  throw TransportError("framing '" + t + "' is not one of can, canfd, hid, bulk");
}

const char* to_string(Framing framing) {
  switch (framing) {
    case Framing::can: return "can";
    case Framing::canfd: return "canfd";
    case Framing::hid: return "hid";
    case Framing::bulk: return "bulk";
  }
  return "?";
}

MessageLink::MessageLink(std::unique_ptr<Transport> transport, Framing framing, std::uint8_t node, Side side)
    : transport_(std::move(transport)), framing_(framing), node_(node), side_(side) {
  if ((framing == Framing::can || framing == Framing::canfd) && (node < 1 || node > 15))
    throw TransportError("CAN node id " + std::to_string(node) + " is not in 1..15");
  hf_can_assembler_init(&assembler_, node);
}

bool MessageLink::send_unit(WireFrame& frame) {
  if (corrupt_ > 0) {
    --corrupt_;
    frame.data[frame.length - 1] ^= 0x01;  // the last byte is a CRC on every framing
  }
  return transport_->send(frame) == Io::ok;
}

bool MessageLink::send(const hf_message& message) {
  WireFrame frame;
  if (framing_ == Framing::can) {
    hf_can_frame frames[HF_CAN_MAX_FRAMES];
    int count = hf_can_encode(&message, node_, frames);
    last_encode_result_ = count < 0 ? count : HF_OK;
    if (count < 0) return false;
    bool ok = true;
    for (int k = 0; k < count; ++k) {
      frame.can_id = frames[k].id;
      frame.fd = false;
      frame.length = frames[k].dlc;
      std::memcpy(frame.data, frames[k].data, frames[k].dlc);
      // the CRC-8 sits in the last frame of STATE and COMMAND sets; other frames carry none
      if (k + 1 < count && corrupt_ > 0) {
        ok = transport_->send(frame) == Io::ok && ok;
        continue;
      }
      ok = send_unit(frame) && ok;
    }
    return ok;
  }
  std::uint8_t* packet = frame.data;
  std::size_t capacity = sizeof frame.data;
  if (framing_ == Framing::hid) {
    frame.data[0] = side_ == Side::host ? kHidReportHostToDevice : kHidReportDeviceToHost;
    packet = frame.data + 1;
    capacity -= 1;
  }
  int length = hf_encode_packet(&message, packet, capacity);
  last_encode_result_ = length < 0 ? length : HF_OK;
  if (length < 0) return false;
  switch (framing_) {
    case Framing::canfd:
      frame.can_id = hf_canfd_id(message.type, node_);
      frame.fd = true;
      frame.length = static_cast<std::uint8_t>(hf_canfd_padded_length(static_cast<std::size_t>(length)));
      break;
    case Framing::hid: frame.length = static_cast<std::uint8_t>(kHidReportBytes); break;
    default: frame.length = static_cast<std::uint8_t>(length); break;
  }
  if (corrupt_ > 0) {
    --corrupt_;
    packet[length - 1] ^= 0x01;  // flip a bit of the CRC-16, keep any padding intact
  }
  return transport_->send(frame) == Io::ok;
}

int MessageLink::decode(const WireFrame& frame, hf_message& out) {
  switch (framing_) {
    case Framing::can:
    case Framing::canfd:
      if (frame.fd) return hf_canfd_decode(frame.can_id, frame.data, frame.length, node_, &out);
      return hf_can_feed(&assembler_, frame.can_id, frame.data, frame.length, &out);
    case Framing::hid: {
      std::uint8_t expected = side_ == Side::host ? kHidReportDeviceToHost : kHidReportHostToDevice;
      if (frame.length < 1) return HF_ERR_SHORT;
      if (frame.data[0] != expected) return HF_ERR_TYPE;
      return hf_decode_packet(frame.data + 1, frame.length - 1u, &out);
    }
    case Framing::bulk: return hf_decode_packet(frame.data, frame.length, &out);
  }
  return HF_ERR_TYPE;
}

Io MessageLink::receive(hf_message& out, int& unit_budget) {
  while (unit_budget > 0) {
    --unit_budget;
    WireFrame frame;
    Io io = transport_->receive(frame);
    if (io != Io::ok) return io;
    int r = decode(frame, out);
    if (r == HF_OK) return Io::ok;
    if (r == HF_ERR_INCOMPLETE || r == HF_ERR_CAN_ID) continue;  // part of a set / someone else's frame
    ++frames_bad_;
    last_bad_result_ = r;
  }
  return Io::empty;
}

}  // namespace hapfluid::device
