// Codec properties beyond the shared vectors: round trips keep every value within half a
// quantisation step (a bounded one, the wrench, within one step and never past it), encoding refuses what it cannot represent (never clips: a clipped force would
// hide a safety-layer bug), decoders reject damaged frames, and sequence gaps are counted.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>

#include "hapfluid/wire/codec.h"

namespace {

hf_message state_message(std::mt19937& rng) {
  std::uniform_real_distribution<double> pos(-0.65, 0.65), vel(-3.2, 3.2), ang(-32, 32), q(-1, 1);
  hf_message m;
  std::memset(&m, 0, sizeof m);
  m.type = HF_MSG_STATE;
  m.seq = static_cast<uint16_t>(rng());
  hf_state& s = m.body.state;
  s.device_time_us = static_cast<uint32_t>(rng());
  double n = 0;
  for (int i = 0; i < 4; ++i) { s.orientation[i] = q(rng); n += s.orientation[i] * s.orientation[i]; }
  for (int i = 0; i < 4; ++i) s.orientation[i] /= std::sqrt(n);
  for (int i = 0; i < 3; ++i) {
    s.position_m[i] = pos(rng);
    s.linear_velocity_m_s[i] = vel(rng);
    s.angular_velocity_rad_s[i] = ang(rng);
  }
  s.buttons = static_cast<uint8_t>(rng() & 0x3F);
  s.status = static_cast<uint8_t>(rng() & 0x3F);
  s.command_echo = static_cast<uint8_t>(rng());
  return m;
}

// q and -q are the same rotation; compare up to sign.
double quaternion_distance(const double* a, const double* b) {
  double plus = 0, minus = 0;
  for (int i = 0; i < 4; ++i) {
    plus = std::max(plus, std::fabs(a[i] - b[i]));
    minus = std::max(minus, std::fabs(a[i] + b[i]));
  }
  return std::min(plus, minus);
}

TEST(WireCodec, StateRoundTripIsWithinHalfAStepOnEveryFraming) {
  std::mt19937 rng(42);
  for (int trial = 0; trial < 2000; ++trial) {
    hf_message m = state_message(rng);
    uint8_t packet[64];
    int n = hf_encode_packet(&m, packet, sizeof packet);
    ASSERT_EQ(n, 38);
    hf_message got;
    ASSERT_EQ(hf_decode_packet(packet, static_cast<size_t>(n), &got), HF_OK);
    for (int i = 0; i < 3; ++i) {
      EXPECT_NEAR(got.body.state.position_m[i], m.body.state.position_m[i], 10e-6 + 1e-12);  // 20 um / 2
      EXPECT_NEAR(got.body.state.linear_velocity_m_s[i], m.body.state.linear_velocity_m_s[i], 0.5e-4 + 1e-12);
      EXPECT_NEAR(got.body.state.angular_velocity_rad_s[i], m.body.state.angular_velocity_rad_s[i], 0.5e-3 + 1e-12);
    }
    // smallest-three keeps every component within ~1e-4 (a rotation error below 0.02 degree)
    EXPECT_LT(quaternion_distance(got.body.state.orientation, m.body.state.orientation), 1e-4);
    EXPECT_EQ(got.body.state.buttons, m.body.state.buttons);
    EXPECT_EQ(got.body.state.device_time_us, m.body.state.device_time_us);

    hf_can_frame frames[HF_CAN_MAX_FRAMES];
    ASSERT_EQ(hf_can_encode(&m, 7, frames), 4);
    hf_can_assembler assembler;
    hf_can_assembler_init(&assembler, 7);
    hf_message classic;
    // frames may arrive in any order (several senders interleave on a bus)
    int order[4] = {2, 0, 3, 1};
    for (int k = 0; k < 4; ++k)
      ASSERT_EQ(hf_can_feed(&assembler, frames[order[k]].id, frames[order[k]].data, 8, &classic),
                k == 3 ? HF_OK : HF_ERR_INCOMPLETE);
    EXPECT_EQ(std::memcmp(classic.body.state.position_m, got.body.state.position_m, sizeof(double) * 3), 0);
  }
}

// The safety layer limits the wrench; the wire must not add to it. Rounding to the nearest mN
// could carry a force limited to 9.9995 N to 10.000 N, past the limit the layer enforced (and
// past the device's own norm limit, which would then saturate). So every component decodes at
// most as large as it was, and within one step of it.
TEST(WireCodec, CommandWrenchNeverDecodesLargerThanItWasEncoded) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> force(-32.7, 32.7), torque(-3.27, 3.27);
  for (int trial = 0; trial < 20000; ++trial) {
    hf_message m;
    std::memset(&m, 0, sizeof m);
    m.type = HF_MSG_COMMAND;
    for (int i = 0; i < 3; ++i) {
      m.body.command.force_n[i] = force(rng);
      m.body.command.torque_nm[i] = torque(rng);
    }
    if (trial < 3) {  // exact half steps, where rounding away from zero would go past
      m.body.command.force_n[trial] = 9.9995;
      m.body.command.torque_nm[trial] = -0.49995;
    }
    uint8_t packet[64];
    ASSERT_EQ(hf_encode_packet(&m, packet, sizeof packet), 20);
    hf_message got;
    ASSERT_EQ(hf_decode_packet(packet, 20, &got), HF_OK);
    for (int i = 0; i < 3; ++i) {
      const double f = m.body.command.force_n[i], g = got.body.command.force_n[i];
      EXPECT_LE(std::fabs(g), std::fabs(f)) << "force " << f << " N decoded as " << g << " N";
      EXPECT_LT(std::fabs(g - f), 1e-3) << "more than one 1 mN step off";
      const double t = m.body.command.torque_nm[i], u = got.body.command.torque_nm[i];
      EXPECT_LE(std::fabs(u), std::fabs(t)) << "torque " << t << " N*m decoded as " << u << " N*m";
      EXPECT_LT(std::fabs(u - t), 1e-4) << "more than one 0.1 mN*m step off";
    }
  }
}

