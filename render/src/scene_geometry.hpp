// The scene's triangles on the GPU: a checkered floor and every body mesh, expanded to flat-shaded
// triangles (per-face normals) in one vertex buffer, with one draw range per body.
#pragma once

#include <vector>

#include <glm/glm.hpp>

#include "hapfluid/render/frame_source.hpp"

namespace hapfluid::render {

struct SceneVertex {
  glm::vec3 position_m;
  glm::vec3 normal;
};

struct DrawRange {
  uint32_t first_vertex = 0, vertex_count = 0;
  int body = -1;                 // index into SceneDescription::bodies; -1: static (the floor)
  double scale = 1.0;
  glm::vec3 colour{1.0f};
  float checker_size_m = 0.0f;   // > 0: checkerboard
  // A container wall: drawn only while the eye is on the inner side of this plane
  // (inward normal . (eye - point) > 0), i.e. when the wall is behind the fluid.
  bool wall = false;
  glm::vec3 wall_point_m{0.0f}, wall_inward_normal{0.0f};
};

struct SceneGeometry {
  std::vector<SceneVertex> vertices;
  std::vector<DrawRange> draws;
  double checker_size_m = 0.0;
};

SceneGeometry build_scene_geometry(const SceneDescription& scene);

}  // namespace hapfluid::render
