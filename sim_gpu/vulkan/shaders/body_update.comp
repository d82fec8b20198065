#version 450
#extension GL_GOOGLE_include_directive : require
// Rigid particles follow their body (eq. 14): x = c + R r, v = v_c + w x (x - c), from the body
// state the host integrated this step (Algorithm 2, line 8).
#include "common.glsl"
layout(local_size_x = 64) in;
layout(std430, binding = BINDING_BODY_STATE) readonly buffer State { vec4 state[]; };
layout(std430, binding = BINDING_B_REST) readonly buffer BRest { vec4 b_rest[]; };
layout(std430, binding = BINDING_B_POS) buffer BPos { vec4 b_pos[]; };
layout(std430, binding = BINDING_B_VEL) buffer BVel { vec4 b_vel[]; };

void main() {
  uint i = gl_GlobalInvocationID.x;
  if (i >= P.counts.z) return;
  vec4 rest = b_rest[i];
  uint s = 8u * uint(rest.w);
  vec3 c = state[s].xyz;
  vec3 r = vec3(dot(state[s + 1u].xyz, rest.xyz), dot(state[s + 2u].xyz, rest.xyz), dot(state[s + 3u].xyz, rest.xyz));
  vec3 x = c + r;
  vec3 v = state[s + 4u].xyz + cross(state[s + 5u].xyz, x - c);
  b_pos[i] = vec4(x, b_pos[i].w);
  b_vel[i] = vec4(v, b_vel[i].w);
}
