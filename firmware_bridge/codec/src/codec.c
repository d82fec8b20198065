/* hapfluid wire protocol v1 codec. Byte layouts: firmware_bridge/protocol.md, section "Payloads".
 * Rounding, square root and scaling are written out so that the Python mirror
 * (scripts/hapfluid/proto/codec.py) performs the very same IEEE-754 operations, bit for bit. */
#include "hapfluid/wire/codec.h"

#include <string.h>

/* ---- scalings (value * scale = integer on the wire) ---- */
#define SCALE_POSITION 50000.0   /* 20 um */
#define SCALE_QUAT 32767.0
#define SCALE_VELOCITY 10000.0   /* 0.1 mm/s */
#define SCALE_ANGVEL 1000.0      /* 1 mrad/s */
#define SCALE_FORCE 1000.0       /* 1 mN */
#define SCALE_TORQUE 10000.0     /* 0.1 mN.m */
#define SCALE_INFO_FORCE 100.0   /* 10 mN */
#define SCALE_INFO_TORQUE 1000.0 /* 1 mN.m */
#define SCALE_INFO_LENGTH 1000.0 /* 1 mm */
#define QUAT_SMALL_MAX 23170     /* 1/sqrt(2) * 32767, rounded up */

enum { PAYLOAD_STATE = 32, PAYLOAD_COMMAND = 14, PAYLOAD_HEARTBEAT = 6, PAYLOAD_INFO_REQUEST = 0,
       PAYLOAD_INFO = 14, PAYLOAD_FAULT = 6, PAYLOAD_ESTOP = 2 };

/* classic CAN function codes, lowest = highest bus priority */
enum { FN_ESTOP = 0x1, FN_FAULT = 0x2, FN_CMD_FORCE = 0x3, FN_CMD_TORQUE = 0x4, FN_STATE_POS = 0x5,
       FN_STATE_ROT = 0x6, FN_STATE_VEL = 0x7, FN_STATE_ANGVEL = 0x8, FN_DEVICE_HB = 0x9,
       FN_HOST_HB = 0xA, FN_INFO_REQUEST = 0xB, FN_INFO_A = 0xC, FN_INFO_B = 0xD };

const char* hf_result_name(int result) {
  switch (result) {
    case HF_OK: return "ok";
    case HF_ERR_SHORT: return "short frame";
    case HF_ERR_LENGTH: return "wrong length";
    case HF_ERR_VERSION: return "wrong protocol version";
    case HF_ERR_TYPE: return "unknown message type";
    case HF_ERR_CRC: return "bad CRC";
    case HF_ERR_RANGE: return "value out of range";
    case HF_ERR_RESERVED: return "reserved bits set";
    case HF_ERR_BUFFER: return "buffer too small";
    case HF_ERR_CAN_ID: return "foreign CAN id";
    case HF_ERR_INCOMPLETE: return "incomplete";
    default: return "unknown result";
  }
}

uint16_t hf_crc16(const uint8_t* data, size_t length) {
  uint16_t crc = 0xFFFF;
  for (size_t i = 0; i < length; ++i) {
    crc = (uint16_t)(crc ^ (data[i] << 8));
    for (int bit = 0; bit < 8; ++bit)
      crc = (crc & 0x8000) ? (uint16_t)((crc << 1) ^ 0x1021) : (uint16_t)(crc << 1);
  }
  return crc;
}

uint8_t hf_crc8(const uint8_t* data, size_t length) {
  uint8_t crc = 0xFF;
  for (size_t i = 0; i < length; ++i) {
    crc = (uint8_t)(crc ^ data[i]);
    for (int bit = 0; bit < 8; ++bit)
      crc = (crc & 0x80) ? (uint8_t)((crc << 1) ^ 0x1D) : (uint8_t)(crc << 1);
  }
  return (uint8_t)(crc ^ 0xFF);
}

/* ---- little-endian helpers ---- */
static void put_u16(uint8_t* p, uint16_t v) { p[0] = (uint8_t)v; p[1] = (uint8_t)(v >> 8); }
static void put_u32(uint8_t* p, uint32_t v) {
  p[0] = (uint8_t)v; p[1] = (uint8_t)(v >> 8); p[2] = (uint8_t)(v >> 16); p[3] = (uint8_t)(v >> 24);
}
static uint16_t get_u16(const uint8_t* p) { return (uint16_t)(p[0] | (p[1] << 8)); }
static uint32_t get_u32(const uint8_t* p) {
  return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}
