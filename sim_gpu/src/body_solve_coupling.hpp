// Strong coupling of the dynamic bodies with the incompressible solver's pressure solves. A body
// lighter than the water it pushes aside cannot take the fluid's pressure only after the solves
// (the added-mass instability of an explicit two-way coupling): inside each solve, every
// iteration's stiffness increments push the bodies too, their predicted velocities follow, and
// the next iteration's density rates see the bodies move, as in the interlinked solvers of
// Gissler et al. 2019.
//
// A body's velocity is linear in the force the solve puts on it: u = u_start + dt A^-1 F, with
// A the body's implicit step (coupling.hpp). Taking it whole each iteration diverges as soon as
// the fluid's response to the body's motion outweighs the body (L below > 1); so each iteration
// moves u by (I + L)^-1 (u_start + dt A^-1 F - u), where L = m A^-1 sum_i factor_i J_i J_i^T is
// the fluid's Jacobi response to the body's own motion (J_i: particle i's pair gradients with the
// body as a 6-vector, force and torque). The fixed point is the body's own step, so a converged
// solve leaves fluid and body consistent, and the body step afterwards (step_bodies) integrates
// the same forces. J_i is kept for the step: each iteration's force on a body is m k_i J_i and
// the body's flux into particle i's density rate J_i . u. Internal to sim_gpu.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "hapfluid/sim/coupling.hpp"
#include "hapfluid/sim/dfsph_solver.hpp"
#include "hapfluid/sim/model.hpp"
#include "hapfluid/sim/thread_pool.hpp"

namespace hapfluid::sim::detail {

class BodySolveCoupling {
 public:
  using Vec6 = std::array<double, 6>;
  using Mat6 = std::array<double, 36>;

  // Sizes the per-slot sums for the model's bodies; nothing is allocated per step after this.
  void init(const SimulationModel& m, int slots);
  bool active() const { return active_; }

  // After the pairs are built: each dynamic body's mobility dt A^-1 at its pose and the
  // relaxation (I + L)^-1 from the pairs and the DFSPH factors of this step.
  void begin_step(const SimulationModel& m, const std::vector<std::vector<VirtualCoupling*>>& couplings_of_body,
                  const std::vector<DeviceState>& devices, double dt, const SortedSolids& bodies,
                  const std::vector<PairLists>& lists, const PairRange* ranges, const DfsphFields& fields,
                  ThreadPool& pool);

  // A solve starts from these body velocities (u_start, and the current prediction) with no
  // force of its own yet.
  void start_solve(std::size_t body, const Vec6& u_start);
  // The same from every dynamic body's velocity now (the start of the step).
  void start_solve_from_body_states(const SimulationModel& m);

  // Inside a slot's pass over the fluid (the slot's particles of begin_step): the force the
  // stiffness increments k of these particles put on the bodies, m k_i Psi_b grad W_ib per pair,
  // summed per slot. Per particle and body that is m k_i J_i, with J_i kept from begin_step: six
  // products per particle next to a body rather than a wrench per pair.
  void add_forces(int slot, const float* k);

  // The bodies' share of the density rates of the slot's particles (those of begin_step),
  // subtracted from `rate`: sum_b J_ib . u_b, the pairs' sum_j Psi_j grad W_ij . v_j for the
  // rigid velocities v_j of the bodies' current prediction u_b, six products per particle next
  // to a body rather than three per pair.
  void subtract_flux(int slot, float* rate) const;

  // After the increments are applied: the bodies' new predicted velocities u, which the next
  // density rates read (subtract_flux).
  void update_velocities();
  // The prediction's rigid velocities onto the body particles, in the cell-sorted view and the
  // grouped body particles, for what reads them after a solve (viscosity, contacts, body step).
  void write_particle_velocities(SimulationModel& m, SortedSolids& bodies) const;

  // The force and torque (about the centre of mass) the current solve has put on the body.
  Vec6 solve_force(std::size_t body) const { return force_[body]; }

 private:
  bool active_ = false;
  int slots_ = 0;
  std::size_t bodies_ = 0;
  float particle_mass_ = 0;
  std::vector<char> dynamic_;
  std::vector<Mat6> mobility_;   // dt A^-1
  std::vector<Mat6> relax_;      // (I + L)^-1
  std::vector<Vec6> u_start_, u_, force_;
  std::vector<float> com_;       // 3 per body
  std::vector<double> slot_force_;   // 6 per body per slot
  std::vector<double> slot_response_;  // 36 per body per slot: sum factor J J^T
  std::vector<double> slot_j_;       // 6 per body per slot, one particle's J
  // J_i of every fluid particle next to a body, per slot, this step (capacity kept across steps).
  struct ParticleJacobian {
    std::uint32_t particle, body;
    double j[6];
  };
  std::vector<std::vector<ParticleJacobian>> slot_jacobians_;
};

}  // namespace hapfluid::sim::detail
