// The live frame source: the simulator's particles channel (and the loop's device-states channel
// for the force bars), read through rt_core's hapfluid_shm. It copies the newest complete frame
// and never blocks or slows the writer; with no writer yet, or after the writer died or was
// restarted, it keeps answering `unchanged` and re-attaches in the background of next_frame().
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "hapfluid/render/frame_source.hpp"
#include "hapfluid/shm/channel.hpp"

namespace hapfluid::render {

struct ShmSourceOptions {
  std::string prefix = "hapfluid";   // segments /<prefix>.particles and /<prefix>.device_states
  double max_force_n = 10.0;         // a full force bar (the rig's limit when known)
  double reattach_interval_s = 0.25; // how often to look for a (new) writer
  double stale_after_s = 1.0;        // no heartbeat for this long: the writer is stale
};

class ShmSource final : public FrameSource {
 public:
  ShmSource(SceneDescription scene, ShmSourceOptions options);

  const SceneDescription& scene() const override { return scene_; }
  FrameStatus next_frame(Frame& frame) override;

  // What the source last concluded about the simulator (for logs and tests).
  shm::WriterStatus writer_status() const { return status_; }

 private:
  void attach_if_due(std::uint64_t now_ns);
  void read_device_forces(Frame& frame);

  SceneDescription scene_;
  ShmSourceOptions options_;
  shm::LatestReader particles_;
  shm::LatestReader devices_;
  std::vector<std::byte> buffer_;    // one particle frame, sized from the writer's segment
  std::uint64_t incarnation_ = 0;
  std::uint64_t last_generation_ = 0;
  std::uint64_t next_attach_ns_ = 0;
  std::uint64_t next_liveness_ns_ = 0;
  std::uint64_t rate_sequence_ = 0, rate_publish_ns_ = 0;
  double steps_per_s_ = 0;
  shm::WriterStatus status_ = shm::WriterStatus::not_attached;
};

}  // namespace hapfluid::render
