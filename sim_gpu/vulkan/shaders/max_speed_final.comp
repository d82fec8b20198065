#version 450
#extension GL_GOOGLE_include_directive : require
// CFL inputs, pass 2 of 2: one workgroup folds the partial maxima into reduce[1] (speed^2)
// and reduce[2] (acceleration^2).
#include "common.glsl"
layout(local_size_x = 256) in;
layout(push_constant) uniform Push { uint groups; uint pad0, pad1, pad2; } pc;
layout(std430, binding = BINDING_REDUCE) buffer Reduce { uint reduce[]; };
shared uint speed[256];
shared uint accel[256];

void main() {
  uint t = gl_LocalInvocationID.x;
  uint vs = 0u, as = 0u;
  for (uint g = t; g < pc.groups; g += 256u) {
    vs = max(vs, reduce[4u + 2u * g]);
    as = max(as, reduce[5u + 2u * g]);
  }
  speed[t] = vs;
  accel[t] = as;
  barrier();
  for (uint s = 128u; s > 0u; s >>= 1) {
    if (t < s) {
      speed[t] = max(speed[t], speed[t + s]);
      accel[t] = max(accel[t], accel[t + s]);
    }
    barrier();
  }
  if (t == 0u) {
    reduce[1] = speed[0];
    reduce[2] = accel[0];
  }
}