static int16_t get_i16(const uint8_t* p) { return (int16_t)get_u16(p); }

/* Round half away from zero; refuses NaN, infinities and values beyond +-limit LSB. */
static int quantise(double value, double scale, long limit, long* out) {
  if (!(value == value)) return HF_ERR_RANGE;
  double scaled = value * scale;
  if (scaled > (double)limit + 0.5 || scaled < -(double)limit - 0.5) return HF_ERR_RANGE;
  long q = scaled >= 0 ? (long)(scaled + 0.5) : -(long)(-scaled + 0.5);
  if (q > limit || q < -limit) return HF_ERR_RANGE;
  *out = q;
  return HF_OK;
}

/* As quantise, then one LSB back toward zero when rounding went past the value: the decoded
 * magnitude (q / scale) never exceeds the encoded one, so a wrench the safety layer limited, or a
 * limit the device reports, never arrives larger than it was. The range is quantise's. */
static int quantise_within(double value, double scale, long limit, long* out) {
  long q;
  int r = quantise(value, scale, limit, &q);
  if (r != HF_OK) return r;
  if (q > 0 && (double)q / scale > value) --q;
  else if (q < 0 && (double)q / scale < value) ++q;
  *out = q;
  return HF_OK;
}

/* i16 fields use -32767..32767; -32768 is reserved ("not available") and rejected. */
static int put_i16_scaled(uint8_t* p, double value, double scale) {
  long q;
  int r = quantise(value, scale, 32767, &q);
  if (r != HF_OK) return r;
  put_u16(p, (uint16_t)(int16_t)q);
  return HF_OK;
}

/* A bounded quantity (the commanded wrench): rounded, but never past the value. */
static int put_i16_within(uint8_t* p, double value, double scale) {
  long q;
  int r = quantise_within(value, scale, 32767, &q);
  if (r != HF_OK) return r;
  put_u16(p, (uint16_t)(int16_t)q);
  return HF_OK;
}

static int get_i16_scaled(const uint8_t* p, double scale, double* out) {
  int16_t q = get_i16(p);
  if (q == -32768) return HF_ERR_RANGE;
  *out = q / scale;
  return HF_OK;
}

static int put_u16_scaled(uint8_t* p, double value, double scale) {
  if (!(value >= 0)) return HF_ERR_RANGE;
  long q;
  int r = quantise_within(value, scale, 65535, &q); /* only INFO limits are u16 */
  if (r != HF_OK) return r;
  put_u16(p, (uint16_t)q);
  return HF_OK;
}

/* Newton's iteration with a fixed count: no libm, and the Python mirror reproduces it exactly. */
static double hf_sqrt(double x) {
  if (!(x > 0)) return 0;
  double y = x > 1 ? x : 1;
  for (int i = 0; i < 64; ++i) y = 0.5 * (y + x / y);
  return y;
}

static double absd(double v) { return v < 0 ? -v : v; }

/* "Smallest three": the largest |component| is dropped (made positive), its index kept in 2 bits. */
static int put_quaternion(uint8_t* p, uint8_t* qinfo, const double q_in[4]) {
  double norm2 = q_in[0] * q_in[0] + q_in[1] * q_in[1] + q_in[2] * q_in[2] + q_in[3] * q_in[3];
  if (!(norm2 > 0.99 && norm2 < 1.01)) return HF_ERR_RANGE; /* also catches NaN */
  double norm = hf_sqrt(norm2);
  double q[4];
  int largest = 0;
  for (int i = 0; i < 4; ++i) {
    q[i] = q_in[i] / norm;
    if (absd(q[i]) > absd(q[largest])) largest = i;
  }
  double sign = q[largest] < 0 ? -1.0 : 1.0;
  for (int i = 0, k = 0; i < 4; ++i) {
    if (i == largest) continue;
    int r = put_i16_scaled(p + 2 * k++, sign * q[i], SCALE_QUAT);
    if (r != HF_OK) return r;
  }
  *qinfo = (uint8_t)largest;
  return HF_OK;
}

