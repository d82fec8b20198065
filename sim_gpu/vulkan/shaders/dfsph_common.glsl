// Shared parts of the incompressible solver's passes (the CPU's dfsph_solver.hpp, step by step):
// the cubic spline, the walls' volume map, the solve state and the per-workgroup sums.
//
// Per-particle passes run one invocation per cell-sorted fluid particle (workgroups of 64) and
// sum their pair terms in the CPU's neighbour order: the density pass over the cells
// (NEIGHBOUR_RUNS), which lists each particle's fluid neighbours with their pair gradients; every
// later pass of the step reads that list (FOR_EACH_LISTED).
#include "common.glsl"
layout(local_size_x = 64) in;

layout(std430, binding = BINDING_D_SOLVE) buffer Solve { uint solve[]; };
layout(binding = BINDING_T_D_WALLS) uniform samplerBuffer t_walls;

// The solver's per-particle fields (D_PARTICLE), 12 vec4 per cell-sorted particle k, field m at
// m N + k (N the fluid count): neighbouring invocations read neighbouring entries.
#define D_AT(k, m) dp[(m) * P.counts.x + (k)]
#define D_FIELD(k) D_AT(k, 0u)   // rho / rho0, DFSPH factor (m^2), neighbours, fluid neighbours
#define D_SOLID(k) D_AT(k, 1u)   // sum over static solids and walls of V grad W (1/m), 0
#define D_STIFF(k) D_AT(k, 2u)   // this iteration's stiffness, density total, divergence total (m^2/s^2), 0
#define D_WARM_S(k) D_AT(k, 3u)  // warm starts: density k dt^2, divergence k dt, 0, 0
#define D_DV_S(k) D_AT(k, 4u)    // the last viscosity solve's velocity change, 0
// The viscosity solve: 0 b, 1 inverse diagonal, 2 r, 3 p, 4 A p (or z), 5 the walls' diagonal,
// 6 the start velocity.
#define D_VISC(k, m) D_AT(k, 5u + (m))
// Then the warm starts in the persistent (F) order, as D_WARM_S and D_DV_S, at fields 12 and 13.
#define D_WARM_F(i) D_AT(i, 12u)
#define D_DV_F(i) D_AT(i, 13u)
layout(std430, binding = BINDING_D_PARTICLE) buffer DParticle { vec4 dp[]; };
float walls(int i) { return texelFetch(t_walls, i).x; }
// Neighbours' fields are read through texel views (T_S_VEL, T_D_PARTICLE): on lavapipe a texel
// fetch costs a fraction of a storage-buffer load.
layout(binding = BINDING_T_D_PARTICLE) uniform samplerBuffer t_dp;
layout(binding = BINDING_T_S_VEL) uniform samplerBuffer t_vel;
// The stiffness increments again, packed (D_KAPPA): the pass that applies them reads one float
// per neighbour from a small array instead of one vec4 from the 12 of its fields.
layout(binding = BINDING_T_D_KAPPA) uniform samplerBuffer t_kappa;
#define T_FIELD(j) texelFetch(t_dp, int(j))
#define T_VISC(j, m) texelFetch(t_dp, int((5u + (m)) * P.counts.x + (j)))

// Each particle's fluid neighbours, listed by the density pass in the CPU's neighbour order, and
// read by every later pass of the step instead of the 27 cells' candidates: per pair one vec4,
// V_j grad W_ij (1/m) and the neighbour's index j as a float (exact below 2^24, which the host
// checks), so that a pair costs one fetch of its own and one of the neighbour's field.
layout(binding = BINDING_T_D_LIST) uniform samplerBuffer t_list;
uint list_capacity() { return uint(P.dfsph_d.x); }
// for (...) { LISTED_PAIR; ... LISTED_INDEX ... LISTED_GRADIENT ... } over particle k's list.
// Slot n of particle k's list is entry n N + k (N the fluid count): neighbouring invocations read
// neighbouring entries at every step of their loops.
uint listed_at(uint k, uint n) { return n * P.counts.x + k; }
#define FOR_EACH_LISTED(k) \
  for (uint q_ = listed_at(k, 0u), e_ = listed_at(k, min(uint(D_FIELD(k).w), list_capacity())); q_ < e_; \
       q_ += P.counts.x)
#define LISTED_PAIR vec4 listed_ = texelFetch(t_list, int(q_))
#define LISTED_INDEX uint(listed_.w)
#define LISTED_GRADIENT listed_.xyz

