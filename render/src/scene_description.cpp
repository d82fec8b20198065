#include "hapfluid/render/scene_description.hpp"

#include <algorithm>
#include <cmath>

#include "hapfluid/config/mesh.hpp"
#include "hapfluid/config/primitive_meshes.hpp"

namespace hapfluid::render {

SceneDescription describe_scene(const config::Scene& scene) {
  SceneDescription d;
  d.name = scene.name;
  // The particle radius is half the spacing; the splats use 1.2x of it (§5.1).
  d.particle_radius_m = 0.5 * scene.fluid.particle_spacing_m;
  d.look = fluid_look(scene.fluid.look);
  const auto& box = scene.domain.box;
  const glm::vec3 lo(box.min_m.x, box.min_m.y, box.min_m.z), hi(box.max_m.x, box.max_m.y, box.max_m.z);
  d.floor_height_m = lo.z;
  d.floor_half_extent_m = 0.75 * std::max(hi.x - lo.x, hi.y - lo.y);
  d.look_at_m = glm::vec3(0.5f * (lo.x + hi.x), 0.5f * (lo.y + hi.y), lo.z + 0.3f * (hi.z - lo.z));
  d.view_distance_m = 1.4 * glm::length(hi - lo);
  const auto& w = scene.domain.walls;
  d.walls = {true, lo, hi, w.x_min, w.x_max, w.y_min, w.y_max};
  // Distinguishable tool colours: steel, wood, ceramic, red plastic.
  const glm::vec3 palette[] = {{0.75f, 0.76f, 0.78f}, {0.70f, 0.52f, 0.32f}, {0.92f, 0.90f, 0.86f}, {0.80f, 0.25f, 0.20f}};
  for (size_t i = 0; i < scene.bodies.size(); ++i) {
    const auto& b = scene.bodies[i];
    BodyMesh mesh;
    mesh.name = b.name;
    // A device's probe (a particle body) has no mesh: a ball of the fluid's particle size.
    mesh.mesh = b.shape == config::BodyShape::particle ? config::primitives::sphere_mesh(d.particle_radius_m, 1)
                                                       : config::load_mesh(b.mesh);
    mesh.scale = b.scale;
    mesh.colour = palette[i % 4];
    mesh.initial_pose.position_m = glm::vec3(b.pose.position_m.x, b.pose.position_m.y, b.pose.position_m.z);
    mesh.initial_pose.orientation = glm::quat(float(b.pose.orientation.w), float(b.pose.orientation.x),
                                              float(b.pose.orientation.y), float(b.pose.orientation.z));
    d.bodies.push_back(std::move(mesh));
  }
  return d;
}

}  // namespace hapfluid::render