static int get_quaternion(const uint8_t* p, uint8_t qinfo, double q[4]) {
  int largest = qinfo & 3;
  double small[3], sum = 0;
  for (int k = 0; k < 3; ++k) {
    int16_t raw = get_i16(p + 2 * k);
    if (raw > QUAT_SMALL_MAX || raw < -QUAT_SMALL_MAX) return HF_ERR_RANGE;
    small[k] = raw / SCALE_QUAT;
    sum += small[k] * small[k];
  }
  if (sum > 1.0) return HF_ERR_RANGE;
  double dropped = hf_sqrt(1.0 - sum);
  /* canonical form only: the dropped component is the largest (4 LSB of quantisation slack) */
  for (int k = 0; k < 3; ++k)
    if (absd(small[k]) > dropped + 4.0 / SCALE_QUAT) return HF_ERR_RANGE;
  for (int i = 0, k = 0; i < 4; ++i) q[i] = i == largest ? dropped : small[k++];
  return HF_OK;
}

#define TRY(expr) do { int r_ = (expr); if (r_ != HF_OK) return r_; } while (0)

static size_t payload_length(uint8_t type) {
  switch (type) {
    case HF_MSG_STATE: return PAYLOAD_STATE;
    case HF_MSG_COMMAND: return PAYLOAD_COMMAND;
    case HF_MSG_HOST_HEARTBEAT:
    case HF_MSG_DEVICE_HEARTBEAT: return PAYLOAD_HEARTBEAT;
    case HF_MSG_INFO_REQUEST: return PAYLOAD_INFO_REQUEST;
    case HF_MSG_INFO: return PAYLOAD_INFO;
    case HF_MSG_FAULT: return PAYLOAD_FAULT;
    case HF_MSG_ESTOP: return PAYLOAD_ESTOP;
    default: return (size_t)-1;
  }
}

size_t hf_packet_length(uint8_t type) {
  size_t n = payload_length(type);
  return n == (size_t)-1 ? 0 : HF_PACKET_HEADER_BYTES + n + HF_PACKET_CRC_BYTES;
}

/* ---- payloads: one writer and one parser per message type ---- */
static int write_state(const hf_state* s, uint8_t* p) {
  uint8_t qinfo = 0;
  if (s->buttons > 0x3F || (s->status & 0xC0) || (s->fault & 0xC0)) return HF_ERR_RESERVED;
  put_u32(p, s->device_time_us);
  for (int i = 0; i < 3; ++i) TRY(put_i16_scaled(p + 4 + 2 * i, s->position_m[i], SCALE_POSITION));
  p[10] = s->command_echo;
  TRY(put_quaternion(p + 11, &qinfo, s->orientation));
  p[17] = (uint8_t)(qinfo | (s->buttons << 2));
  for (int i = 0; i < 3; ++i)
    TRY(put_i16_scaled(p + 18 + 2 * i, s->linear_velocity_m_s[i], SCALE_VELOCITY));
  p[24] = s->status;
  for (int i = 0; i < 3; ++i)
    TRY(put_i16_scaled(p + 25 + 2 * i, s->angular_velocity_rad_s[i], SCALE_ANGVEL));
  p[31] = s->fault;
  return HF_OK;
}

static int parse_state(const uint8_t* p, hf_state* s) {
  if ((p[24] & 0xC0) || (p[31] & 0xC0)) return HF_ERR_RESERVED;
  s->device_time_us = get_u32(p);
  for (int i = 0; i < 3; ++i) TRY(get_i16_scaled(p + 4 + 2 * i, SCALE_POSITION, &s->position_m[i]));
  s->command_echo = p[10];
  TRY(get_quaternion(p + 11, p[17], s->orientation));
  s->buttons = (uint8_t)(p[17] >> 2);
  for (int i = 0; i < 3; ++i)
    TRY(get_i16_scaled(p + 18 + 2 * i, SCALE_VELOCITY, &s->linear_velocity_m_s[i]));
  s->status = p[24];
  for (int i = 0; i < 3; ++i)
    TRY(get_i16_scaled(p + 25 + 2 * i, SCALE_ANGVEL, &s->angular_velocity_rad_s[i]));
  s->fault = p[31];
  return HF_OK;
}

