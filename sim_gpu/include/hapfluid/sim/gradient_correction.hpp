// First-moment correction of the pressure force (eq. 5): symmetric, so momentum is conserved.
//
// Why. The pressure force on particle i, f_i = -V_i sum_j V_j (P_i + P_j) grad W_ij, reproduces
// -V grad P only where the first moment of the kernel gradient, M_i = -sum_j V_j grad W_ij (x)
// r_ij (r_ij = x_i - x_j), is the identity (Randles & Libersky 1996; Bonet & Lok 1999). The
// spiky gradient is scaled so that it is on the rest lattice (scene_setup.cpp), but a settled
// fluid is not a lattice. In the bulk of a settled tank tr(M_i)/3 is a few percent short of 1,
// and the deficit is in the volumes: tr(M_i)/3 = sum_j V_j Wm(r_ij) with Wm(r) = -r W'(r) / 3, a
// kernel that integrates to 1 like W but has no self term, so it is a number-density estimate
// (times V); it falls short because the poly6 density of eq. 2, whose self term W(0) is a fifth
// of the sum at h = 2 spacings, counts more particles per m^3 than the relaxed packing holds,
// and V = m / rho is as much too small. Both volumes of the pair term carry that bias, so the
// force a plane of fluid transmits per pascal is c^2 of its area, and a column at rest needs
// dp/dd = rho0 g / c^2 (sim_gpu/README.md gives the measured bias and the causes ruled out).
//
// The correction. c_i = tr(M_i)/3 per fluid particle, and the particle volumes of the pressure
// force replaced by V_i / c_i, the volumes for which the gradient's first moment is exact:
//   f_i = -sum_j (V_i / c_i) (V_j / c_j) (P_i + P_j) grad W_ij.
// The pair factor 1 / (c_i c_j) is symmetric in i and j, so pair forces stay equal, opposite
// and along r_ij: linear and angular momentum are conserved exactly (unlike the matrix
// correction L_i = M_i^-1 of Bonet & Lok). Solid particles keep their volumes (lattice or Akinci
// volumes): a fluid-solid pair carries 1 / c_i. The one-sided form 2 / (c_i + c_j) corrects only
// the neighbour's volume and leaves half the error.
//
// c_i is computed in the density pass with the particle's own volume for its fluid neighbours
// (V_j ~ V_i within a support radius): c_i = V_i sum_j Wm(r_ij) + sum_b V_b Wm(r_ib), so no extra
// neighbour pass is needed. Near a free surface the neighbourhood is incomplete and c_i drops
// towards 0; that deficit is missing fluid, not a biased volume, and must not inflate the surface
// particles' forces: c_i is clamped to [kGradientCorrectionMin, kGradientCorrectionMax], a band
// the settled bulk lies inside. On the rest lattice c = m / (rho0 s^3) = 0.990 at h = 2 spacings
// (the poly6 self term again), so V / c is the lattice cell s^3.
#pragma once

#include "hapfluid/sim/kernels.hpp"

namespace hapfluid::sim {

inline constexpr float kGradientCorrectionMin = 0.9f;
inline constexpr float kGradientCorrectionMax = 1.1f;

// Shape of the first-moment kernel: Wm(r) = (-spiky_grad / 3) (h - r)^2 r, with hr = h - r.
inline float moment_shape(float r, float hr) { return hr * hr * r; }

// c_i from the density pass's two sums of the moment shape: over fluid neighbours (unweighted,
// times the particle's own volume) and over solid neighbours weighted by their volumes.
inline float gradient_correction(const KernelConstants& k, float own_volume, float fluid_shape_sum,
                                 float solid_shape_sum) {
  const float c = (-k.spiky_grad / 3.0f) * (own_volume * fluid_shape_sum + solid_shape_sum);
  return c < kGradientCorrectionMin ? kGradientCorrectionMin : (c > kGradientCorrectionMax ? kGradientCorrectionMax : c);
}

}  // namespace hapfluid::sim
