// The byte layouts of every shared-memory channel (docs/architecture.md, Contracts). One file, one ABI version:
// any change to a struct here bumps kAbiVersion, and readers of an older build refuse to attach
// with a message naming both versions.
//
// Conventions: SI units; orientations are unit quaternions (w, x, y, z); times are CLOCK_MONOTONIC
// nanoseconds (same clock in every process on the machine) unless named sim_time_s. Poses,
// velocities and wrenches in device_states and sim_samples are in the SCENE frame: haptic-rt
// applies the rig's workspace mapping, so the simulator never needs the rig file.
//
// Device indexing: device_states.devices[i] carries the rig device's name; the sim looks each
// name up once and writes that device's coupling into sim_samples.couplings[i] (same index).
#pragma once

#include <cstdint>
#include <string>
#include <type_traits>

namespace hapfluid::shm {

inline constexpr std::uint32_t kAbiVersion = 4;
inline constexpr int kMaxDevices = 4;
inline constexpr int kMaxBodies = 16;
inline constexpr int kDeviceNameBytes = 32;

enum class ChannelKind : std::uint32_t {
  device_states = 1,  // haptic-rt -> haptic-sim, haptic-render      (LatestWriter, 1 kHz)
  sim_samples = 2,    // haptic-sim -> haptic-rt                       (LatestWriter, 60-1000 Hz)
  particles = 3,      // haptic-sim -> haptic-render                   (LatestWriter, variable size)
  trace = 4,          // haptic-rt -> haptic-trace                     (RingWriter, 1 kHz)
  flight_recorder = 5 // private to haptic-rt (never a named segment)
};
const char* channel_name(ChannelKind kind);
// "/<prefix>.<channel>", e.g. "/hapfluid.sim_samples".
std::string segment_name(const std::string& prefix, ChannelKind kind);

// ---- device_states ------------------------------------------------------------------------
struct DeviceStateEntry {
  char name[kDeviceNameBytes];     // rig device name, NUL-terminated
  std::uint32_t present;           // 1: this entry is a configured device
  std::uint32_t buttons;           // bit 0: deadman/enable
  std::uint32_t safety_flags;      // safety::Flag bits of the last tick
  std::uint32_t faults;            // safety::Fault bits of the last tick
  std::uint64_t host_receive_ns;   // when the newest device frame arrived
  double position_m[3];            // scene frame (workspace mapping applied)
  double orientation[4];
  double linear_velocity_m_s[3];
  double angular_velocity_rad_s[3];
  double force_n[3];               // wrench rendered on the hand this tick, scene frame
  double torque_nm[3];
};

struct DeviceStatesRecord {
  std::uint64_t tick;              // haptic-rt loop tick
  std::uint64_t time_ns;           // scheduled wake time of that tick
  std::uint32_t device_count;
  std::uint32_t reserved;
  DeviceStateEntry devices[kMaxDevices];
};

// ---- sim_samples --------------------------------------------------------------------------
struct BodyState {
  double position_m[3];
  double orientation[4];
  double linear_velocity_m_s[3];
  double angular_velocity_rad_s[3];
};

// The local coupling model of one device (wrench_mode = coupling) and the wrench the sim computed
// (both modes). All terms are the wrench ON THE HAND, scene frame, evaluated at the device pose
// x0/q0 and twist v0/w0 the sim used for this step. The spring pulls toward the held body's
// grasp, which moves on between samples: vref/wref is its twist (the couplings' grasp velocities,
// weighted by their stiffness). haptic-rt renders at 1 kHz, h the time since the device pose x0
// (SimSample::pose_lead_s after device_tick's poll; negative before it) times the sim's pace
// (simulated seconds per wall second, measured from the samples, at most 1):
//   F = F0 - K (x - x0 - vref h) + D (v0 - v),   tau = tau0 - Kr rotvec(q (exp(wref h) q0)^-1) + Dr (w0 - w),
// so a hand moving with the body it holds feels what the sim computed, however old the sample.
struct CouplingModel {
  std::uint32_t valid;             // 1: the sim couples this device this sample
  std::uint32_t reserved;
  double force_n[3];               // F0
  double torque_nm[3];             // tau0
  double x0_m[3];
  double q0[4];
  double v0_m_s[3];
  double w0_rad_s[3];
  double stiffness_n_per_m;        // K  (haptic-rt caps it with the rig's max_stiffness_n_per_m)
  double damping_n_s_per_m;        // D
  double angular_stiffness_nm_per_rad;
  double angular_damping_nm_s_per_rad;
  double vref_m_s[3];              // the grasp's twist at the sample: where the spring's anchor goes
  double wref_rad_s[3];
};

struct SimSample {
  std::uint64_t sequence;          // sim step number; strictly increasing within one sim run
  double sim_time_s;               // simulated time of this sample
  std::uint64_t publish_ns;        // CLOCK_MONOTONIC when published
  std::uint64_t device_tick;       // device_states tick the sim used (0: none)
  std::uint32_t body_count;
  std::uint32_t device_count;
  // What the operator's view shows of the sim (haptic-status): its backend ("cpu", "vulkan";
  // NUL-terminated), its fluid particles and the CPU threads stepping them now (0: not the cpu).
  char backend[16];
  std::uint32_t fluid_particles;
  std::uint32_t threads_active;
  // The couplings' x0/q0 are the device poses this long after device_tick's poll: the sim couples
  // a step at its end, so it moves the pose it read on by the step (v0 dt).
  double pose_lead_s;
  BodyState bodies[kMaxBodies];
  CouplingModel couplings[kMaxDevices];
};

// ---- particles (variable size) ------------------------------------------------------------
struct BodyTransform {
  double position_m[3];
  double orientation[4];
};

// A particle frame is a ParticleFrameHeader followed by max_particles ParticleRecord entries;
// only the first particle_count are meaningful. The writer picks max_particles at creation;
// readers learn it from the segment's payload size (particle_frame_bytes()).
struct ParticleFrameHeader {
  std::uint64_t sequence;
  double sim_time_s;
  std::uint64_t publish_ns;
  std::uint32_t particle_count;
  std::uint32_t max_particles;
  std::uint32_t body_count;
  float particle_radius_m;
  BodyTransform bodies[kMaxBodies];
};
struct ParticleRecord {
  float position_m[3];
  float scalar;                    // per-particle value for colouring (speed m/s by convention)
};
inline constexpr std::uint64_t particle_frame_bytes(std::uint32_t max_particles) {
  return sizeof(ParticleFrameHeader) + std::uint64_t(max_particles) * sizeof(ParticleRecord);
}

// ---- trace --------------------------------------------------------------------------------
struct TraceDevice {
  std::uint32_t safety_flags;      // safety::Flag bits
  std::uint32_t faults;            // safety::Fault bits
  float force_n[3];                // command sent to the device, device frame
  float torque_nm[3];
  std::uint32_t link_miss_run;     // consecutive ticks without a fresh valid frame
  std::uint32_t fresh;             // 1: a fresh valid frame arrived this tick
  // Wire sequence numbers (protocol.md §3; classic CAN carries their low 8 bits) of the STATE
  // frame whose pose this tick used and of the COMMAND this tick sent, and when that frame
  // arrived. With the fake device's log they tie a pose sample and a command to this tick
  // (hapfluid.motion_to_force_latency).
  std::uint16_t state_sequence;
  std::uint16_t command_sequence;
  std::uint32_t reserved;
  std::uint64_t state_receive_ns;  // DeviceState::host_receive_ns of that frame
};

struct TraceRecord {
  std::uint64_t tick;
  std::uint64_t scheduled_ns;      // absolute wake time the loop asked for
  std::uint64_t wake_ns;           // when it actually woke
  std::int64_t sim_age_ns;         // now - publish time of the newest sim sample; -1: none
  std::uint64_t sim_device_tick;   // device_states tick the newest sim sample was computed from; 0: none
  std::uint64_t sim_publish_ns;    // that sample's publish_ns; 0: none
  std::uint64_t send_ns;           // when this tick's commands began to leave (after the sim read and rendering)
  std::uint32_t compute_ns;        // loop work excluding device I/O
  std::uint32_t io_ns;             // device poll + send
  std::uint32_t loop_flags;        // rt::LoopFlag bits
  std::uint32_t overruns;          // total missed periods so far
  std::uint32_t device_count;
  std::uint32_t reserved;
  TraceDevice devices[kMaxDevices];
};

// Guards: these records cross process boundaries byte for byte. A failing size check means a
// layout changed: bump kAbiVersion, then update the number here.
template <class T>
inline constexpr bool kPlainRecord = std::is_trivially_copyable_v<T> && std::is_standard_layout_v<T>;
static_assert(kPlainRecord<DeviceStatesRecord> && kPlainRecord<SimSample> && kPlainRecord<ParticleFrameHeader> &&
              kPlainRecord<ParticleRecord> && kPlainRecord<TraceRecord>);
static_assert(kAbiVersion == 4 && sizeof(DeviceStatesRecord) == 856 && sizeof(SimSample) == 2696 &&
                  sizeof(ParticleFrameHeader) == 936 && sizeof(ParticleRecord) == 16 && sizeof(TraceRecord) == 304,
              "shm layout changed: bump kAbiVersion and update these sizes");

}  // namespace hapfluid::shm