// The solve state (D_SOLVE), mirrored by vulkan_solver.cpp's DfsphState.
#define SOLVE_GROUPS 0          // indirect dispatch arguments of the iterating passes: x, y, z
#define SOLVE_DONE 3            // the running solve has ended
#define SOLVE_ITERATIONS 4      // its iterations, once it has ended
#define SOLVE_CONVERGED 5       // it ended below its tolerance (not at the iteration cap)
#define SOLVE_MEAN 6            // float: the last mean error (pressure) or the CG's |r|^2
#define SOLVE_DENSITY_ITS 7     // counters since the host last read them
#define SOLVE_DIVERGENCE_ITS 8
#define SOLVE_VISCOSITY_ITS 9
#define SOLVE_UNCONVERGED 10
#define SOLVE_EXPLICIT_VISC 11
#define SOLVE_LAST_DENSITY_ERROR 12  // float
#define SOLVE_MAX_DENSITY_ERROR 13   // float, non-negative: its bits order as uints
#define SOLVE_EXPLICIT 14       // this step's viscosity is one explicit step
#define SOLVE_CG_RZ 15          // float: r . z
#define SOLVE_CG_LIMIT 16       // float: |r|^2 at which the CG stops
#define SOLVE_CG_ALPHA 17       // float
#define SOLVE_CG_BETA 18        // float
#define SOLVE_LIST_OVERFLOW 19  // the most fluid neighbours of a particle whose list overflowed
#define SOLVE_MOST_DENSITY_ITS 20     // the most iterations one solve took, since the host last read
#define SOLVE_MOST_DIVERGENCE_ITS 21
#define SOLVE_MOST_VISCOSITY_ITS 22
#define SOLVE_BUDGET_OVERRUNS 23      // solves that ran out of a recorded budget below the cap
#define SOLVE_PARTIALS 32       // 4 floats per workgroup

float solve_float(uint i) { return uintBitsToFloat(solve[i]); }
void set_solve_float(uint i, float v) { solve[i] = floatBitsToUint(v); }
uint fluid_groups() { return uint(P.dfsph_c.w); }

// The cubic spline (cubic_kernel.hpp), same expressions.
float cubic_w(float r) {
  float q = r * P.dfsph_kernel.y;
  float a = 1.0 - q > 0.0 ? 1.0 - q : 0.0;
  float inner = 6.0 * q * q * (q - 1.0) + 1.0;
  return P.dfsph_kernel.z * (q <= 0.5 ? inner : 2.0 * a * a * a);
}
float cubic_grad_over_r(float r) {
  float q = r * P.dfsph_kernel.y;
  float a = 1.0 - q > 0.0 ? 1.0 - q : 0.0;
  float inner = (3.0 * q - 2.0) * P.dfsph_kernel.y;
  float outer = -a * a / (r > 0.0 ? r : 1.0);
  return P.dfsph_kernel.w * (q <= 0.5 ? inner : outer);
}
// V grad W(x_i - x_j) and V W for the offset d = x_i - x_j (within h).
vec4 pair_term(vec3 d, float volume) {
  float r = sqrt(dot(d, d));
  return volume * vec4(cubic_grad_over_r(r) * d, cubic_w(r));
}

// The walls' volume map (WallMap, wall_map.cpp): a header, then four tables over u in [-h, h].
#define WALLS_ENABLED 0   // 6 floats, 1 for a wall
#define WALLS_FACE 6      // 6 floats
#define WALLS_OFFSET 12
#define WALLS_GRADIENT_SCALE 13
#define WALLS_H 14
#define WALLS_DU 15
#define WALLS_SIZE 16     // entries per table
#define WALLS_TABLES 20   // share, slope, friction normal, friction tangent

struct TableAt {
  int i;
  float f;
};
TableAt table_at(float u) {
  float h = walls(WALLS_H), du = walls(WALLS_DU);
  float size = walls(WALLS_SIZE);
  float t = (u + h) / du;
  t = t > 0.0 ? t : 0.0;
  t = min(t, size - 1.0 - 1e-3);
  int i = int(t);
  return TableAt(i, t - float(i));
}
float table_lerp(int table, TableAt a) {
  int base = WALLS_TABLES + table * int(walls(WALLS_SIZE));
  return walls(base + a.i) + a.f * (walls(base + a.i + 1) - walls(base + a.i));
}

// Wall w (x_min, x_max, y_min, y_max, floor, ceiling) as seen from p: whether it is within
// reach, its axis, the normal into the fluid along it, and u (the distance from the face plus the
// offset: the tables' abscissa).
bool wall_within_reach(int w, vec3 p, out int axis, out float inward, out float u) {
  axis = w / 2;
  inward = (w % 2 == 0) ? 1.0 : -1.0;
  u = (p[axis] - walls(WALLS_FACE + w)) * inward + walls(WALLS_OFFSET);
  return walls(WALLS_ENABLED + w) != 0.0 && u < walls(WALLS_H);
}

