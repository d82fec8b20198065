/* hapfluid wire protocol v1: encoder and decoders shared by the host and the device firmware.
 * Plain C11, no allocation, no libc beyond memcpy, no libm: a device firmware compiles it as is.
 * firmware_bridge/protocol.md is the specification; this header is its byte-exact implementation.
 *
 * One message is one "packet":  [version u8][type u8][seq u16][payload][crc16 u16], little endian,
 * carried as one HID report, one USB bulk transfer or one CAN FD frame. Classic CAN (8-byte
 * frames) carries the same fields spread over several frames (hf_can_encode / hf_can_assembler). */
#ifndef HAPFLUID_WIRE_CODEC_H
#define HAPFLUID_WIRE_CODEC_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define HF_PROTOCOL_VERSION 1u
#define HF_PACKET_HEADER_BYTES 4u
#define HF_PACKET_CRC_BYTES 2u
#define HF_PACKET_MAX_BYTES 38u /* STATE, the largest */

/* Full scale of the COMMAND wrench per axis (i16 at 1 mN and 0.1 mN.m) and the INFO watchdog
 * (u8 ms): a rig limit beyond them could never be sent (config checks rigs against them). */
#define HF_WIRE_MAX_FORCE_N 32.767
#define HF_WIRE_MAX_TORQUE_NM 3.2767
#define HF_WIRE_MAX_WATCHDOG_MS 255

/* Message types; the classic-CAN function code of each message's first frame is in protocol.md. */
typedef enum {
  HF_MSG_STATE = 1,            /* device -> host, every 1 ms */
  HF_MSG_COMMAND = 2,          /* host -> device, every 1 ms */
  HF_MSG_HOST_HEARTBEAT = 3,   /* host -> device, every 100 ms */
  HF_MSG_DEVICE_HEARTBEAT = 4, /* device -> host, every 100 ms */
  HF_MSG_INFO_REQUEST = 5,     /* host -> device */
  HF_MSG_INFO = 6,             /* device -> host, answer to INFO_REQUEST */
  HF_MSG_FAULT = 7,            /* device -> host, on every new fault and every 100 ms while faulted */
  HF_MSG_ESTOP = 8             /* host -> device, latches the device's emergency stop */
} hf_msg_type;

typedef enum {
  HF_OK = 0,
  HF_ERR_SHORT = -1,        /* fewer bytes than the message needs */
  HF_ERR_LENGTH = -2,       /* more bytes than the message has, and they are not zero padding */
  HF_ERR_VERSION = -3,      /* protocol version byte is not HF_PROTOCOL_VERSION */
  HF_ERR_TYPE = -4,         /* unknown message type or CAN function code */
  HF_ERR_CRC = -5,          /* CRC-16 (packet) or CRC-8 (classic CAN frame set) mismatch */
  HF_ERR_RANGE = -6,        /* a field outside its documented range (decode) or not encodable */
  HF_ERR_RESERVED = -7,     /* a reserved bit or byte is not zero */
  HF_ERR_BUFFER = -8,       /* output buffer too small */
  HF_ERR_CAN_ID = -9,       /* CAN identifier not of this protocol, or node id out of 1..15 */
  HF_ERR_INCOMPLETE = -10   /* classic CAN: frame accepted, message not complete yet */
} hf_result;

const char* hf_result_name(int result);

/* Status bits (STATE.status, HEARTBEAT.status). */
enum {
  HF_STATUS_MOTORS_ENABLED = 1u << 0,
  HF_STATUS_FAULTED = 1u << 1,
  HF_STATUS_ESTOP_LATCHED = 1u << 2,
  HF_STATUS_WATCHDOG_TRIPPED = 1u << 3,
  HF_STATUS_FORCE_SATURATED = 1u << 4,
  HF_STATUS_AT_WORKSPACE_LIMIT = 1u << 5
};

/* Fault bits (STATE.fault, FAULT.faults). */
enum {
  HF_FAULT_COMMAND_WATCHDOG = 1u << 0, /* no valid command for watchdog_ms */
  HF_FAULT_ESTOP = 1u << 1,            /* ESTOP message or command flag received */
  HF_FAULT_BAD_COMMANDS = 1u << 2,     /* a burst of invalid command frames */
  HF_FAULT_WORKSPACE = 1u << 3,        /* handle left the workspace */
  HF_FAULT_OVERCURRENT = 1u << 4,
  HF_FAULT_INTERNAL = 1u << 5
};

/* COMMAND.flags */
enum { HF_CMD_ENABLE = 1u << 0, HF_CMD_ESTOP = 1u << 1, HF_CMD_CLEAR_FAULTS = 1u << 2 };

/* Physical values (SI); the codec quantises them with the scalings of protocol.md. */
typedef struct {
  uint32_t device_time_us;
  double position_m[3];        /* 20 um per LSB, +-0.65534 m */
  double orientation[4];       /* unit quaternion w, x, y, z; "smallest three" on the wire */
  double linear_velocity_m_s[3];    /* 0.1 mm/s per LSB, +-3.2767 m/s */
  double angular_velocity_rad_s[3]; /* 1 mrad/s per LSB, +-32.767 rad/s */
  uint8_t command_echo;        /* low 8 bits of the sequence of the last applied COMMAND */
  uint8_t buttons;             /* 6 bits; bit 0 deadman/enable */
  uint8_t status;              /* HF_STATUS_* */
  uint8_t fault;               /* HF_FAULT_* */
} hf_state;

