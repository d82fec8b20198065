// The incompressible CPU solver: Divergence-Free SPH (Bender & Koschier, SCA 2015 and TVCG 2017)
// in the unified particle model of the paper (rigid bodies as boundary particles, eqs. 8-14,
// devices through the implicit virtual coupling of coupling.hpp).
//
// One step of dt:
//  1. sort the fluid by cell; neighbour lists with V_j grad W_ij and V_j W_ij per pair, built
//     once and read by every solver iteration; density and the DFSPH factor
//     1 / (|sum_j V_j grad W_ij|^2 + sum_fluid |V_j grad W_ij|^2) (normalised density rho/rho0);
//  2. divergence-free solve on the current velocities (D rho / Dt = 0), warm-started with half of
//     the last step's stiffness;
//  3. non-pressure forces: gravity and the scene's XSPH fraction, then viscosity (the SPH Laplacian
//     of Monaghan 2005 with the fluid's and each body's viscosity, eq. 9's pairing) solved
//     implicitly (implicit_viscosity.hpp), so that no viscosity limits the step; a viscosity so
//     low that one explicit step is as exact as the solve (water's) takes that step instead;
//  4. constant-density solve on the predicted velocities (rho* = rho0), warm-started likewise;
//  5. bodies: the pressure and viscous forces the fluid received from each body particle, with
//     the opposite sign (two-way coupling, Akinci et al. 2012), plus contacts; Algorithm 2.
//     Both solves move the bodies as they iterate (body_solve_coupling.hpp), so that a body
//     lighter than the water around it stays stable;
//  6. positions x += dt v; a particle that still reaches a wall is clamped and counted (a fault).
// The domain walls enter through a volume map (wall_map.hpp); static and dynamic bodies as
// boundary particles with their Akinci volumes Psi_b: rho_i += Psi_b W_ib, and the fluid's
// pressure pushes on them with its own stiffness.
//
// Work is split statically over a ThreadPool (bit-for-bit repeatable for a thread count); nothing
// is allocated per step once the lists have grown to the scene's neighbourhood size.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "hapfluid/sim/body_reach.hpp"
#include "hapfluid/sim/model.hpp"
#include "hapfluid/sim/neighbour_grid.hpp"
#include "hapfluid/sim/solver.hpp"
#include "hapfluid/sim/thread_pool.hpp"
#include "hapfluid/sim/wall_map.hpp"

namespace hapfluid::sim {

namespace detail {

// Four floats in one 16-byte register: a pair's terms or a particle's velocity. A pass over the
// pairs then reads a neighbour's whole vector with one load instead of three gathered scalars.
struct alignas(16) Packed4 {
  float x = 0, y = 0, z = 0, w = 0;
};

// Pairs of the fluid particles of one slot: fluid neighbours, then static solid, then dynamic
// body neighbours of each particle.
struct PairLists {
  std::vector<std::uint32_t> index;
  // x, y, z: V_j grad W(x_i - x_j), 1/m (V_j = m / rho0, or Psi_b); w: V_j W(x_i - x_j).
  std::vector<Packed4> term;
  std::size_t used = 0;
  // The offsets x_i - x_j of the particle being listed, from the candidate filter to its kernels
  // (which leave their terms there before packing them).
  std::vector<float> scratch_dx, scratch_dy, scratch_dz, scratch_w;
  void reserve(std::size_t n);
  void reserve_scratch(std::size_t n);
};

struct PairRange {
  std::uint32_t offset = 0;
  std::uint16_t fluid = 0, statics = 0, bodies = 0;
};

// Per fluid particle, in sorted order, recomputed every step.
struct DfsphFields {
  std::vector<float> density_hat;        // rho / rho0
  std::vector<float> factor;             // DFSPH factor, m^2
  std::vector<float> solid_gx, solid_gy, solid_gz;  // sum over solids of Psi_b grad W_ib, 1/m
  std::vector<float> stiffness_step;     // this iteration's stiffness increment, m^2/s^2
  // Packed copies for the pair passes: the sorted positions (w: the particle's viscosity, Pa s) and
  // the velocities during a solve (w: rho / rho0 in the viscosity solve, else unused), m and m/s.
  std::vector<Packed4> position, velocity;
  std::vector<float> density_stiffness, divergence_stiffness;  // this step's totals, m^2/s^2
  // Implicit viscosity (implicit_viscosity.hpp): right-hand side, inverse diagonal, and the
  // conjugate-gradient residual, search direction and its image.
  std::vector<float> visc_bx, visc_by, visc_bz, visc_inv_diag_x, visc_inv_diag_y, visc_inv_diag_z;
  std::vector<float> cg_rx, cg_ry, cg_rz, cg_px, cg_py, cg_pz, cg_ax, cg_ay, cg_az;
  std::vector<float> visc_wall_x, visc_wall_y, visc_wall_z;  // the walls' share of the diagonal (WallMap::friction)
  std::vector<std::uint16_t> neighbours;
  void resize(std::size_t n);
};

class BodySolveCoupling;

}  // namespace detail

// The incompressible solver's step bound from the fastest particle's squared speed (fluid or
// body): cfl * particle spacing / speed, the scene's max_dt_s, and the contact stiffness while
// bodies touch other solids; or the scene's fixed dt_s. Both backends use it.
double incompressible_time_step(const SimulationParams& p, float max_speed2, bool bodies_touching);

// fluid.settle_s is a dynamic relaxation: the fluid keeps this fraction of its velocity after
// each step. Zeroing it instead (a quasi-static relaxation) leaves the column pressed down by one
// step of gravity and it springs back when released, by 1.8 mm in a 20 cm tank.
inline constexpr float kSettleVelocityKept = 0.8f;

namespace detail {

enum class BodyForcePart;

}  // namespace detail

class DfsphSolver final : public Solver {
 public:
  DfsphSolver(SimulationModel model, int threads);
  ~DfsphSolver() override;