static int write_command(const hf_command* c, uint8_t* p) {
  if (c->flags & 0xF8) return HF_ERR_RESERVED;
  for (int i = 0; i < 3; ++i) TRY(put_i16_within(p + 2 * i, c->force_n[i], SCALE_FORCE));
  for (int i = 0; i < 3; ++i) TRY(put_i16_within(p + 6 + 2 * i, c->torque_nm[i], SCALE_TORQUE));
  p[12] = c->flags;
  p[13] = 0;
  return HF_OK;
}

static int parse_command(const uint8_t* p, hf_command* c) {
  if ((p[12] & 0xF8) || p[13]) return HF_ERR_RESERVED;
  for (int i = 0; i < 3; ++i) TRY(get_i16_scaled(p + 2 * i, SCALE_FORCE, &c->force_n[i]));
  for (int i = 0; i < 3; ++i) TRY(get_i16_scaled(p + 6 + 2 * i, SCALE_TORQUE, &c->torque_nm[i]));
  c->flags = p[12];
  return HF_OK;
}

static int write_info(const hf_info* n, uint8_t* p) {
  if (n->watchdog_ms == 0) return HF_ERR_RANGE;
  put_u16(p, n->vendor_id);
  put_u16(p + 2, n->product_id);
  put_u16(p + 4, n->firmware_version);
  p[6] = n->protocol_version;
  p[7] = n->watchdog_ms;
  TRY(put_u16_scaled(p + 8, n->max_force_n, SCALE_INFO_FORCE));
  TRY(put_u16_scaled(p + 10, n->max_torque_nm, SCALE_INFO_TORQUE));
  TRY(put_u16_scaled(p + 12, n->workspace_half_extent_m, SCALE_INFO_LENGTH));
  return HF_OK;
}

static int parse_info(const uint8_t* p, hf_info* n) {
  if (p[6] == 0 || p[7] == 0) return HF_ERR_RANGE;
  n->vendor_id = get_u16(p);
  n->product_id = get_u16(p + 2);
  n->firmware_version = get_u16(p + 4);
  n->protocol_version = p[6];
  n->watchdog_ms = p[7];
  n->max_force_n = get_u16(p + 8) / SCALE_INFO_FORCE;
  n->max_torque_nm = get_u16(p + 10) / SCALE_INFO_TORQUE;
  n->workspace_half_extent_m = get_u16(p + 12) / SCALE_INFO_LENGTH;
  return HF_OK;
}

static int write_payload(const hf_message* m, uint8_t* p) {
  switch (m->type) {
    case HF_MSG_STATE: return write_state(&m->body.state, p);
    case HF_MSG_COMMAND: return write_command(&m->body.command, p);
    case HF_MSG_HOST_HEARTBEAT:
    case HF_MSG_DEVICE_HEARTBEAT:
      if (m->body.heartbeat.status & 0xC0) return HF_ERR_RESERVED;
      put_u32(p, m->body.heartbeat.uptime_ms);
      p[4] = m->body.heartbeat.status;
      p[5] = 0;
      return HF_OK;
    case HF_MSG_INFO_REQUEST: return HF_OK;
    case HF_MSG_INFO: return write_info(&m->body.info, p);
    case HF_MSG_FAULT:
      if ((m->body.fault.faults & 0xC0)) return HF_ERR_RESERVED;
      if (m->body.fault.cause > 5) return HF_ERR_RANGE;
      p[0] = m->body.fault.faults;
      p[1] = m->body.fault.cause;
      put_u32(p + 2, m->body.fault.detail);
      return HF_OK;
    case HF_MSG_ESTOP:
      if (m->body.estop.reason > 2) return HF_ERR_RANGE;
      p[0] = m->body.estop.reason;
      p[1] = 0;
      return HF_OK;
    default: return HF_ERR_TYPE;
  }
}