typedef struct {
  double force_n[3];           /* 1 mN per LSB, +-32.767 N */
  double torque_nm[3];         /* 0.1 mN.m per LSB, +-3.2767 N.m */
  uint8_t flags;               /* HF_CMD_* */
} hf_command;

typedef struct {
  uint32_t uptime_ms;
  uint8_t status;
} hf_heartbeat;

typedef struct {
  uint16_t vendor_id, product_id, firmware_version;
  uint8_t protocol_version;
  uint8_t watchdog_ms;         /* device command watchdog, 1..255 ms */
  double max_force_n;          /* 10 mN per LSB */
  double max_torque_nm;        /* 1 mN.m per LSB */
  double workspace_half_extent_m; /* 1 mm per LSB */
} hf_info;

typedef struct {
  uint8_t faults;              /* HF_FAULT_* currently active */
  uint8_t cause;               /* bit index of the newest fault */
  uint32_t detail;             /* cause-specific, e.g. ms since the last valid command */
} hf_fault;

typedef struct {
  uint8_t reason;              /* 0 operator, 1 host safety layer, 2 link loss, others reserved */
} hf_estop;

typedef struct {
  uint8_t type;                /* hf_msg_type */
  uint16_t seq;                /* per sender and type; classic CAN carries the low 8 bits */
  union {
    hf_state state;
    hf_command command;
    hf_heartbeat heartbeat;
    hf_info info;
    hf_fault fault;
    hf_estop estop;
  } body;
} hf_message;

/* Packet length of a message type (header + payload + CRC), 0 for an unknown type. */
size_t hf_packet_length(uint8_t type);

/* Encodes `msg` into `out`; returns the packet length (> 0) or a negative hf_result. Values out of
 * range or non-finite are refused (HF_ERR_RANGE), never clipped: limiting is the safety layer's job. */
int hf_encode_packet(const hf_message* msg, uint8_t* out, size_t capacity);

/* Decodes one packet. Bytes after the packet must be zero (padding of CAN FD frames and HID
 * reports). Returns HF_OK or the first problem found; `out` is only valid on HF_OK. */
int hf_decode_packet(const uint8_t* data, size_t length, hf_message* out);

/* ---- classic CAN (11-bit identifiers: function << 4 | node) ---- */
typedef struct {
  uint32_t id;
  uint8_t dlc;
  uint8_t data[8];
} hf_can_frame;

#define HF_CAN_MAX_FRAMES 4
#define HF_CANFD_FUNCTION_BASE 0x10u /* CAN FD id = (0x10 | first classic function) << 4 | node */

/* Frames of one message, in sending order; returns their count or a negative hf_result. */
int hf_can_encode(const hf_message* msg, uint8_t node, hf_can_frame frames[HF_CAN_MAX_FRAMES]);

/* Reassembles classic frames into messages, one slot per multi-frame message type. */
typedef struct {
  uint8_t present;              /* bit i: frame i of the pending message received */
  uint8_t seq8;
  uint8_t bytes[HF_CAN_MAX_FRAMES][8];
} hf_can_pending;

typedef struct {
  uint8_t node;
  hf_can_pending state, command, info;
} hf_can_assembler;

void hf_can_assembler_init(hf_can_assembler* assembler, uint8_t node);
/* Feeds one frame. HF_OK: `out` holds a complete message. HF_ERR_INCOMPLETE: frame kept.
 * HF_ERR_CAN_ID: not this protocol or another node (ignore it). Other values: a bad frame. */
int hf_can_feed(hf_can_assembler* assembler, uint32_t id, const uint8_t* data, uint8_t dlc,
                hf_message* out);

/* CAN FD: identifier and padded length of the single frame carrying `type`. */
uint32_t hf_canfd_id(uint8_t type, uint8_t node);
size_t hf_canfd_padded_length(size_t packet_length);
/* Decodes a CAN FD frame: checks the id's node and that the id matches the packet's type. */
int hf_canfd_decode(uint32_t id, const uint8_t* data, size_t length, uint8_t node, hf_message* out);

/* ---- sequence tracking: counts frames lost between valid ones ---- */
typedef struct {
  uint16_t last;
  uint8_t started;
  uint32_t gaps;       /* messages missing between accepted ones */
  uint32_t duplicates; /* repeated or older sequence numbers */
} hf_seq_tracker;

/* Accepts `seq` (16-bit; pass modulus 256 for classic CAN). Returns 1 when it is newer. */
int hf_seq_accept(hf_seq_tracker* tracker, uint16_t seq, uint32_t modulus);

/* ---- checksums (exposed for the test vectors and the fake device's fault injection) ---- */
uint16_t hf_crc16(const uint8_t* data, size_t length);  /* CRC-16/CCITT-FALSE */
uint8_t hf_crc8(const uint8_t* data, size_t length);    /* CRC-8/SAE-J1850 */

#ifdef __cplusplus
}
#endif
#endif
