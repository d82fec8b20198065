// What the renderer draws and where it comes from. A FrameSource hands out the scene's static
// description (meshes, particle radius, fluid look) once, then frames of particle positions and
// body poses. Implementations:
//   ReplaySource     - a recorded run of `haptic-sim --out DIR` (VTK frames + bodies.csv)
//   SyntheticSource  - fixed particle sets for tests and benchmarks
//   (shared memory)  - the live sim's particles channel (rt_core's hapfluid_shm): implement
//                      next_frame() as "copy the newest complete frame, never block the writer".
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include "hapfluid/config/mesh.hpp"
#include "hapfluid/render/fluid_look.hpp"

namespace hapfluid::render {

struct BodyPose {
  glm::vec3 position_m{0.0f};
  glm::quat orientation{1.0f, 0.0f, 0.0f, 0.0f};  // (w, x, y, z)
};

// A rigid body drawn from its mesh; its pose comes with each frame (Frame::body_poses[i]).
struct BodyMesh {
  std::string name;
  config::TriangleMesh mesh;  // in the body's mesh frame, metres before `scale`
  double scale = 1.0;
  glm::vec3 colour{0.75f, 0.72f, 0.68f};
  BodyPose initial_pose;      // the scene file's pose, used until a frame says otherwise
};

// The simulation domain's side walls (the container the fluid sits in). Only the walls behind
// the fluid as seen from the camera are drawn, so the box never hides what is inside it.
struct ContainerWalls {
  bool present = false;
  glm::vec3 min_m{0.0f}, max_m{0.0f};
  bool x_min = false, x_max = false, y_min = false, y_max = false;
};

struct SceneDescription {
  std::string name;
  std::vector<BodyMesh> bodies;
  double particle_radius_m = 0.01;  // half the particle spacing; splats are 1.2x this (§5.1)
  FluidLook look = fluid_look(config::FluidLook::water);
  double floor_height_m = 0.0;      // z of the checkered floor (z is up)
  double floor_half_extent_m = 1.0;
  glm::vec3 look_at_m{0.0f};        // where the camera looks by default
  double view_distance_m = 1.5;     // default camera distance
  ContainerWalls walls;
};

// A haptic device's rendered force, for the on-screen force bars (from the device-states
// channel in live mode; replays have none).
struct DeviceForce {
  std::string device;
  float force_n = 0.0f;
  float max_force_n = 1.0f;  // the rig's limit: a full bar
};

struct Frame {
  std::uint64_t index = 0;
  double sim_time_s = 0.0;
  std::vector<glm::vec3> fluid_m;   // fluid particle centres
  std::vector<glm::vec3> solid_m;   // boundary and body particles (debug spheres mode only)
  std::vector<BodyPose> body_poses; // one per SceneDescription::bodies entry
  std::vector<DeviceForce> device_forces;
  double sim_steps_per_s = 0.0;     // as reported by the simulator, 0 when unknown
};

enum class FrameStatus {
  new_frame,     // `frame` was overwritten with a newer frame
  unchanged,     // nothing newer yet (live sources); `frame` is untouched
  end_of_stream  // a finite source is exhausted
};

class FrameSource {
 public:
  virtual ~FrameSource() = default;
  virtual const SceneDescription& scene() const = 0;
  // Never blocks for long: a live source returns `unchanged` when the writer has nothing newer.
  virtual FrameStatus next_frame(Frame& frame) = 0;
  // Frames this source will produce in total, or -1 when unknown (live sources).
  virtual long frame_count() const { return -1; }
};

}  // namespace hapfluid::render
