#version 450
#extension GL_GOOGLE_include_directive : require
// Simple two-sided Lambert shading; writes the scene colour S_c and the scene's linear depth S_d
// that the composite pass (§5.2) needs.
#include "common.glsl"

layout(push_constant) uniform Push {
  mat4 model;
  vec4 colour;
  vec4 params;
} push;

layout(location = 0) in vec3 v_view_position;
layout(location = 1) in vec3 v_view_normal;
layout(location = 2) in vec3 v_world_position;

layout(location = 0) out vec4 out_colour;
layout(location = 1) out float out_depth;

void main() {
  vec3 n = normalize(v_view_normal);
  if (dot(n, -v_view_position) < 0.0) n = -n;
  float diffuse = max(dot(n, frame.light_dir_view.xyz), 0.0);
  vec3 base = push.colour.rgb;
  float square = push.params.x;
  if (square > 0.0) {
    vec2 cell = floor(v_world_position.xy / square);
    base *= (mod(cell.x + cell.y, 2.0) < 0.5) ? 1.0 : 0.45;
  }
  out_colour = vec4(base * (0.3 + 0.7 * diffuse), 1.0);
  out_depth = -v_view_position.z;
}