// WallMap::sample: the walls' share of rho / rho0 at p and its gradient.
float wall_sample(vec3 p, out vec3 gradient) {
  float share[6], grad[6];
  int axis_of[6];
  int n = 0;
  for (int w = 0; w < 6; ++w) {
    int axis;
    float inward, u;
    if (!wall_within_reach(w, p, axis, inward, u)) continue;
    TableAt a = table_at(u);
    share[n] = table_lerp(0, a);
    grad[n] = -inward * table_lerp(1, a) * walls(WALLS_GRADIENT_SCALE);
    axis_of[n] = axis;
    ++n;
  }
  gradient = vec3(0.0);
  if (n == 0) return 0.0;
  float outside = 1.0;
  for (int k = 0; k < n; ++k) outside *= 1.0 - share[k];
  for (int k = 0; k < n; ++k) {
    float others = 1.0;
    for (int o = 0; o < n; ++o)
      if (o != k) others *= 1.0 - share[o];
    gradient[axis_of[k]] += grad[k] * others;
  }
  return 1.0 - outside;
}

// WallMap::friction: the walls' friction integrals per axis at p, 1/m^2.
vec3 wall_friction(vec3 p) {
  vec3 out_ = vec3(0.0);
  for (int w = 0; w < 6; ++w) {
    int axis;
    float inward, u;
    if (!wall_within_reach(w, p, axis, inward, u)) continue;
    TableAt a = table_at(u);
    float normal = table_lerp(2, a), tangent = table_lerp(3, a);
    for (int k = 0; k < 3; ++k) out_[k] += k == axis ? normal : tangent;
  }
  return out_;
}

// Per-workgroup sums: every invocation gives up to 4 values (x, y, z summed; w the maximum) and
// gets the group's totals, in the same order every run: eight invocations fold eight values each,
// then every invocation folds their eight. Two barriers, where a tree of halvings takes seven:
// lavapipe runs a barrier as a switch between the invocations' coroutines, and the tree cost an
// iteration a tenth of its time. Invocations past the fluid give zeros.
shared vec4 group_sum[64];
vec4 fold_two(vec4 a, vec4 b) { return vec4(a.xyz + b.xyz, max(a.w, b.w)); }
vec4 fold_group(vec4 v) {
  uint t = gl_LocalInvocationID.x;
  group_sum[t] = v;
  barrier();
  if (t < 8u) {
    vec4 acc = group_sum[8u * t];
    for (uint k = 1u; k < 8u; ++k) acc = fold_two(acc, group_sum[8u * t + k]);
    group_sum[8u * t] = acc;
  }
  barrier();
  vec4 total = group_sum[0];
  for (uint k = 1u; k < 8u; ++k) total = fold_two(total, group_sum[8u * k]);
  return total;
}

// The group's totals into its partials slot.
void write_group_partial(vec4 v) {
  vec4 total = fold_group(v);
  if (gl_LocalInvocationID.x == 0u) {
    uint o = SOLVE_PARTIALS + 4u * gl_WorkGroupID.x;
    solve[o] = floatBitsToUint(total.x);
    solve[o + 1u] = floatBitsToUint(total.y);
    solve[o + 2u] = floatBitsToUint(total.z);
    solve[o + 3u] = floatBitsToUint(total.w);
  }
}

// The totals of the partials of the last per-particle pass, in one workgroup (every invocation
// gets them): each invocation folds a strided share, then the group folds those.
vec4 total_of_partials() {
  vec4 acc = vec4(0.0);
  for (uint g = gl_LocalInvocationID.x; g < fluid_groups(); g += 64u) {
    uint o = SOLVE_PARTIALS + 4u * g;
    acc.xyz += vec3(uintBitsToFloat(solve[o]), uintBitsToFloat(solve[o + 1u]), uintBitsToFloat(solve[o + 2u]));
    acc.w = max(acc.w, uintBitsToFloat(solve[o + 3u]));
  }
  return fold_group(acc);
}

// The implicit viscosity's pair coefficients (implicit_viscosity.cpp): scale = dt 10 / 2 / rho0
// (2 (d + 2) of the SPH Laplacian in 3D, halved for the mean of two viscosities).
float viscosity_scale() { return P.gravity_dt.w * 10.0 * 0.5 / P.material.z; }
