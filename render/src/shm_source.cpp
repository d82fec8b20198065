#include "hapfluid/render/shm_source.hpp"

#include <cmath>
#include <cstdio>
#include <cstring>

#include "hapfluid/config/log.hpp"
#include "hapfluid/shm/layouts.hpp"

namespace hapfluid::render {
namespace {
constexpr std::uint64_t kNsPerS = 1'000'000'000ull;
}

ShmSource::ShmSource(SceneDescription scene, ShmSourceOptions options)
    : scene_(std::move(scene)), options_(std::move(options)) {}

void ShmSource::attach_if_due(std::uint64_t now_ns) {
  if (particles_.valid() && now_ns >= next_liveness_ns_) {
    next_liveness_ns_ = now_ns + std::uint64_t(options_.reattach_interval_s * kNsPerS);
    status_ = particles_.check_liveness(now_ns, std::uint64_t(options_.stale_after_s * kNsPerS));
    if (status_ == shm::WriterStatus::dead || status_ == shm::WriterStatus::replaced ||
        status_ == shm::WriterStatus::closed || status_ == shm::WriterStatus::corrupt) {
      log::notice("the simulator's particles channel is %s: waiting for a new writer",
                  shm::to_string(status_));
      particles_ = shm::LatestReader();
      devices_ = shm::LatestReader();
    }
  }
  if (particles_.valid() || now_ns < next_attach_ns_) return;
  next_attach_ns_ = now_ns + std::uint64_t(options_.reattach_interval_s * kNsPerS);
  const std::string name = shm::segment_name(options_.prefix, shm::ChannelKind::particles);
  try {
    // Payload size 0: the writer chose max_particles; check the frame layout ourselves.
    shm::LatestReader reader = shm::LatestReader::attach(name, shm::ChannelKind::particles, 0);
    const std::uint64_t bytes = reader.segment().layout().payload_bytes;
    if (bytes < sizeof(shm::ParticleFrameHeader) ||
        (bytes - sizeof(shm::ParticleFrameHeader)) % sizeof(shm::ParticleRecord) != 0) {
      log::warning("%s holds %llu-byte records, not particle frames: ignoring it",
                   name.c_str(), (unsigned long long)bytes);
      return;
    }
    buffer_.assign(bytes, std::byte{0});
    incarnation_ = reader.segment().layout().incarnation;
    particles_ = std::move(reader);
    last_generation_ = 0;
    status_ = shm::WriterStatus::live;
    log::info("attached to %s (up to %llu particles)", name.c_str(),
              (unsigned long long)((bytes - sizeof(shm::ParticleFrameHeader)) / sizeof(shm::ParticleRecord)));
  } catch (const shm::ShmError&) {
    status_ = shm::WriterStatus::not_attached;  // no simulator yet: try again later, quietly
  }
  if (!devices_.valid()) {
    try {
      devices_ = shm::LatestReader::attach(shm::segment_name(options_.prefix, shm::ChannelKind::device_states),
                                           shm::ChannelKind::device_states, sizeof(shm::DeviceStatesRecord));
    } catch (const shm::ShmError&) {
      // The force bars are optional: no loop running means no bars.
    }
  }
}

void ShmSource::read_device_forces(Frame& frame) {
  frame.device_forces.clear();
  if (!devices_.valid()) return;
  shm::DeviceStatesRecord record;
  if (devices_.try_read(record) != shm::ReadResult::ok) return;
  for (std::uint32_t i = 0; i < record.device_count && i < std::uint32_t(shm::kMaxDevices); ++i) {
    const auto& d = record.devices[i];
    if (!d.present) continue;
    DeviceForce f;
    f.device.assign(d.name, strnlen(d.name, sizeof d.name));
    f.force_n = float(std::sqrt(d.force_n[0] * d.force_n[0] + d.force_n[1] * d.force_n[1] + d.force_n[2] * d.force_n[2]));
    f.max_force_n = float(options_.max_force_n);
    frame.device_forces.push_back(f);
  }
}

FrameStatus ShmSource::next_frame(Frame& frame) {
  const std::uint64_t now = shm::monotonic_ns();
  attach_if_due(now);
  if (!particles_.valid()) return FrameStatus::unchanged;
  std::uint64_t generation = 0;
  if (particles_.try_read(buffer_.data(), buffer_.size(), &generation) != shm::ReadResult::ok ||
      generation == last_generation_)
    return FrameStatus::unchanged;
  last_generation_ = generation;

  shm::ParticleFrameHeader header;
  std::memcpy(&header, buffer_.data(), sizeof header);
  const std::uint32_t capacity = std::uint32_t((buffer_.size() - sizeof header) / sizeof(shm::ParticleRecord));
  const std::uint32_t count = std::min(header.particle_count, capacity);
  frame.index = header.sequence;
  frame.sim_time_s = header.sim_time_s;
  frame.fluid_m.resize(count);
  frame.solid_m.clear();
  const std::byte* records = buffer_.data() + sizeof header;
  for (std::uint32_t i = 0; i < count; ++i) {
    shm::ParticleRecord r;
    std::memcpy(&r, records + std::size_t(i) * sizeof r, sizeof r);
    frame.fluid_m[i] = glm::vec3(r.position_m[0], r.position_m[1], r.position_m[2]);
  }
  frame.body_poses.resize(scene_.bodies.size());
  for (std::size_t b = 0; b < scene_.bodies.size(); ++b) {
    if (b >= header.body_count || b >= std::size_t(shm::kMaxBodies)) {
      frame.body_poses[b] = scene_.bodies[b].initial_pose;
      continue;
    }
    const auto& t = header.bodies[b];
    frame.body_poses[b].position_m = glm::vec3(t.position_m[0], t.position_m[1], t.position_m[2]);
    frame.body_poses[b].orientation =
        glm::quat(float(t.orientation[0]), float(t.orientation[1]), float(t.orientation[2]), float(t.orientation[3]));
  }
  // The simulator's step rate, from the step counter it stamps on frames, over >= 0.5 s windows.
  if (rate_publish_ns_ == 0 || header.sequence < rate_sequence_) {
    rate_sequence_ = header.sequence;
    rate_publish_ns_ = header.publish_ns;
  } else if (header.publish_ns > rate_publish_ns_ + kNsPerS / 2) {
    steps_per_s_ = double(header.sequence - rate_sequence_) * kNsPerS / double(header.publish_ns - rate_publish_ns_);
    rate_sequence_ = header.sequence;
    rate_publish_ns_ = header.publish_ns;
  }
  frame.sim_steps_per_s = steps_per_s_;
  read_device_forces(frame);
  return FrameStatus::new_frame;
}

}  // namespace hapfluid::render
