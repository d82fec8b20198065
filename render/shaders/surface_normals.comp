#version 450
#extension GL_GOOGLE_include_directive : require
// §5.2: "The normal n is computed using finite difference on the front fluid surface depth [21]",
// once per half-resolution texel of the smoothed depth (a quarter of the composite's pixels),
// choosing the one-sided difference with the smaller depth change so silhouettes do not bend
// normals. Only the fluid tiles are dispatched; texels without fluid are never read.
#include "common.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 0, binding = 1) uniform sampler2D smoothed_front;
layout(set = 0, binding = 2) uniform writeonly image2D normals;  // view space, xyz
layout(set = 0, binding = 3, std430) readonly buffer FluidTiles { uint fluid_tiles[]; };

ivec2 half_size() { return ivec2(frame.half_viewport.xy); }

float front_at(ivec2 texel) {
  return texelFetch(smoothed_front, clamp(texel, ivec2(0), half_size() - 1), 0).r;
}

bool is_fluid(float depth) { return depth <= frame.splat.w; }

vec3 tangent(ivec2 texel, vec3 centre, ivec2 step) {
  float zp = front_at(texel + step), zm = front_at(texel - step);
  vec3 forward = view_position(vec2(texel + step), frame.half_viewport.zw, zp) - centre;
  vec3 backward = centre - view_position(vec2(texel - step), frame.half_viewport.zw, zm);
  bool use_forward = is_fluid(zp) && (!is_fluid(zm) || abs(forward.z) <= abs(backward.z));
  if (use_forward) return forward;
  if (is_fluid(zm)) return backward;
  // Isolated texel: a screen-aligned tangent, so the normal faces the camera.
  return view_position(vec2(texel + step), frame.half_viewport.zw, -centre.z) - centre;
}

void main() {
  uint tile = fluid_tiles[gl_WorkGroupID.x];
  ivec2 texel = ivec2(uvec2(tile & 0xffffu, tile >> 16) * 8u + gl_LocalInvocationID.xy);
  if (texel.x >= half_size().x || texel.y >= half_size().y) return;
  float front = texelFetch(smoothed_front, texel, 0).r;
  if (!is_fluid(front)) return;
  vec3 centre = view_position(vec2(texel), frame.half_viewport.zw, front);
  vec3 n = normalize(cross(tangent(texel, centre, ivec2(1, 0)), tangent(texel, centre, ivec2(0, 1))));
  if (dot(n, -centre) < 0.0) n = -n;
  imageStore(normals, texel, vec4(n, 0.0));
}