// The host checks its rig limits against the device's INFO: a limit reported above the real
// one (9.996 N sent as 10.00 N) would let a rig ask for force the motors do not have.
TEST(WireCodec, InfoLimitsNeverDecodeAboveTheDevicesOwn) {
  hf_message m;
  std::memset(&m, 0, sizeof m);
  m.type = HF_MSG_INFO;
  m.body.info.protocol_version = 1;
  m.body.info.watchdog_ms = 20;
  m.body.info.max_force_n = 9.996;
  m.body.info.max_torque_nm = 0.4996;
  m.body.info.workspace_half_extent_m = 0.2996;
  uint8_t packet[64];
  ASSERT_EQ(hf_encode_packet(&m, packet, sizeof packet), 20);
  hf_message got;
  ASSERT_EQ(hf_decode_packet(packet, 20, &got), HF_OK);
  EXPECT_DOUBLE_EQ(got.body.info.max_force_n, 9.99);
  EXPECT_DOUBLE_EQ(got.body.info.max_torque_nm, 0.499);
  EXPECT_DOUBLE_EQ(got.body.info.workspace_half_extent_m, 0.299);
}

TEST(WireCodec, EncoderRefusesWhatItCannotRepresentAndWritesNothing) {
  hf_message m;
  std::memset(&m, 0, sizeof m);
  m.type = HF_MSG_COMMAND;
  uint8_t out[64];
  std::memset(out, 0xAA, sizeof out);
  m.body.command.force_n[1] = 32.7675;  // one half step above the 32.767 N full scale
  EXPECT_EQ(hf_encode_packet(&m, out, sizeof out), HF_ERR_RANGE);
  m.body.command.force_n[1] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(hf_encode_packet(&m, out, sizeof out), HF_ERR_RANGE);
  m.body.command.force_n[1] = -std::numeric_limits<double>::infinity();
  EXPECT_EQ(hf_encode_packet(&m, out, sizeof out), HF_ERR_RANGE);
  m.body.command.force_n[1] = 0;
  m.body.command.flags = 0x10;
  EXPECT_EQ(hf_encode_packet(&m, out, sizeof out), HF_ERR_RESERVED);
  for (uint8_t byte : out) EXPECT_EQ(byte, 0xAA) << "a refused message must leave the buffer untouched";

  m.body.command.flags = HF_CMD_ENABLE;
  EXPECT_EQ(hf_encode_packet(&m, out, 19), HF_ERR_BUFFER);
  EXPECT_EQ(hf_encode_packet(&m, out, 20), 20);

  hf_message s;
  std::memset(&s, 0, sizeof s);
  s.type = HF_MSG_STATE;
  s.body.state.orientation[0] = 0.5;  // not a unit quaternion: a kinematics bug, not a pose
  EXPECT_EQ(hf_encode_packet(&s, out, sizeof out), HF_ERR_RANGE);
  s.body.state.orientation[0] = 1;
  s.body.state.position_m[2] = 0.7;  // beyond the +-0.655 m workspace the format can carry
  EXPECT_EQ(hf_encode_packet(&s, out, sizeof out), HF_ERR_RANGE);
  m.type = 42;
  EXPECT_EQ(hf_encode_packet(&m, out, sizeof out), HF_ERR_TYPE);
}

TEST(WireCodec, EverySingleBitFlipOfAPacketIsRejected) {
  std::mt19937 rng(7);
  hf_message m = state_message(rng);
  uint8_t packet[64];
  int n = hf_encode_packet(&m, packet, sizeof packet);
  ASSERT_GT(n, 0);
  // CRC-16/CCITT detects every single-bit error; the version/type checks come first.
  for (int bit = 0; bit < n * 8; ++bit) {
    uint8_t damaged[64];
    std::memcpy(damaged, packet, static_cast<size_t>(n));
    damaged[bit / 8] ^= static_cast<uint8_t>(1u << (bit % 8));
    hf_message got;
    EXPECT_NE(hf_decode_packet(damaged, static_cast<size_t>(n), &got), HF_OK) << "bit " << bit;
  }
}