  const SimulationModel& model() const override { return m_; }
  double time_s() const override { return time_s_; }
  std::uint64_t steps() const override { return steps_; }
  int threads() const override { return pool_.size(); }
  void set_active_threads(int n) override { pool_.set_active(n); }
  int active_threads() const override { return pool_.active(); }
  PhaseTimes phase_times() const override { return times_; }
  SolverIterations iterations() const override { return iterations_; }
  std::uint64_t clamped_particle_count() const override { return clamped_; }

  void set_device_state(std::size_t device, const DeviceState& state) override;
  // cfl * particle spacing / fastest fluid or body particle; the contact stiffness while bodies
  // touch other solids; the scene's max_dt_s (the implicit viscosity sets no limit).
  double stable_time_step() const override;
  void step(double dt) override;

  void sync_and_check_finite() override;
  const char* backend() const override { return "cpu"; }
  ComputeDevice device() const override;

 private:
  // fluid.settle_s: steps at max_dt_s with the fluid's velocities damped after each and the
  // bodies held, then the clock, step count, timings and iteration counts start from zero.
  void settle(double duration_s);
  void sort_and_build_pairs();
  void divergence_solve(float dt);
  void non_pressure_forces(float dt);
  // The viscosity solve on the velocities after gravity and XSPH, then the bodies' viscous
  // forces; returns CG iterations (0 for an explicit step).
  int viscosity_solve(float dt);
  void body_fluid_forces(detail::BodyForcePart part);
  void density_solve(float dt);
  // Contacts between solids, from the positions at the start of the step.
  void body_contacts();
  // The bodies' velocities before the density solve: their step with the viscous, contact and
  // divergence-solve forces so far (the density solve adds its own as it goes).
  void start_density_coupling(double dt);
  void body_forces_and_step(double dt);
  void integrate_positions(float dt);
  // One solve: iterations until the mean error is below `tolerance`; returns iterations.
  template <class Rate>
  int solve(float dt, bool density, float tolerance, Rate&& rate);

  SimulationModel m_;
  ThreadPool pool_;
  CellSort fluid_sort_, body_sort_;
  SortedSolids body_view_;
  detail::BodyReach body_reach_;
  // The fluid's static solids: the static bodies' particles. The domain walls are the volume map
  // (their particles stay in the model for body contacts and outputs).
  SortedSolids fluid_statics_;
  WallMap walls_;
  std::vector<DeviceState> devices_;
  std::vector<std::vector<VirtualCoupling*>> couplings_of_body_;
  std::vector<detail::PairLists> lists_;  // one per slot
  std::vector<detail::PairRange> ranges_;
  detail::DfsphFields fields_;
  std::unique_ptr<detail::BodySolveCoupling> coupling_;
  bool coupled_ = false;  // this step's solves move the bodies (not while settling)
  std::vector<double> slot_error_;
  std::vector<double> slot_dots_;  // 2 per slot
  std::vector<std::uint64_t> slot_clamped_;
  std::vector<char> slot_touching_;
  std::vector<float> slot_body_force_;  // 3 per body particle per slot (body_fluid_forces)
  bool bodies_touching_ = false;
  bool settling_ = false;
  double time_s_ = 0;
  std::uint64_t steps_ = 0;
  std::uint64_t clamped_ = 0;
  PhaseTimes times_;
  SolverIterations iterations_;
};

}  // namespace hapfluid::sim
