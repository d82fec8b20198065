#version 450
#extension GL_GOOGLE_include_directive : require
// Debug spheres: exact depth through gl_FragDepth (slow on a software rasteriser, debug only).
#include "common.glsl"

layout(push_constant) uniform Push { vec4 params; } push;

layout(location = 0) in vec2 v_corner;
layout(location = 1) flat in vec3 v_centre_view;
layout(location = 2) flat in float v_kind;

layout(location = 0) out vec4 out_colour;
layout(location = 1) out float out_depth;

void main() {
  vec2 c = v_corner * 1.05;
  float q = dot(c, c);
  if (q > 1.0) discard;
  vec3 n = vec3(c, sqrt(1.0 - q));
  vec3 surface = v_centre_view + n * push.params.x;
  vec4 clip = frame.proj * vec4(surface, 1.0);
  gl_FragDepth = clip.z / clip.w;
  vec3 base = v_kind < 0.5 ? vec3(0.2, 0.45, 0.9) : vec3(0.7, 0.6, 0.5);
  float diffuse = max(dot(n, frame.light_dir_view.xyz), 0.0);
  out_colour = vec4(base * (0.25 + 0.75 * diffuse), 1.0);
  out_depth = -surface.z;
}
