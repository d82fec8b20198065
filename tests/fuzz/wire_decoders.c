/* Fuzz entry points for every decoder of the wire codec, one libFuzzer target each
 * (HF_FUZZ_TARGET: 0 packet, 1 canfd, 2 can). Also linked into the deterministic random-input
 * driver (wire_random_inputs.c), so the gcc build throws hostile inputs at the decoders too.
 * Besides "no crash", each target checks a property: whatever decodes re-encodes to bytes that
 * decode to the same message (the codec never accepts what it could not have produced). */
#include <stdlib.h>
#include <string.h>

#include "hapfluid/wire/codec.h"
#include "fuzz_target.h"

#ifndef HF_FUZZ_TARGET
#define HF_FUZZ_TARGET 0
#endif

static double absd(double v) { return v < 0 ? -v : v; }

/* Quaternions may legitimately change their dropped component between passes when two
 * components tie within a quantisation step; everything else must come back bit-identical. */
static void check_reencodes(const hf_message* m) {
  uint8_t out[64];
  int n = hf_encode_packet(m, out, sizeof out);
  if (n <= 0) abort(); /* accepted input must be representable */
  hf_message again;
  if (hf_decode_packet(out, (size_t)n, &again) != HF_OK) abort();
  if (m->type != HF_MSG_STATE) {
    uint8_t out2[64];
    if (hf_encode_packet(&again, out2, sizeof out2) != n || memcmp(out, out2, (size_t)n) != 0) abort();
    return;
  }
  const hf_state* a = &m->body.state;
  const hf_state* b = &again.body.state;
  if (memcmp(a->position_m, b->position_m, sizeof a->position_m) ||
      memcmp(a->linear_velocity_m_s, b->linear_velocity_m_s, sizeof a->linear_velocity_m_s) ||
      memcmp(a->angular_velocity_rad_s, b->angular_velocity_rad_s, sizeof a->angular_velocity_rad_s) ||
      a->buttons != b->buttons || a->status != b->status || a->fault != b->fault)
    abort();
  double plus = 0, minus = 0;
  for (int i = 0; i < 4; ++i) {
    if (absd(a->orientation[i] - b->orientation[i]) > plus) plus = absd(a->orientation[i] - b->orientation[i]);
    if (absd(a->orientation[i] + b->orientation[i]) > minus) minus = absd(a->orientation[i] + b->orientation[i]);
  }
  if ((plus < minus ? plus : minus) > 2e-4) abort();
}

int hf_fuzz_packet(const uint8_t* data, size_t size) {
  hf_message m;
  if (hf_decode_packet(data, size, &m) == HF_OK) {
    check_reencodes(&m);
    ++hapfluid_fuzz_accepted;
  }
  return 0;
}

int hf_fuzz_canfd(const uint8_t* data, size_t size) {
  if (size < 3) return 0;
  uint32_t id = (uint32_t)(data[0] | (data[1] << 8)) & 0x7FF;
  hf_message m;
  if (hf_canfd_decode(id, data + 3, size - 3, data[2] & 0xF, &m) == HF_OK) {
    check_reencodes(&m);
    ++hapfluid_fuzz_accepted;
  }
  return 0;
}

/* A stream of classic frames: [id lo][id hi][dlc][8 data bytes] repeated. */
int hf_fuzz_can(const uint8_t* data, size_t size) {
  hf_can_assembler assembler;
  hf_can_assembler_init(&assembler, 3);
  for (size_t at = 0; at + 11 <= size; at += 11) {
    uint32_t id = (uint32_t)(data[at] | (data[at + 1] << 8)) & 0x7FF;
    uint8_t dlc = data[at + 2] % 9;
    hf_message m;
    if (hf_can_feed(&assembler, id, data + at + 3, dlc, &m) == HF_OK) {
      hf_can_frame frames[HF_CAN_MAX_FRAMES];
      if (hf_can_encode(&m, 3, frames) <= 0) abort();
      check_reencodes(&m);
      ++hapfluid_fuzz_accepted;
    }
  }
  return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  switch (HF_FUZZ_TARGET) {
    case 1: return hf_fuzz_canfd(data, size);
    case 2: return hf_fuzz_can(data, size);
    default: return hf_fuzz_packet(data, size);
  }
}
