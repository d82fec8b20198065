#version 450
#extension GL_GOOGLE_include_directive : require
// §5.1: each fluid particle as a point splat. An instanced camera-facing quad sized exactly to the
// splat disc (no point-size limit, no wasted fragments beyond the disc's bounding square).
#include "common.glsl"

layout(location = 0) in vec3 in_centre_m;

layout(location = 0) out vec2 v_corner;
layout(location = 1) flat out float v_centre_depth;

const vec2 corners[4] = vec2[](vec2(-1, -1), vec2(1, -1), vec2(-1, 1), vec2(1, 1));

void main() {
  vec2 corner = corners[gl_VertexIndex];
  vec4 view = frame.view * vec4(in_centre_m, 1.0);
  v_corner = corner;
  v_centre_depth = -view.z;
  view.xy += corner * frame.splat.x;
  gl_Position = frame.proj * view;
}
