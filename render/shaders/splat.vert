#version 450
#extension GL_GOOGLE_include_directive : require
// §5.1: each fluid particle as a point splat: one camera-facing triangle circumscribing the splat
// disc (no point-size limit). On a software rasteriser the cost per primitive (assembly,
// clipping, set-up) dominates the few fragments of a splat, so one triangle beats a two-triangle
// quad, and one plain draw of 3 vertices per particle beats instancing (paid per instance).
#include "common.glsl"

layout(set = 0, binding = 1, std430) readonly buffer FluidParticles { float fluid_xyz_m[]; };

layout(location = 0) out vec2 v_corner;
layout(location = 1) flat out float v_centre_depth;

// Equilateral triangle whose inscribed circle is the unit disc.
const vec2 corners[3] = vec2[](vec2(0.0, 2.0), vec2(-1.7320508, -1.0), vec2(1.7320508, -1.0));

void main() {
  int particle = gl_VertexIndex / 3;
  vec2 corner = corners[gl_VertexIndex - 3 * particle];
  vec3 centre = vec3(fluid_xyz_m[3 * particle], fluid_xyz_m[3 * particle + 1], fluid_xyz_m[3 * particle + 2]);
  vec4 view = frame.view * vec4(centre, 1.0);
  v_corner = corner;
  v_centre_depth = -view.z;
  view.xy += corner * frame.splat.x;
  gl_Position = frame.proj * view;
}