TEST(WireCodec, ClassicCommandWithAFrameFromAnotherSequenceIsNotApplied) {
  hf_message a, b;
  std::memset(&a, 0, sizeof a);
  a.type = HF_MSG_COMMAND;
  a.seq = 10;
  a.body.command.force_n[0] = 5;
  b = a;
  b.seq = 11;
  b.body.command.force_n[0] = -5;
  hf_can_frame fa[HF_CAN_MAX_FRAMES], fb[HF_CAN_MAX_FRAMES];
  ASSERT_EQ(hf_can_encode(&a, 2, fa), 2);
  ASSERT_EQ(hf_can_encode(&b, 2, fb), 2);
  hf_can_assembler assembler;
  hf_can_assembler_init(&assembler, 2);
  hf_message got;
  // force frame of seq 10 lost its torque frame; seq 11 arrives whole: only seq 11 is applied
  EXPECT_EQ(hf_can_feed(&assembler, fa[0].id, fa[0].data, 8, &got), HF_ERR_INCOMPLETE);
  EXPECT_EQ(hf_can_feed(&assembler, fb[0].id, fb[0].data, 8, &got), HF_ERR_INCOMPLETE);
  ASSERT_EQ(hf_can_feed(&assembler, fb[1].id, fb[1].data, 8, &got), HF_OK);
  EXPECT_EQ(got.seq, 11);
  EXPECT_EQ(got.body.command.force_n[0], -5.0);
  // a torque frame whose seq8 matches but whose bytes were altered fails the CRC-8
  fa[1].data[3] ^= 0x40;
  EXPECT_EQ(hf_can_feed(&assembler, fa[0].id, fa[0].data, 8, &got), HF_ERR_INCOMPLETE);
  EXPECT_EQ(hf_can_feed(&assembler, fa[1].id, fa[1].data, 8, &got), HF_ERR_CRC);
}

TEST(WireCodec, FramesOfOtherNodesAndOtherProtocolsAreIgnoredNotErrors) {
  hf_can_assembler assembler;
  hf_can_assembler_init(&assembler, 2);
  uint8_t data[8] = {0};
  hf_message got;
  EXPECT_EQ(hf_can_feed(&assembler, 0x53, data, 8, &got), HF_ERR_CAN_ID);   // node 3
  EXPECT_EQ(hf_can_feed(&assembler, 0x7E2, data, 8, &got), HF_ERR_CAN_ID);  // another protocol
  EXPECT_EQ(hf_canfd_decode(0x152, data, 8, 3, &got), HF_ERR_CAN_ID);
}

TEST(WireCodec, CanFdFrameWhoseIdDoesNotMatchItsPacketTypeIsRejected) {
  hf_message m;
  std::memset(&m, 0, sizeof m);
  m.type = HF_MSG_ESTOP;
  uint8_t packet[64] = {0};
  int n = hf_encode_packet(&m, packet, sizeof packet);
  ASSERT_EQ(n, 8);
  hf_message got;
  EXPECT_EQ(hf_canfd_decode(hf_canfd_id(HF_MSG_ESTOP, 4), packet, 8, 4, &got), HF_OK);
  // an e-stop packet arriving under the COMMAND id: a mis-wired sender; never act on it
  EXPECT_EQ(hf_canfd_decode(hf_canfd_id(HF_MSG_COMMAND, 4), packet, 8, 4, &got), HF_ERR_TYPE);
}

TEST(WireCodec, SequenceTrackerCountsGapsAndDuplicatesAcrossWrap) {
  hf_seq_tracker t;
  std::memset(&t, 0, sizeof t);
  EXPECT_EQ(hf_seq_accept(&t, 65534, 65536), 1);
  EXPECT_EQ(hf_seq_accept(&t, 65535, 65536), 1);
  EXPECT_EQ(hf_seq_accept(&t, 2, 65536), 1);  // 0 and 1 lost across the wrap
  EXPECT_EQ(t.gaps, 2u);
  EXPECT_EQ(hf_seq_accept(&t, 2, 65536), 0);  // repeated
  EXPECT_EQ(hf_seq_accept(&t, 1, 65536), 0);  // late
  EXPECT_EQ(t.duplicates, 2u);
  hf_seq_tracker c;
  std::memset(&c, 0, sizeof c);
  hf_seq_accept(&c, 250, 256);
  EXPECT_EQ(hf_seq_accept(&c, 4, 256), 1);  // classic CAN seq8: 251..255, 0..3 lost
  EXPECT_EQ(c.gaps, 9u);
}

TEST(WireCodec, ChecksumsMatchTheirPublishedCheckValues) {
  const uint8_t check[] = {'1', '2', '3', '4', '5', '6', '7', '8', '9'};
  EXPECT_EQ(hf_crc16(check, 9), 0x29B1);  // CRC-16/CCITT-FALSE catalogue check value
  EXPECT_EQ(hf_crc8(check, 9), 0x4B);     // CRC-8/SAE-J1850 catalogue check value
}

}  // namespace
