// The C codec against the shared test vectors (firmware_bridge/test_vectors/vectors.json), which
// the Python codec also passes: host tools, firmware and the DBC must agree byte for byte, or a
// monitor would show a different force from the one the motors apply.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <string>

#include "hapfluid/wire/codec.h"
#include "json_mini.hpp"

namespace {

using json_mini::Value;

const Value& vectors() {
  static const Value v =
      json_mini::load(std::string(HAPFLUID_SOURCE_DIR) + "/firmware_bridge/test_vectors/vectors.json");
  return v;
}

int type_id(const std::string& name) {
  static const char* names[] = {"", "STATE", "COMMAND", "HOST_HEARTBEAT", "DEVICE_HEARTBEAT",
                                "INFO_REQUEST", "INFO", "FAULT", "ESTOP"};
  for (int i = 1; i <= 8; ++i)
    if (name == names[i]) return i;
  return 0;
}

int error_code(const std::string& name) {
  static const std::pair<const char*, int> codes[] = {
      {"SHORT", HF_ERR_SHORT}, {"LENGTH", HF_ERR_LENGTH}, {"VERSION", HF_ERR_VERSION},
      {"TYPE", HF_ERR_TYPE}, {"CRC", HF_ERR_CRC}, {"RANGE", HF_ERR_RANGE},
      {"RESERVED", HF_ERR_RESERVED}, {"CAN_ID", HF_ERR_CAN_ID}};
  for (auto& [n, c] : codes)
    if (name == n) return c;
  return 1;
}

void arr(const Value& v, double* out, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) out[i] = v[i].num;
}

hf_message from_json(const Value& m) {
  hf_message msg;
  std::memset(&msg, 0, sizeof msg);
  msg.type = static_cast<uint8_t>(type_id(m["type"].str));
  msg.seq = static_cast<uint16_t>(m["seq"].num);
  const Value& f = m["fields"];
  switch (msg.type) {
    case HF_MSG_STATE: {
      hf_state& s = msg.body.state;
      s.device_time_us = static_cast<uint32_t>(f["device_time_us"].num);
      arr(f["position_m"], s.position_m, 3);
      arr(f["orientation"], s.orientation, 4);
      arr(f["linear_velocity_m_s"], s.linear_velocity_m_s, 3);
      arr(f["angular_velocity_rad_s"], s.angular_velocity_rad_s, 3);
      s.command_echo = static_cast<uint8_t>(f["command_echo"].num);
      s.buttons = static_cast<uint8_t>(f["buttons"].num);
      s.status = static_cast<uint8_t>(f["status"].num);
      s.fault = static_cast<uint8_t>(f["fault"].num);
      break;
    }
    case HF_MSG_COMMAND:
      arr(f["force_n"], msg.body.command.force_n, 3);
      arr(f["torque_nm"], msg.body.command.torque_nm, 3);
      msg.body.command.flags = static_cast<uint8_t>(f["flags"].num);
      break;
    case HF_MSG_HOST_HEARTBEAT:
    case HF_MSG_DEVICE_HEARTBEAT:
      msg.body.heartbeat.uptime_ms = static_cast<uint32_t>(f["uptime_ms"].num);
      msg.body.heartbeat.status = static_cast<uint8_t>(f["status"].num);
      break;
    case HF_MSG_INFO: {
      hf_info& n = msg.body.info;
      n.vendor_id = static_cast<uint16_t>(f["vendor_id"].num);
      n.product_id = static_cast<uint16_t>(f["product_id"].num);
      n.firmware_version = static_cast<uint16_t>(f["firmware_version"].num);
      n.protocol_version = static_cast<uint8_t>(f["protocol_version"].num);
      n.watchdog_ms = static_cast<uint8_t>(f["watchdog_ms"].num);
      n.max_force_n = f["max_force_n"].num;
      n.max_torque_nm = f["max_torque_nm"].num;
      n.workspace_half_extent_m = f["workspace_half_extent_m"].num;
      break;
    }
    case HF_MSG_FAULT:
      msg.body.fault.faults = static_cast<uint8_t>(f["faults"].num);
      msg.body.fault.cause = static_cast<uint8_t>(f["cause"].num);
      msg.body.fault.detail = static_cast<uint32_t>(f["detail"].num);
      break;
    case HF_MSG_ESTOP: msg.body.estop.reason = static_cast<uint8_t>(f["reason"].num); break;
    default: break;
  }
  return msg;
}

