#version 450
#extension GL_GOOGLE_include_directive : require
// §5.1: front and back depth of the fluid volume in ONE pass. Instead of two passes with a depth
// test and a reversed depth test (each needing gl_FragDepth, which disables early depth work on a
// software rasteriser), the sphere's front and back depths go to an RG32F colour target with MIN
// blending: R = front depth (min), G = -back depth (min of the negation = max of the back).
#include "common.glsl"

layout(location = 0) in vec2 v_corner;
layout(location = 1) flat in float v_centre_depth;

layout(location = 0) out vec2 out_front_negback;

void main() {
  float q = dot(v_corner, v_corner);
  if (q > 1.0) discard;
  float half_chord = frame.splat.x * sqrt(1.0 - q);
  out_front_negback = vec2(v_centre_depth - half_chord, -(v_centre_depth + half_chord));
}
