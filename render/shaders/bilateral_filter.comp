#version 450
#extension GL_GOOGLE_include_directive : require
// §5.1, fig. 5: the fast bilateral filter of the front fluid depth. One inner sample S_i (weight
// 2.0) and four outer samples S_o (weight 4.0 each, times a range weight on their depth
// difference to S_i). Each outer sample sits on a texel corner so hardware bilinear filtering
// returns the average of four depths: 1 + 4 x 4 = 17 depths from 5 texture samples. The four
// outer samples form a pinwheel around the centre so the 16 averaged texels are all distinct.
// An outer sample is used only if its four depths are all fluid (their average stays below the
// no-fluid threshold, since a no-fluid texel holds a depth far above it).
#include "common.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 0, binding = 1) uniform sampler2D source_depth;  // .r: front depth, bilinear
layout(set = 0, binding = 2) uniform writeonly image2D smoothed_depth;
// Only the 8 x 8 tiles that splats may touch are dispatched (tile x | y << 16, one workgroup
// each); the rest of the target was cleared to "no fluid" (see fluid_tiles.hpp).
layout(set = 0, binding = 3, std430) readonly buffer FluidTiles { uint fluid_tiles[]; };

const float inner_weight = 2.0;
const float outer_weight = 4.0;
// Offsets from the texel centre, in texels, to a corner shared by four texels (pinwheel).
const vec2 outer_offsets[4] = vec2[](vec2(1.5, 0.5), vec2(-0.5, 1.5), vec2(-1.5, -0.5), vec2(0.5, -1.5));

void main() {
  uint tile = fluid_tiles[gl_WorkGroupID.x];
  ivec2 pixel = ivec2(uvec2(tile & 0xffffu, tile >> 16) * 8u + gl_LocalInvocationID.xy);
  if (pixel.x >= int(frame.half_viewport.x) || pixel.y >= int(frame.half_viewport.y)) return;
  float inner = texelFetch(source_depth, pixel, 0).r;
  if (inner > frame.splat.w) {  // no fluid here: nothing to smooth
    imageStore(smoothed_depth, pixel, vec4(inner));
    return;
  }
  float inv_two_sigma2 = 1.0 / (2.0 * frame.splat.y * frame.splat.y);
  float sum = inner_weight * inner;
  float weight_sum = inner_weight;
  vec2 centre = vec2(pixel) + 0.5;
  for (int i = 0; i < 4; ++i) {
    float outer = textureLod(source_depth, (centre + outer_offsets[i]) * frame.half_viewport.zw, 0.0).r;
    if (outer > frame.splat.w) continue;  // one of the four averaged depths is not fluid
    float difference = outer - inner;
    float w = outer_weight * exp(-difference * difference * inv_two_sigma2);
    sum += w * outer;
    weight_sum += w;
  }
  imageStore(smoothed_depth, pixel, vec4(sum / weight_sum));
}