static int parse_payload(uint8_t type, const uint8_t* p, hf_message* m) {
  m->type = type;
  switch (type) {
    case HF_MSG_STATE: return parse_state(p, &m->body.state);
    case HF_MSG_COMMAND: return parse_command(p, &m->body.command);
    case HF_MSG_HOST_HEARTBEAT:
    case HF_MSG_DEVICE_HEARTBEAT:
      if ((p[4] & 0xC0) || p[5]) return HF_ERR_RESERVED;
      m->body.heartbeat.uptime_ms = get_u32(p);
      m->body.heartbeat.status = p[4];
      return HF_OK;
    case HF_MSG_INFO_REQUEST: return HF_OK;
    case HF_MSG_INFO: return parse_info(p, &m->body.info);
    case HF_MSG_FAULT:
      if (p[0] & 0xC0) return HF_ERR_RESERVED;
      if (p[1] > 5) return HF_ERR_RANGE;
      m->body.fault.faults = p[0];
      m->body.fault.cause = p[1];
      m->body.fault.detail = get_u32(p + 2);
      return HF_OK;
    case HF_MSG_ESTOP:
      if (p[1]) return HF_ERR_RESERVED;
      if (p[0] > 2) return HF_ERR_RANGE;
      m->body.estop.reason = p[0];
      return HF_OK;
    default: return HF_ERR_TYPE;
  }
}

int hf_encode_packet(const hf_message* msg, uint8_t* out, size_t capacity) {
  size_t length = hf_packet_length(msg->type);
  if (length == 0) return HF_ERR_TYPE;
  if (capacity < length) return HF_ERR_BUFFER;
  uint8_t buffer[HF_PACKET_MAX_BYTES];
  buffer[0] = HF_PROTOCOL_VERSION;
  buffer[1] = msg->type;
  put_u16(buffer + 2, msg->seq);
  TRY(write_payload(msg, buffer + HF_PACKET_HEADER_BYTES));
  put_u16(buffer + length - 2, hf_crc16(buffer, length - 2));
  memcpy(out, buffer, length); /* nothing half-written on error */
  return (int)length;
}

int hf_decode_packet(const uint8_t* data, size_t length, hf_message* out) {
  if (length < HF_PACKET_HEADER_BYTES + HF_PACKET_CRC_BYTES) return HF_ERR_SHORT;
  if (data[0] != HF_PROTOCOL_VERSION) return HF_ERR_VERSION;
  size_t expected = hf_packet_length(data[1]);
  if (expected == 0) return HF_ERR_TYPE;
  if (length < expected) return HF_ERR_SHORT;
  for (size_t i = expected; i < length; ++i)
    if (data[i]) return HF_ERR_LENGTH;
  if (hf_crc16(data, expected - 2) != get_u16(data + expected - 2)) return HF_ERR_CRC;
  hf_message m;
  m.seq = get_u16(data + 2);
  TRY(parse_payload(data[1], data + HF_PACKET_HEADER_BYTES, &m));
  *out = m;
  return HF_OK;
}

/* ---- CAN FD: one frame per message ---- */
static uint8_t first_function(uint8_t type) {
  switch (type) {
    case HF_MSG_STATE: return FN_STATE_POS;
    case HF_MSG_COMMAND: return FN_CMD_FORCE;
    case HF_MSG_HOST_HEARTBEAT: return FN_HOST_HB;
    case HF_MSG_DEVICE_HEARTBEAT: return FN_DEVICE_HB;
    case HF_MSG_INFO_REQUEST: return FN_INFO_REQUEST;
    case HF_MSG_INFO: return FN_INFO_A;
    case HF_MSG_FAULT: return FN_FAULT;
    case HF_MSG_ESTOP: return FN_ESTOP;
    default: return 0;
  }
}

uint32_t hf_canfd_id(uint8_t type, uint8_t node) {
  return ((uint32_t)(HF_CANFD_FUNCTION_BASE | first_function(type)) << 4) | (node & 0xF);
}

size_t hf_canfd_padded_length(size_t n) {
  static const uint8_t sizes[] = {0, 1, 2, 3, 4, 5, 6, 7, 8, 12, 16, 20, 24, 32, 48, 64};
  for (size_t i = 0; i < sizeof sizes; ++i)
    if (sizes[i] >= n) return sizes[i];
  return 0;
}

int hf_canfd_decode(uint32_t id, const uint8_t* data, size_t length, uint8_t node,
                    hf_message* out) {
  if (id > 0x7FF || (id & 0xF) != node || (id >> 8) != 1) return HF_ERR_CAN_ID;
  hf_message m;
  TRY(hf_decode_packet(data, length, &m));
  if (hf_canfd_id(m.type, node) != id) return HF_ERR_TYPE;
  *out = m;
  return HF_OK;
}

