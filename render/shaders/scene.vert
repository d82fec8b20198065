#version 450
#extension GL_GOOGLE_include_directive : require
// The scene behind the fluid: floor and body meshes (flat normals), drawn at full resolution.
#include "common.glsl"

layout(location = 0) in vec3 in_position_m;
layout(location = 1) in vec3 in_normal;

layout(push_constant) uniform Push {
  mat4 model;    // mesh frame -> world (rotation, translation, uniform scale)
  vec4 colour;   // base colour (rgb)
  vec4 params;   // x: checker square size m (0: plain)
} push;

layout(location = 0) out vec3 v_view_position;
layout(location = 1) out vec3 v_view_normal;
layout(location = 2) out vec3 v_world_position;

void main() {
  vec4 world = push.model * vec4(in_position_m, 1.0);
  vec4 view = frame.view * world;
  v_view_position = view.xyz;
  v_view_normal = mat3(frame.view) * mat3(push.model) * in_normal;
  v_world_position = world.xyz;
  gl_Position = frame.proj * view;
}
