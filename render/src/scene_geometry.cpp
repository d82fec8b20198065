#include "scene_geometry.hpp"

namespace hapfluid::render {

SceneGeometry build_scene_geometry(const SceneDescription& scene) {
  SceneGeometry g;
  // Floor: a square around the look-at point, ten checker squares across.
  const float e = float(scene.floor_half_extent_m);
  const float z = float(scene.floor_height_m);
  const glm::vec2 c{scene.look_at_m.x, scene.look_at_m.y};
  g.checker_size_m = scene.floor_half_extent_m / 5.0;
  const glm::vec3 up{0, 0, 1};
  const glm::vec3 corners[4] = {{c.x - e, c.y - e, z}, {c.x + e, c.y - e, z}, {c.x + e, c.y + e, z}, {c.x - e, c.y + e, z}};
  for (int i : {0, 1, 2, 0, 2, 3}) g.vertices.push_back({corners[i], up});
  g.draws.push_back({0, 6, -1, 1.0, glm::vec3(0.85f, 0.85f, 0.82f), float(g.checker_size_m)});

  const ContainerWalls& w = scene.walls;
  if (w.present) {
    const glm::vec3 lo = w.min_m, hi = w.max_m;
    auto wall = [&](glm::vec3 a, glm::vec3 b, glm::vec3 c, glm::vec3 d, glm::vec3 inward) {
      DrawRange range;
      range.first_vertex = uint32_t(g.vertices.size());
      for (const glm::vec3& p : {a, b, c, a, c, d}) g.vertices.push_back({p, inward});
      range.vertex_count = 6;
      range.colour = glm::vec3(0.78f, 0.80f, 0.83f);
      range.wall = true;
      range.wall_point_m = a;
      range.wall_inward_normal = inward;
      g.draws.push_back(range);
    };
    if (w.x_min) wall({lo.x, lo.y, lo.z}, {lo.x, hi.y, lo.z}, {lo.x, hi.y, hi.z}, {lo.x, lo.y, hi.z}, {1, 0, 0});
    if (w.x_max) wall({hi.x, lo.y, lo.z}, {hi.x, hi.y, lo.z}, {hi.x, hi.y, hi.z}, {hi.x, lo.y, hi.z}, {-1, 0, 0});
    if (w.y_min) wall({lo.x, lo.y, lo.z}, {hi.x, lo.y, lo.z}, {hi.x, lo.y, hi.z}, {lo.x, lo.y, hi.z}, {0, 1, 0});
    if (w.y_max) wall({lo.x, hi.y, lo.z}, {hi.x, hi.y, lo.z}, {hi.x, hi.y, hi.z}, {lo.x, hi.y, hi.z}, {0, -1, 0});
  }

  for (size_t b = 0; b < scene.bodies.size(); ++b) {
    const BodyMesh& body = scene.bodies[b];
    DrawRange range;
    range.first_vertex = uint32_t(g.vertices.size());
    range.body = int(b);
    range.scale = body.scale;
    range.colour = body.colour;
    for (const auto& tri : body.mesh.triangles) {
      glm::vec3 p[3];
      for (int k = 0; k < 3; ++k) {
        const auto& v = body.mesh.vertices_m.at(tri[k]);
        p[k] = glm::vec3(float(v.x), float(v.y), float(v.z));
      }
      glm::vec3 n = glm::cross(p[1] - p[0], p[2] - p[0]);
      const float len = glm::length(n);
      if (len <= 0.0f) continue;  // degenerate triangle
      n /= len;
      for (int k = 0; k < 3; ++k) g.vertices.push_back({p[k], n});
    }
    range.vertex_count = uint32_t(g.vertices.size()) - range.first_vertex;
    g.draws.push_back(range);
  }
  return g;
}

}  // namespace hapfluid::render