/* ---- classic CAN: frames carry seq8 in byte 0 and 7 bytes of fields ---- */
static void frame(hf_can_frame* f, uint8_t function, uint8_t node, uint8_t dlc, uint8_t seq8) {
  memset(f, 0, sizeof *f);
  f->id = ((uint32_t)function << 4) | node;
  f->dlc = dlc;
  f->data[0] = seq8;
}

int hf_can_encode(const hf_message* msg, uint8_t node, hf_can_frame frames[HF_CAN_MAX_FRAMES]) {
  if (node < 1 || node > 15) return HF_ERR_CAN_ID;
  uint8_t p[HF_PACKET_MAX_BYTES] = {0};
  if (payload_length(msg->type) == (size_t)-1) return HF_ERR_TYPE;
  TRY(write_payload(msg, p));
  uint8_t s = (uint8_t)msg->seq;
  switch (msg->type) {
    case HF_MSG_STATE: /* 4 frames = payload bytes 4..31; the last byte (fault) becomes the CRC-8 */
      for (int k = 0; k < 4; ++k) {
        frame(&frames[k], (uint8_t)(FN_STATE_POS + k), node, 8, s);
        memcpy(frames[k].data + 1, p + 4 + 7 * k, 7);
      }
      {
        uint8_t all[32];
        for (int k = 0; k < 4; ++k) memcpy(all + 8 * k, frames[k].data, 8);
        frames[3].data[7] = hf_crc8(all, 31);
      }
      return 4;
    case HF_MSG_COMMAND:
      frame(&frames[0], FN_CMD_FORCE, node, 8, s);
      memcpy(frames[0].data + 1, p, 6);
      frames[0].data[7] = p[12];
      frame(&frames[1], FN_CMD_TORQUE, node, 8, s);
      memcpy(frames[1].data + 1, p + 6, 6);
      {
        uint8_t all[15];
        memcpy(all, frames[0].data, 8);
        memcpy(all + 8, frames[1].data, 7);
        frames[1].data[7] = hf_crc8(all, 15);
      }
      return 2;
    case HF_MSG_HOST_HEARTBEAT:
    case HF_MSG_DEVICE_HEARTBEAT:
      frame(&frames[0], first_function(msg->type), node, 8, s);
      frames[0].data[1] = p[4];
      memcpy(frames[0].data + 2, p, 4);
      frames[0].data[6] = HF_PROTOCOL_VERSION;
      return 1;
    case HF_MSG_INFO_REQUEST:
      frame(&frames[0], FN_INFO_REQUEST, node, 1, s);
      return 1;
    case HF_MSG_INFO:
      frame(&frames[0], FN_INFO_A, node, 8, s);
      memcpy(frames[0].data + 1, p, 7);
      frame(&frames[1], FN_INFO_B, node, 8, s);
      memcpy(frames[1].data + 1, p + 8, 6);
      frames[1].data[7] = p[7];
      return 2;
    case HF_MSG_FAULT:
      frame(&frames[0], FN_FAULT, node, 8, s);
      frames[0].data[1] = p[0];
      frames[0].data[2] = p[1];
      memcpy(frames[0].data + 4, p + 2, 4);
      return 1;
    case HF_MSG_ESTOP:
      frame(&frames[0], FN_ESTOP, node, 2, s);
      frames[0].data[1] = p[0];
      return 1;
    default: return HF_ERR_TYPE;
  }
}

void hf_can_assembler_init(hf_can_assembler* a, uint8_t node) {
  memset(a, 0, sizeof *a);
  a->node = node;
}

/* Keeps frame `index` of a multi-frame message; returns 1 when all `count` frames share one seq. */
static int keep(hf_can_pending* slot, int index, int count, const uint8_t* data) {
  if (slot->present && slot->seq8 != data[0]) slot->present = 0; /* the older set is lost: a gap */
  slot->seq8 = data[0];
  slot->present |= (uint8_t)(1u << index);
  memcpy(slot->bytes[index], data, 8);
  if (slot->present != (1u << count) - 1) return 0;
  slot->present = 0;
  return 1;
}

static int expect_dlc(uint8_t dlc, uint8_t wanted) {
  return dlc < wanted ? HF_ERR_SHORT : dlc > wanted ? HF_ERR_LENGTH : HF_OK;
}

