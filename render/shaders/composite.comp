#version 450
#extension GL_GOOGLE_include_directive : require
// §5.2: the single full-resolution compositing pass, equation 15:
//   col(p) = lerp(F_c, S_c(p + beta T(p) n.xy), exp(-T(p) F_e)) + k_s (n . h)^alpha
// with T(p) = min(back, S_d) - min(front, S_d); where T = 0 the scene colour is copied.
// The normal n comes from surface_normals.comp (finite differences of the smoothed front depth).
#include "common.glsl"

// One workgroup per 16 x 16 pixel tile that may hold fluid (the 8 x 8 half-resolution tiles of
// the filter); every other pixel was copied from the scene beforehand.
layout(local_size_x = 16, local_size_y = 16) in;

layout(set = 0, binding = 1) uniform sampler2D scene_colour;   // S_c, full resolution, bilinear
layout(set = 0, binding = 2) uniform sampler2D scene_depth;    // S_d, full resolution, linear depth
layout(set = 0, binding = 3) uniform sampler2D smoothed_front; // half resolution
layout(set = 0, binding = 4) uniform sampler2D splat_depth;    // half resolution: (front, -back)
layout(set = 0, binding = 5) uniform writeonly image2D out_colour;
layout(set = 0, binding = 6, std430) readonly buffer FluidTiles { uint fluid_tiles[]; };
layout(set = 0, binding = 7) uniform sampler2D surface_normals; // half resolution, view space

layout(push_constant) uniform Push {
  int mode;                // 0: eq. 15; 1: normals as colour; 2: thickness as grey
  float thickness_scale_m; // mode 2: thickness shown as white
} push;

ivec2 half_size() { return ivec2(frame.half_viewport.xy); }

bool is_fluid(float depth) { return depth <= frame.splat.w; }

void main() {
  uint tile = fluid_tiles[gl_WorkGroupID.x];
  ivec2 pixel = ivec2(uvec2(tile & 0xffffu, tile >> 16) * 16u + gl_LocalInvocationID.xy);
  if (pixel.x >= int(frame.viewport.x) || pixel.y >= int(frame.viewport.y)) return;
  ivec2 texel = min(pixel / 2, half_size() - 1);
  vec4 scene = texelFetch(scene_colour, pixel, 0);
  float front = texelFetch(smoothed_front, texel, 0).r;
  vec4 no_fluid = push.mode == 0 ? scene : vec4(0.0, 0.0, 0.0, 1.0);
  if (!is_fluid(front)) {
    imageStore(out_colour, pixel, no_fluid);
    return;
  }
  float back = -texelFetch(splat_depth, texel, 0).g;
  float scene_d = texelFetch(scene_depth, pixel, 0).r;
  float thickness = min(back, scene_d) - min(front, scene_d);
  if (thickness <= 0.0) {  // the fluid is behind the scene here
    imageStore(out_colour, pixel, no_fluid);
    return;
  }

  vec3 n = texelFetch(surface_normals, texel, 0).xyz;

  vec4 result;
  if (push.mode == 1) {
    result = vec4(n * 0.5 + 0.5, 1.0);
  } else if (push.mode == 2) {
    result = vec4(vec3(clamp(thickness / push.thickness_scale_m, 0.0, 1.0)), 1.0);
  } else {
    vec2 uv = (vec2(pixel) + 0.5) * frame.viewport.zw;
    // Screen v grows downwards while view y grows upwards.
    vec2 refracted_uv = uv + frame.refraction.x * thickness * vec2(n.x, -n.y);
    vec3 behind = textureLod(scene_colour, refracted_uv, 0.0).rgb;
    vec3 transmittance = exp(-thickness * frame.extinction.rgb);
    vec3 surface = view_position(vec2(pixel), frame.viewport.zw, front);
    vec3 h = normalize(frame.light_dir_view.xyz + normalize(-surface));
    vec3 specular = frame.specular.rgb * pow(max(dot(n, h), 0.0), frame.specular.w);
    result = vec4(mix(frame.fluid_colour.rgb, behind, transmittance) + specular, 1.0);
  }
  imageStore(out_colour, pixel, result);
}