// Decoded values must equal the vector's "decoded" fields exactly: both codecs perform the same
// IEEE operations. `classic` drops what classic CAN does not carry (device time, fault byte).
void expect_decoded(const hf_message& got, const Value& want, const std::string& name, bool classic) {
  SCOPED_TRACE(name);
  auto same3 = [](const double* a, const Value& b, std::size_t n) {
    for (std::size_t i = 0; i < n; ++i) EXPECT_EQ(a[i], b[i].num) << "index " << i;
  };
  switch (got.type) {
    case HF_MSG_STATE: {
      const hf_state& s = got.body.state;
      EXPECT_EQ(s.device_time_us, classic ? 0u : static_cast<uint32_t>(want["device_time_us"].num));
      same3(s.position_m, want["position_m"], 3);
      same3(s.orientation, want["orientation"], 4);
      same3(s.linear_velocity_m_s, want["linear_velocity_m_s"], 3);
      same3(s.angular_velocity_rad_s, want["angular_velocity_rad_s"], 3);
      EXPECT_EQ(s.command_echo, want["command_echo"].num);
      EXPECT_EQ(s.buttons, want["buttons"].num);
      EXPECT_EQ(s.status, want["status"].num);
      EXPECT_EQ(s.fault, classic ? 0 : want["fault"].num);
      break;
    }
    case HF_MSG_COMMAND:
      same3(got.body.command.force_n, want["force_n"], 3);
      same3(got.body.command.torque_nm, want["torque_nm"], 3);
      EXPECT_EQ(got.body.command.flags, want["flags"].num);
      break;
    case HF_MSG_INFO:
      EXPECT_EQ(got.body.info.vendor_id, want["vendor_id"].num);
      EXPECT_EQ(got.body.info.watchdog_ms, want["watchdog_ms"].num);
      EXPECT_EQ(got.body.info.max_force_n, want["max_force_n"].num);
      EXPECT_EQ(got.body.info.max_torque_nm, want["max_torque_nm"].num);
      EXPECT_EQ(got.body.info.workspace_half_extent_m, want["workspace_half_extent_m"].num);
      break;
    case HF_MSG_FAULT:
      EXPECT_EQ(got.body.fault.faults, want["faults"].num);
      EXPECT_EQ(got.body.fault.cause, want["cause"].num);
      EXPECT_EQ(got.body.fault.detail, want["detail"].num);
      break;
    case HF_MSG_HOST_HEARTBEAT:
    case HF_MSG_DEVICE_HEARTBEAT:
      EXPECT_EQ(got.body.heartbeat.uptime_ms, want["uptime_ms"].num);
      EXPECT_EQ(got.body.heartbeat.status, want["status"].num);
      break;
    case HF_MSG_ESTOP: EXPECT_EQ(got.body.estop.reason, want["reason"].num); break;
    default: break;
  }
}

TEST(WireVectors, PacketEncodingMatchesTheSharedBytes) {
  for (const Value& v : vectors()["valid"].items) {
    hf_message msg = from_json(v["message"]);
    uint8_t out[64];
    int n = hf_encode_packet(&msg, out, sizeof out);
    ASSERT_GT(n, 0) << v["name"].str << ": " << hf_result_name(n);
    EXPECT_EQ(std::vector<unsigned char>(out, out + n), json_mini::hex(v["packet"].str)) << v["name"].str;
  }
}

