// Fixed particle sets for tests, benchmarks and `haptic-render --synthetic`: no simulator needed.
#pragma once

#include <cstdint>

#include "hapfluid/render/frame_source.hpp"

namespace hapfluid::render {

// A 1 m checkered floor at z = 0, no bodies, particles of `particle_radius_m`, camera on the ball.
SceneDescription synthetic_scene(double particle_radius_m, config::FluidLook look = config::FluidLook::water);

// The benchmark's view: the same floor, 3 m across, the camera 1.7 m from the pool's centre.
SceneDescription synthetic_pool_scene(double particle_radius_m);

// Particles on a cubic lattice of spacing 2 x particle radius filling a ball, with a small
// deterministic jitter (fraction of the spacing) so splats are not perfectly regular.
std::vector<glm::vec3> fluid_ball(glm::vec3 centre_m, double ball_radius_m, double particle_radius_m,
                                  double jitter_fraction = 0.15, uint32_t seed = 1);
// Exactly `count` particles on a jittered lattice filling a shallow square pool resting on the
// floor, centred at (0, 0): the benchmark's pool (32,768 particles of radius 8 mm: 1 m square).
std::vector<glm::vec3> fluid_pool(uint32_t count, double particle_radius_m);

class SyntheticSource final : public FrameSource {
 public:
  // Plays `frames` once, then reports end_of_stream (repeat > 1 plays them that many times).
  SyntheticSource(SceneDescription scene, std::vector<Frame> frames, int repeat = 1);
  const SceneDescription& scene() const override { return scene_; }
  FrameStatus next_frame(Frame& frame) override;
  long frame_count() const override { return long(frames_.size()) * repeat_; }

 private:
  SceneDescription scene_;
  std::vector<Frame> frames_;
  int repeat_;
  long next_ = 0;
};

}  // namespace hapfluid::render
