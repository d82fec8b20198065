// Damping of rigid contacts (body <-> wall, body <-> body).
//
// Why. Solids push each other apart through the same particle pressure as the fluid: each body
// particle gets the contact pressure k rho0 sum_c V_c W over the other solid's particles, and the
// pair force -V_i V_c (P_i + P_c) grad W (cpu_solver.cpp). That is a pure spring: a ball dropped
// 10 cm onto the floor came back to 9.9 cm (coefficient of restitution 0.99) and bounced for
// ever. Two dissipative terms act between solid particles:
//  - eq. 9 of the paper, V_i V_c (mu_i + mu_c) / 2 (v_c - v_i) lap W, with the bodies' (and the
//    walls') viscosities, as between a body and the fluid. It damps sliding as well as approach,
//    but at the viscosities the scenes use (0.001-40 Pa s) it is far too weak for an impact
//    (sim_gpu/README.md gives the restitutions).
//  - Monaghan's artificial viscosity (Monaghan 1992, "Smoothed particle hydrodynamics", Annu.
//    Rev. Astron. Astrophys. 30, eq. 4.1 with beta = 0), the standard SPH damping of colliding
//    particles: an extra pair pressure
//        Pi_ij = alpha rho0 c h max(0, -v_ij . r_ij) / (r_ij^2 + 0.01 h^2)
//    added to P_i + P_j in the contact pair term, only while the particles approach. Its force
//    is along r_ij and the same for both particles of a pair, so momentum and angular momentum
//    are conserved, and it never pulls a separating contact together. With the contact
//    stiffness k rho0 = c^2 rho0 and the damping proportional to c, the damping ratio of a
//    contact does not depend on the scene's speed of sound.
//
// kContactArtificialViscosity (alpha) = 10, larger than the 0.01-1 of fluid shocks: a contact
// is one or two particle layers deep, not a bulk of pairs. It is chosen for the restitution of a
// ball dropped 10 cm on the floor: 0.80 at alpha = 1, 0.59 at 3, 0.33-0.42 at 10 (c = 10-20 m/s,
// ball density 400-2000 kg/m^3), no rebound at 30 (tests/sim_gpu/test_rigid_bodies.cpp). Its
// equivalent viscosity, alpha rho0 c h / 10 (Monaghan 2005, 3D), is rho0 c h: ~200 Pa s at
// c = 10 m/s and h = 2 cm; eq. 9 alone reached that restitution only with a body viscosity
// between 50 and 500 Pa s. It acts between solid particles only, never on the fluid.
#pragma once

namespace hapfluid::sim {

inline constexpr float kContactArtificialViscosity = 10.0f;

// alpha rho0 c h, Pa s: the scale of Pi_ij (SimulationParams::contact_damping_pa_s).
inline double contact_damping_scale(double rest_density, double speed_of_sound, double support_radius) {
  return kContactArtificialViscosity * rest_density * speed_of_sound * support_radius;
}

// Pi_ij of the pair, Pa: v_dot_r = (v_i - v_j) . (x_i - x_j), negative while they approach.
inline float contact_viscous_pressure(float scale_pa_s, float v_dot_r, float r2, float h2) {
  return v_dot_r < 0.0f ? scale_pa_s * -v_dot_r / (r2 + 0.01f * h2) : 0.0f;
}

}  // namespace hapfluid::sim