TEST(WireVectors, PacketDecodingGivesTheSharedValues) {
  for (const Value& v : vectors()["valid"].items) {
    auto bytes = json_mini::hex(v["packet"].str);
    hf_message got;
    ASSERT_EQ(hf_decode_packet(bytes.data(), bytes.size(), &got), HF_OK) << v["name"].str;
    EXPECT_EQ(got.type, type_id(v["message"]["type"].str));
    EXPECT_EQ(got.seq, v["message"]["seq"].num);
    expect_decoded(got, v["decoded"], v["name"].str, false);
  }
}

TEST(WireVectors, CanFdFrameIsThePaddedPacketUnderTheTypesId) {
  for (const Value& v : vectors()["valid"].items) {
    hf_message msg = from_json(v["message"]);
    uint8_t node = static_cast<uint8_t>(v["node"].num);
    auto data = json_mini::hex(v["canfd"]["data"].str);
    EXPECT_EQ(hf_canfd_id(msg.type, node), v["canfd"]["id"].num) << v["name"].str;
    EXPECT_EQ(hf_canfd_padded_length(hf_packet_length(msg.type)), data.size()) << v["name"].str;
    hf_message got;
    ASSERT_EQ(hf_canfd_decode(static_cast<uint32_t>(v["canfd"]["id"].num), data.data(), data.size(), node, &got),
              HF_OK) << v["name"].str;
    expect_decoded(got, v["decoded"], v["name"].str, false);
  }
}

TEST(WireVectors, ClassicCanFramesMatchAndReassemble) {
  for (const Value& v : vectors()["valid"].items) {
    hf_message msg = from_json(v["message"]);
    uint8_t node = static_cast<uint8_t>(v["node"].num);
    hf_can_frame frames[HF_CAN_MAX_FRAMES];
    int n = hf_can_encode(&msg, node, frames);
    const Value& want = v["can"];
    ASSERT_EQ(n, static_cast<int>(want.size())) << v["name"].str;
    hf_can_assembler assembler;
    hf_can_assembler_init(&assembler, node);
    hf_message got;
    for (int k = 0; k < n; ++k) {
      EXPECT_EQ(frames[k].id, want[k]["id"].num) << v["name"].str << " frame " << k;
      EXPECT_EQ(std::vector<unsigned char>(frames[k].data, frames[k].data + frames[k].dlc),
                json_mini::hex(want[k]["data"].str)) << v["name"].str << " frame " << k;
      int r = hf_can_feed(&assembler, frames[k].id, frames[k].data, frames[k].dlc, &got);
      EXPECT_EQ(r, k + 1 < n ? HF_ERR_INCOMPLETE : HF_OK) << v["name"].str << " frame " << k;
    }
    EXPECT_EQ(got.seq, static_cast<uint16_t>(v["message"]["seq"].num) & 0xFF);
    expect_decoded(got, v["decoded"], v["name"].str, true);
  }
}

TEST(WireVectors, EveryMalformedPacketIsRejectedForItsReason) {
  for (const Value& v : vectors()["malformed_packets"].items) {
    auto bytes = json_mini::hex(v["bytes"].str);
    hf_message got;
    EXPECT_EQ(hf_decode_packet(bytes.data(), bytes.size(), &got), error_code(v["error"].str))
        << v["name"].str;
  }
}

TEST(WireVectors, EveryMalformedClassicFrameSetIsRejectedForItsReason) {
  for (const Value& v : vectors()["malformed_can"].items) {
    hf_can_assembler assembler;
    hf_can_assembler_init(&assembler, static_cast<uint8_t>(v["node"].num));
    hf_message got;
    int r = HF_OK;
    for (const Value& f : v["frames"].items) {
      auto data = json_mini::hex(f["data"].str);
      r = hf_can_feed(&assembler, static_cast<uint32_t>(f["id"].num), data.data(),
                      static_cast<uint8_t>(data.size()), &got);
    }
    EXPECT_EQ(r, error_code(v["error"].str)) << v["name"].str;
  }
}

}  // namespace
