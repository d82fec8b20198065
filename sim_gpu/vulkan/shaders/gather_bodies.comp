#version 450
#extension GL_GOOGLE_include_directive : require
// Dynamic body particles into cell order for neighbour queries (CpuSolver::build_body_view):
// V[k] = B[order[k]] with the body index and the source index alongside.
#include "common.glsl"
layout(local_size_x = 64) in;
layout(std430, binding = BINDING_ORDER) readonly buffer Order { uint order[]; };
layout(std430, binding = BINDING_B_POS) readonly buffer BPos { vec4 b_pos[]; };
layout(std430, binding = BINDING_B_VEL) readonly buffer BVel { vec4 b_vel[]; };
layout(std430, binding = BINDING_B_REST) readonly buffer BRest { vec4 b_rest[]; };
layout(std430, binding = BINDING_V_A) writeonly buffer VA { vec4 v_a[]; };
layout(std430, binding = BINDING_V_B) writeonly buffer VB { vec4 v_b[]; };
layout(std430, binding = BINDING_V_C) writeonly buffer VC { vec4 v_c[]; };

void main() {
  uint k = gl_GlobalInvocationID.x;
  if (k >= P.counts.z) return;
  uint i = order[P.counts.x + k];
  v_a[k] = b_pos[i];
  v_b[k] = b_vel[i];
  v_c[k] = vec4(0.0, b_rest[i].w, float(i), 0.0);
}
