/* Deterministic random-input driver for the decoders (a ctest of the normal build; make fuzz
 * runs the libFuzzer targets of wire_decoders.c): random bytes, and valid packets and frame sets
 * with random bit flips, truncations and extensions, so inputs reach past the CRC check.
 * Usage: random_inputs [iterations] */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "hapfluid/wire/codec.h"

int hf_fuzz_packet(const uint8_t* data, size_t size);
int hf_fuzz_canfd(const uint8_t* data, size_t size);
int hf_fuzz_can(const uint8_t* data, size_t size);

static uint64_t rng = 0x9E3779B97F4A7C15ull;
static uint32_t next(void) {
  rng ^= rng << 13; rng ^= rng >> 7; rng ^= rng << 17;
  return (uint32_t)(rng >> 11);
}
static double uniform(double lo, double hi) { return lo + (hi - lo) * (next() / 4294967296.0); }

/* A valid random message of every type, so mutations start from a correct CRC. */
static hf_message random_message(void) {
  hf_message m;
  memset(&m, 0, sizeof m);
  m.type = (uint8_t)(1 + next() % 8);
  m.seq = (uint16_t)next();
  if (m.type == HF_MSG_STATE) {
    for (int i = 0; i < 3; ++i) {
      m.body.state.position_m[i] = uniform(-0.6, 0.6);
      m.body.state.linear_velocity_m_s[i] = uniform(-3, 3);
      m.body.state.angular_velocity_rad_s[i] = uniform(-30, 30);
    }
    double q[4], n = 0;
    for (int i = 0; i < 4; ++i) { q[i] = uniform(-1, 1); n += q[i] * q[i]; }
    if (n < 1e-3) q[0] = n = 1;
    double s = 1, x = n; /* crude normalisation is enough: the encoder accepts |q|^2 within 1% */
    for (int k = 0; k < 40; ++k) s = 0.5 * (s + x / s);
    for (int i = 0; i < 4; ++i) m.body.state.orientation[i] = q[i] / s;
    m.body.state.buttons = (uint8_t)(next() & 0x3F);
  } else if (m.type == HF_MSG_COMMAND) {
    for (int i = 0; i < 3; ++i) {
      m.body.command.force_n[i] = uniform(-30, 30);
      m.body.command.torque_nm[i] = uniform(-3, 3);
    }
    m.body.command.flags = (uint8_t)(next() & 7);
  } else if (m.type == HF_MSG_INFO) {
    m.body.info.protocol_version = 1;
    m.body.info.watchdog_ms = 20;
    m.body.info.max_force_n = 10;
  }
  return m;
}

int main(int argc, char** argv) {
  long iterations = argc > 1 ? atol(argv[1]) : 1000000;
  uint8_t buf[96];
  for (long it = 0; it < iterations; ++it) {
    size_t n;
    if (it % 4 == 0) {
      n = next() % sizeof buf;
      for (size_t i = 0; i < n; ++i) buf[i] = (uint8_t)next();
    } else {
      hf_message m = random_message();
      int r = hf_encode_packet(&m, buf + 3, sizeof buf - 3);
      if (r <= 0) { fprintf(stderr, "random message %d did not encode: %s\n", m.type, hf_result_name(r)); return 1; }
      n = (size_t)r + 3;
      uint32_t id = hf_canfd_id(m.type, 3);
      buf[0] = (uint8_t)id; buf[1] = (uint8_t)(id >> 8); buf[2] = 3;
      int flips = (int)(next() % 3);
      for (int f = 0; f < flips; ++f) buf[next() % n] ^= (uint8_t)(1u << (next() % 8));
      if (next() % 8 == 0) n = next() % n;
    }
    hf_fuzz_packet(buf + 3, n > 3 ? n - 3 : 0);
    hf_fuzz_canfd(buf, n);
    /* classic: encode a message into frames, serialise them, mutate, feed */
    hf_message m = random_message();
    hf_can_frame frames[HF_CAN_MAX_FRAMES];
    int count = hf_can_encode(&m, 3, frames);
    size_t at = 0;
    for (int k = 0; k < count && at + 11 <= sizeof buf; ++k, at += 11) {
      buf[at] = (uint8_t)frames[k].id; buf[at + 1] = (uint8_t)(frames[k].id >> 8); buf[at + 2] = frames[k].dlc;
      memcpy(buf + at + 3, frames[k].data, 8);
    }
    if (next() % 2) buf[next() % (at ? at : 1)] ^= (uint8_t)(1u << (next() % 8));
    hf_fuzz_can(buf, at);
  }
  printf("random_inputs: %ld iterations, no crash, every accepted input re-encoded identically\n", iterations);
  return 0;
}