int hf_can_feed(hf_can_assembler* a, uint32_t id, const uint8_t* data, uint8_t dlc,
                hf_message* out) {
  if (id > 0x0FF || (id & 0xF) != a->node) return HF_ERR_CAN_ID;
  uint8_t function = (uint8_t)(id >> 4);
  uint8_t p[HF_PACKET_MAX_BYTES] = {0};
  hf_message m;
  switch (function) {
    case FN_STATE_POS:
    case FN_STATE_ROT:
    case FN_STATE_VEL:
    case FN_STATE_ANGVEL: {
      TRY(expect_dlc(dlc, 8));
      if (!keep(&a->state, function - FN_STATE_POS, 4, data)) return HF_ERR_INCOMPLETE;
      uint8_t all[32];
      for (int k = 0; k < 4; ++k) memcpy(all + 8 * k, a->state.bytes[k], 8);
      if (hf_crc8(all, 31) != all[31]) return HF_ERR_CRC;
      for (int k = 0; k < 4; ++k) memcpy(p + 4 + 7 * k, all + 8 * k + 1, 7);
      p[31] = 0; /* fault bits travel in FAULT frames on classic CAN */
      m.type = HF_MSG_STATE;
      break;
    }
    case FN_CMD_FORCE:
    case FN_CMD_TORQUE: {
      TRY(expect_dlc(dlc, 8));
      if (!keep(&a->command, function - FN_CMD_FORCE, 2, data)) return HF_ERR_INCOMPLETE;
      const uint8_t* f0 = a->command.bytes[0];
      const uint8_t* f1 = a->command.bytes[1];
      uint8_t all[15];
      memcpy(all, f0, 8);
      memcpy(all + 8, f1, 7);
      if (hf_crc8(all, 15) != f1[7]) return HF_ERR_CRC;
      memcpy(p, f0 + 1, 6);
      memcpy(p + 6, f1 + 1, 6);
      p[12] = f0[7];
      m.type = HF_MSG_COMMAND;
      break;
    }
    case FN_INFO_A:
    case FN_INFO_B: {
      TRY(expect_dlc(dlc, 8));
      if (!keep(&a->info, function - FN_INFO_A, 2, data)) return HF_ERR_INCOMPLETE;
      memcpy(p, a->info.bytes[0] + 1, 7);
      p[7] = a->info.bytes[1][7];
      memcpy(p + 8, a->info.bytes[1] + 1, 6);
      m.type = HF_MSG_INFO;
      break;
    }
    case FN_DEVICE_HB:
    case FN_HOST_HB:
      TRY(expect_dlc(dlc, 8));
      if (data[6] != HF_PROTOCOL_VERSION) return HF_ERR_VERSION;
      if (data[7]) return HF_ERR_RESERVED;
      memcpy(p, data + 2, 4);
      p[4] = data[1];
      m.type = function == FN_HOST_HB ? HF_MSG_HOST_HEARTBEAT : HF_MSG_DEVICE_HEARTBEAT;
      break;
    case FN_INFO_REQUEST:
      TRY(expect_dlc(dlc, 1));
      m.type = HF_MSG_INFO_REQUEST;
      break;
    case FN_FAULT:
      TRY(expect_dlc(dlc, 8));
      if (data[3]) return HF_ERR_RESERVED;
      p[0] = data[1];
      p[1] = data[2];
      memcpy(p + 2, data + 4, 4);
      m.type = HF_MSG_FAULT;
      break;
    case FN_ESTOP:
      TRY(expect_dlc(dlc, 2));
      p[0] = data[1];
      m.type = HF_MSG_ESTOP;
      break;
    default: return HF_ERR_CAN_ID;
  }
  m.seq = data[0];
  TRY(parse_payload(m.type, p, &m));
  *out = m;
  return HF_OK;
}

int hf_seq_accept(hf_seq_tracker* t, uint16_t seq, uint32_t modulus) {
  if (!t->started) {
    t->started = 1;
    t->last = seq;
    return 1;
  }
  uint32_t diff = (uint32_t)(seq - t->last + modulus) % modulus;
  if (diff == 0 || diff >= modulus / 2) {
    t->duplicates++;
    return 0;
  }
  t->gaps += diff - 1;
  t->last = seq;
  return 1;
}
