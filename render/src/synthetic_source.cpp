#include "hapfluid/render/synthetic_source.hpp"

#include <algorithm>
#include <cmath>

namespace hapfluid::render {
namespace {

// A small deterministic generator (xorshift32): the same particles on every machine.
float unit_noise(uint32_t& state) {
  state ^= state << 13;
  state ^= state >> 17;
  state ^= state << 5;
  return float(state) / 4294967296.0f * 2.0f - 1.0f;
}

}  // namespace

SceneDescription synthetic_scene(double particle_radius_m, config::FluidLook look) {
  SceneDescription d;
  d.name = "synthetic";
  d.particle_radius_m = particle_radius_m;
  d.look = fluid_look(look);
  d.floor_height_m = 0.0;
  d.floor_half_extent_m = 1.0;
  d.look_at_m = glm::vec3(0.0f, 0.0f, 0.15f);
  d.view_distance_m = 1.0;
  return d;
}

SceneDescription synthetic_pool_scene(double particle_radius_m) {
  SceneDescription d = synthetic_scene(particle_radius_m);
  d.floor_half_extent_m = 1.5;
  d.look_at_m = glm::vec3(0.0f, 0.0f, 0.0f);
  d.view_distance_m = 1.7;
  return d;
}

std::vector<glm::vec3> fluid_ball(glm::vec3 centre, double ball_radius, double particle_radius, double jitter,
                                  uint32_t seed) {
  std::vector<glm::vec3> out;
  const double spacing = 2.0 * particle_radius;
  const int n = int(std::ceil(ball_radius / spacing));
  uint32_t state = seed ? seed : 1;
  for (int i = -n; i <= n; ++i)
    for (int j = -n; j <= n; ++j)
      for (int k = -n; k <= n; ++k) {
        glm::vec3 offset = glm::vec3(float(i), float(j), float(k)) * float(spacing);
        if (glm::length(offset) > ball_radius) continue;
        glm::vec3 wobble(unit_noise(state), unit_noise(state), unit_noise(state));
        out.push_back(centre + offset + wobble * float(jitter * spacing));
      }
  return out;
}

std::vector<glm::vec3> fluid_pool(uint32_t count, double particle_radius) {
  // A shallow square pool (about 8 layers for 32,768 particles, like the paper's 1 x 1 m pool),
  // filled layer by layer from the floor, with a little jitter so it does not look like a lattice.
  const int layers = std::max(1, int(std::lround(std::cbrt(double(count)) / 4.0)));
  const int side = int(std::ceil(std::sqrt(double(count) / layers) - 1e-9));
  const float spacing = float(2.0 * particle_radius);
  const float half = 0.5f * float(side - 1) * spacing;
  uint32_t state = 7;
  std::vector<glm::vec3> out;
  out.reserve(count);
  for (int k = 0; out.size() < count; ++k)
    for (int j = 0; j < side && out.size() < count; ++j)
      for (int i = 0; i < side && out.size() < count; ++i) {
        glm::vec3 wobble(unit_noise(state), unit_noise(state), unit_noise(state));
        out.push_back(glm::vec3(float(i) * spacing - half, float(j) * spacing - half,
                                float(particle_radius) + float(k) * spacing) +
                      wobble * (0.1f * spacing));
      }
  return out;
}

SyntheticSource::SyntheticSource(SceneDescription scene, std::vector<Frame> frames, int repeat)
    : scene_(std::move(scene)), frames_(std::move(frames)), repeat_(repeat < 1 ? 1 : repeat) {}

FrameStatus SyntheticSource::next_frame(Frame& frame) {
  if (frames_.empty() || next_ >= frame_count()) return FrameStatus::end_of_stream;
  frame = frames_[size_t(next_ % long(frames_.size()))];
  frame.index = uint64_t(next_);
  ++next_;
  return FrameStatus::new_frame;
}

}  // namespace hapfluid::render
