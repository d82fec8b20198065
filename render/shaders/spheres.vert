#version 450
#extension GL_GOOGLE_include_directive : require
// Debug mode: every particle as a shaded sphere impostor (instanced camera-facing quad).
#include "common.glsl"

layout(location = 0) in vec4 in_particle;  // xyz: centre m, w: kind (0 fluid, 1 solid)

layout(push_constant) uniform Push { vec4 params; } push;  // x: sphere radius m

layout(location = 0) out vec2 v_corner;
layout(location = 1) flat out vec3 v_centre_view;
layout(location = 2) flat out float v_kind;

const vec2 corners[4] = vec2[](vec2(-1, -1), vec2(1, -1), vec2(-1, 1), vec2(1, 1));

void main() {
  vec2 corner = corners[gl_VertexIndex];
  vec4 view = frame.view * vec4(in_particle.xyz, 1.0);
  v_corner = corner;
  v_centre_view = view.xyz;
  v_kind = in_particle.w;
  // Slightly larger than the sphere so its perspective silhouette fits.
  view.xyz += vec3(corner * push.params.x * 1.05, push.params.x);
  gl_Position = frame.proj * view;
}
