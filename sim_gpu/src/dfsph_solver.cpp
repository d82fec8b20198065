#include "hapfluid/sim/dfsph_solver.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>

#include "body_contacts.hpp"
#include "body_solve_coupling.hpp"
#include "body_step.hpp"
#include "dfsph_passes.hpp"
#include "implicit_viscosity.hpp"
#include "hapfluid/sim/finite_state.hpp"

namespace hapfluid::sim {
namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// Warm start: half of the last step's stiffness (Bender & Koschier 2017 start from it; the half
// keeps a solve that overshot last step from ringing).
constexpr float kWarmStartFraction = 0.5f;

// The viscosity solve ends once the residual is this fraction of the right-hand side's norm (the
// velocities: 0.1 % of a 1 m/s flow is 1 mm/s).
constexpr double kViscosityTolerance = 1e-3;

}  // namespace

DfsphSolver::~DfsphSolver() = default;

DfsphSolver::DfsphSolver(SimulationModel model, int threads)
    : m_(std::move(model)), pool_(threads), coupling_(std::make_unique<detail::BodySolveCoupling>()) {
  if (m_.params.solver != config::PressureSolver::dfsph)
    throw std::invalid_argument("DfsphSolver: the model was built for solver = \"wcsph\"");
  devices_.resize(m_.devices.size());
  for (std::size_t d = 0; d < m_.devices.size(); ++d)
    devices_[d] = device_state_from(config::evaluate_motion(m_.devices[d].motion, 0.0));
  couplings_of_body_.resize(m_.bodies.size());
  for (auto& c : m_.couplings) couplings_of_body_[c.body].push_back(&c);
  const int slots = pool_.slots();
  lists_.resize(slots);
  // Room for the neighbourhood of a particle in the bulk (about 34 at h = 2 spacings) plus its
  // solids, so that the lists do not grow during the first steps.
  const std::size_t per_particle = 64;
  for (int w = 0; w < slots; ++w) {
    std::size_t b, e;
    ThreadPool::chunk(m_.fluid.size(), slots, w, b, e);
    lists_[w].reserve((e - b) * per_particle + 4096);
    lists_[w].reserve_scratch(4096);
  }
  ranges_.resize(m_.fluid.size());
  fields_.resize(m_.fluid.size());
  slot_error_.assign(slots, 0);
  slot_dots_.assign(2 * slots, 0);
  slot_clamped_.assign(slots, 0);
  slot_touching_.assign(slots, 0);
  body_reach_.resize(m_.bodies.size());
  slot_body_force_.assign(3 * m_.body_particles.size() * static_cast<std::size_t>(slots), 0.0f);
  detail::set_body_particle_velocities(m_);
  coupling_->init(m_, slots);
  const SimulationParams& p = m_.params;
  walls_ = domain_wall_map(p);
  fluid_statics_ = static_solids_beside_walls(m_);
  if (p.incompressible.settle_s > 0) settle(p.incompressible.settle_s);
  // Density and pressure of the initial state, for a frame exported before the first step.
  sort_and_build_pairs();
  for (std::size_t i = 0; i < m_.fluid.size(); ++i) {
    m_.fluid.density[i] = fields_.density_hat[i] * m_.params.rest_density_kg_m3;
    m_.fluid.volume[i] = m_.params.fluid_particle_mass_kg / m_.fluid.density[i];
  }
}

void DfsphSolver::settle(double duration_s) {
  settling_ = true;
  const double dt = m_.params.fixed_dt_s > 0 ? m_.params.fixed_dt_s : m_.params.max_dt_s;
  const int steps = std::max(1, static_cast<int>(std::ceil(duration_s / dt - 1e-9)));
  FluidParticles& f = m_.fluid;
  for (int k = 0; k < steps; ++k) {
    step(dt);
    for (std::size_t i = 0; i < f.size(); ++i)
      f.vx[i] *= kSettleVelocityKept, f.vy[i] *= kSettleVelocityKept, f.vz[i] *= kSettleVelocityKept;
  }
  settling_ = false;
  time_s_ = 0;
  steps_ = 0;
  clamped_ = 0;
  std::fill(slot_clamped_.begin(), slot_clamped_.end(), 0);
  times_ = {};
  iterations_ = {};
}

void DfsphSolver::set_device_state(std::size_t device, const DeviceState& state) {
  if (device >= devices_.size())
    throw std::out_of_range("device index " + std::to_string(device) + " out of range (" +
                            std::to_string(devices_.size()) + " devices in the scene)");
  devices_[device] = state;
}

double DfsphSolver::stable_time_step() const {
  const SimulationParams& p = m_.params;
  if (p.fixed_dt_s > 0) return p.fixed_dt_s;
  float v2 = 0;
  const FluidParticles& f = m_.fluid;
  for (std::size_t i = 0; i < f.size(); ++i) v2 = std::max(v2, f.vx[i] * f.vx[i] + f.vy[i] * f.vy[i] + f.vz[i] * f.vz[i]);
  const BodyParticles& bp = m_.body_particles;
  for (std::size_t i = 0; i < bp.size(); ++i) v2 = std::max(v2, bp.vx[i] * bp.vx[i] + bp.vy[i] * bp.vy[i] + bp.vz[i] * bp.vz[i]);
  return incompressible_time_step(p, v2, bodies_touching_);
}

double incompressible_time_step(const SimulationParams& p, float max_speed2, bool bodies_touching) {
  if (p.fixed_dt_s > 0) return p.fixed_dt_s;
  double dt = p.max_dt_s;
  if (max_speed2 > 0) dt = std::min(dt, p.cfl * p.particle_spacing_m / std::sqrt(static_cast<double>(max_speed2)));
  // Contacts are springs of the contact stiffness (body_contacts.hpp): while a body touches
  // another solid the step resolves them like a speed of sound.
  if (bodies_touching) dt = std::min(dt, 0.4 * p.kernel.h / p.speed_of_sound_m_s);
  return dt;
}

void DfsphSolver::sort_and_build_pairs() {
  FluidParticles& f = m_.fluid;
  fluid_sort_.sort(m_.params.grid, f.x.data(), f.y.data(), f.z.data(), f.size());
  f.permute(fluid_sort_.order);
  if (m_.body_particles.size() > 0) {
    detail::sort_body_view(m_.params.grid, m_.body_particles, body_sort_, body_view_);
  } else {
    body_view_.resize(0);
    body_view_.cell_start.clear();
  }
  pool_.parallel_for(f.size(), [&](std::size_t b, std::size_t e, int w) {
    for (std::size_t i = b; i < e; ++i) fields_.position[i] = {f.x[i], f.y[i], f.z[i], f.viscosity[i]};
    detail::build_pairs(m_.params, f, fluid_sort_.cell_start.data(), fluid_statics_, body_view_, walls_, b, e, lists_[w],
                        ranges_.data(), fields_);
  });
}

// One DFSPH solve (Bender & Koschier 2017, algorithms 2 and 3). `rate(i, s)` turns particle i's
// density rate s into its error: for the density solve the predicted density excess
// rho*/rho0 - 1 = rho_i/rho0 - 1 + dt s (clamped at 0: a free surface is not pulled together);
// for the divergence solve the compression rate itself, times dt. The stiffness increment
// error * factor / dt^2 is applied to the velocities until the mean error is below tolerance.
template <class Rate>
int DfsphSolver::solve(float dt, bool density, float tolerance, Rate&& rate) {
  const IncompressibleParams& ip = m_.params.incompressible;
  FluidParticles& f = m_.fluid;
  const std::size_t n = f.size();
  if (n == 0) return 0;
  float* total = density ? fields_.density_stiffness.data() : fields_.divergence_stiffness.data();
  float* warm = density ? f.density_stiffness_dt2.data() : f.divergence_stiffness_dt.data();
  const float warm_scale = density ? 1.0f / (dt * dt) : 1.0f / dt;
  const float inv_dt2 = 1.0f / (dt * dt);
  float* step = fields_.stiffness_step.data();
  detail::Packed4* velocity = fields_.velocity.data();
  // Warm start: where the particle is compressed now, start from part of last step's stiffness.
  // The solve works on packed velocities (simd.hpp), unpacked at its end.
  pool_.parallel_for(n, [&](std::size_t b, std::size_t e, int w) {
    for (std::size_t i = b; i < e; ++i) velocity[i] = {f.vx[i], f.vy[i], f.vz[i], 0.0f};
  });
  // Coupled, the bodies' share of the rates comes from their rigid velocities (subtract_flux).
  auto rates = [&](std::size_t b, std::size_t e, int w) {
    detail::density_rate(body_view_, fields_, lists_[w], ranges_.data(), b, e, step, !coupled_);
    if (coupled_) coupling_->subtract_flux(w, step);
  };
  pool_.parallel_for(n, [&](std::size_t b, std::size_t e, int w) {
    rates(b, e, w);
    for (std::size_t i = b; i < e; ++i) {
      const float k = rate(i, step[i]) > 0 ? kWarmStartFraction * warm[i] * warm_scale : 0.0f;
      step[i] = k;
      total[i] = k;
    }
  });
  auto apply = [&] {
    pool_.parallel_for(n, [&](std::size_t b, std::size_t e, int w) {
      detail::apply_stiffness(fields_, lists_[w], ranges_.data(), b, e, dt);
      if (coupled_) coupling_->add_forces(w, step);
    });
    if (coupled_) coupling_->update_velocities();
  };
  apply();
  int it = 0;
  double mean_error = 0;
  for (; it < ip.max_iterations; ++it) {
    pool_.parallel_for(n, [&](std::size_t b, std::size_t e, int w) {
      rates(b, e, w);
      double sum = 0;
      for (std::size_t i = b; i < e; ++i) {
        const float error = rate(i, step[i]);
        sum += error;
        const float k = error * fields_.factor[i] * inv_dt2;
        step[i] = k;
        total[i] += k;
      }
      slot_error_[w] = sum;
    });
    double sum = 0;
    for (double s : slot_error_) sum += s;
    mean_error = sum / static_cast<double>(n);
    if (it >= (density ? ip.min_density_iterations : ip.min_divergence_iterations) && mean_error <= tolerance) break;
    apply();
  }
  // The last error pass's increments were not applied: take them back out of the total.
  pool_.parallel_for(n, [&](std::size_t b, std::size_t e, int) {
    const float scale = density ? dt * dt : dt;
    for (std::size_t i = b; i < e; ++i) {
      if (it < ip.max_iterations) total[i] -= step[i];
      warm[i] = total[i] * scale;
      f.vx[i] = velocity[i].x, f.vy[i] = velocity[i].y, f.vz[i] = velocity[i].z;
    }
  });
  if (coupled_) coupling_->write_particle_velocities(m_, body_view_);
  if (it >= ip.max_iterations) ++iterations_.unconverged_solves;
  if (density) {
    iterations_.last_density_error = mean_error;
    iterations_.max_density_error = std::max(iterations_.max_density_error, mean_error);
  }
  return it;
}

void DfsphSolver::divergence_solve(float dt) {
  const IncompressibleParams& ip = m_.params.incompressible;
  const std::uint16_t min_neighbours = static_cast<std::uint16_t>(ip.min_divergence_neighbours);
  // Error: the compression over one step, dt D(rho/rho0)/Dt, only where the neighbourhood is
  // full enough to estimate it and only compression (an expanding surface is left alone).
  auto rate = [&](std::size_t i, float s) {
    return fields_.neighbours[i] >= min_neighbours && s > 0 ? s * dt : 0.0f;
  };
  // The increment is error * factor / dt^2 with error = s dt: s factor / dt, as the divergence
  // solve needs.
  iterations_.divergence_iterations += static_cast<std::uint64_t>(solve(dt, false, ip.max_divergence_error, rate));
}

void DfsphSolver::density_solve(float dt) {
  const IncompressibleParams& ip = m_.params.incompressible;
  auto rate = [&](std::size_t i, float s) {
    const float excess = fields_.density_hat[i] - 1.0f + dt * s;
    return excess > 0 ? excess : 0.0f;
  };
  iterations_.density_iterations += static_cast<std::uint64_t>(solve(dt, true, ip.max_density_error, rate));
}

void DfsphSolver::non_pressure_forces(float dt) {
  FluidParticles& f = m_.fluid;
  pool_.parallel_for(f.size(), [&](std::size_t b, std::size_t e, int w) {
    detail::non_pressure_accelerations(m_.params, f, fields_, lists_[w], ranges_.data(), b, e, dt);
  });
  // Apart from the pass above: XSPH reads the neighbours' velocities of before the update. The
  // viscosity solve's right-hand side takes these velocities v* (in visc_b), its iterate starts
  // from v* plus the change its last solve made (Weiler et al. 2018's warm start; zero where the
  // last step took the explicit step), packed.
  pool_.parallel_for(f.size(), [&](std::size_t b, std::size_t e, int) {
    for (std::size_t i = b; i < e; ++i) {
      f.vx[i] += dt * f.ax[i];
      f.vy[i] += dt * f.ay[i];
      f.vz[i] += dt * f.az[i];
      fields_.visc_bx[i] = f.vx[i], fields_.visc_by[i] = f.vy[i], fields_.visc_bz[i] = f.vz[i];
      f.vx[i] += f.viscous_dvx[i], f.vy[i] += f.viscous_dvy[i], f.vz[i] += f.viscous_dvz[i];
      fields_.velocity[i] = {f.vx[i], f.vy[i], f.vz[i], fields_.density_hat[i]};
    }
  });
  iterations_.viscosity_iterations += static_cast<std::uint64_t>(viscosity_solve(dt));
}

// The fluid's force on each body particle, from the pair lists: each slot sums what its fluid
// particles' pairs give, then the slots are added in order (the same sums for any thread count).
// The viscous part is written, the pressure part added to it.
void DfsphSolver::body_fluid_forces(detail::BodyForcePart part) {
  BodyParticles& bp = m_.body_particles;
  const std::size_t nb = body_view_.size();
  if (nb == 0) return;
  pool_.parallel_for(m_.fluid.size(), [&](std::size_t b, std::size_t e, int slot) {
    detail::body_pair_forces(m_.params, m_.fluid, fields_, body_view_, part, lists_[slot], ranges_.data(), b, e,
                             slot_body_force_.data() + 3 * nb * static_cast<std::size_t>(slot));
  });
  const bool add = part == detail::BodyForcePart::pressure;
  for (std::size_t q = 0; q < nb; ++q) {
    float fx = 0, fy = 0, fz = 0;
    for (int slot = 0; slot < pool_.slots(); ++slot) {
      const float* s = slot_body_force_.data() + 3 * (nb * static_cast<std::size_t>(slot) + q);
      fx += s[0], fy += s[1], fz += s[2];
    }
    const std::uint32_t i = body_view_.source[q];
    if (add) {
      bp.fx[i] += fx, bp.fy[i] += fy, bp.fz[i] += fz;
    } else {
      bp.fx[i] = fx, bp.fy[i] = fy, bp.fz[i] = fz;
    }
  }
}

// Preconditioned conjugate gradients (Jacobi) on K v = b, started from the velocities after
// gravity and XSPH; the fluid's velocity arrays are the iterate.
int DfsphSolver::viscosity_solve(float dt) {
  FluidParticles& f = m_.fluid;
  const std::size_t n = f.size();
  if (n == 0) return 0;
  bool any = m_.params.fluid_viscosity_pa_s > 0;
  for (const RigidBody& b : m_.bodies) any = any || b.viscosity_pa_s > 0;
  if (!any) {
    body_fluid_forces(detail::BodyForcePart::viscous);
    return 0;
  }
  detail::DfsphFields& d = fields_;
  auto reduce = [&](int k) {
    double s = 0;
    for (int w = 0; w < pool_.slots(); ++w) s += slot_dots_[2 * w + k];
    return s;
  };
  auto apply = [&](const float* x, const float* y, const float* z, float* ox, float* oy, float* oz, std::size_t b,
                   std::size_t e, int w) {
    detail::viscosity_apply(m_.params, fluid_statics_, body_view_, d, lists_[w], ranges_.data(), b, e, dt, x, y, z, ox,
                            oy, oz);
  };
  // r = b - K v, p = M^-1 r; dots: r . p and b . b; and each slot's largest diagonal excess
  // sum_a (K_ii,aa - 1), for the bound on K's spectrum below.
  pool_.parallel_for(n, [&](std::size_t b, std::size_t e, int w) {
    detail::viscosity_rhs(m_.params, fluid_statics_, body_view_, walls_, lists_[w], ranges_.data(), b, e, dt, d);
    double rz = 0, bb = 0;
    float excess = 0;
    for (std::size_t i = b; i < e; ++i) {
      d.cg_rx[i] = d.visc_bx[i] - d.cg_ax[i], d.cg_ry[i] = d.visc_by[i] - d.cg_ay[i], d.cg_rz[i] = d.visc_bz[i] - d.cg_az[i];
      d.cg_px[i] = d.visc_inv_diag_x[i] * d.cg_rx[i], d.cg_py[i] = d.visc_inv_diag_y[i] * d.cg_ry[i],
      d.cg_pz[i] = d.visc_inv_diag_z[i] * d.cg_rz[i];
      rz += d.cg_rx[i] * d.cg_px[i] + d.cg_ry[i] * d.cg_py[i] + d.cg_rz[i] * d.cg_pz[i];
      bb += d.visc_bx[i] * d.visc_bx[i] + d.visc_by[i] * d.visc_by[i] + d.visc_bz[i] * d.visc_bz[i];
      excess = std::max(excess, 1.0f / d.visc_inv_diag_x[i] + 1.0f / d.visc_inv_diag_y[i] + 1.0f / d.visc_inv_diag_z[i] - 3.0f);
    }
    slot_dots_[2 * w] = rz, slot_dots_[2 * w + 1] = bb;
    slot_error_[w] = excess;
  });
  // A viscosity as low as water's barely acts within one step. K = I + dt L, and every pair term
  // of dt L is c (x_ij x_ij^T) (a rank-one block), so a row of dt L sums in magnitude to at most
  // 2 sqrt(3) times particle i's diagonal excess (Gershgorin): that bounds dt L's largest
  // eigenvalue lambda. The explicit step v + r (r = b - K v, the viscous change at v) damps a mode
  // by 1 - lambda where the implicit one damps it by 1 / (1 + lambda); they differ by at most
  // lambda^2 of the mode, so when lambda^2 is within the solve's own tolerance the explicit step
  // is the solve's answer, at no further pass.
  double lambda = 0;
  for (int w = 0; w < pool_.slots(); ++w) lambda = std::max(lambda, 2.0 * std::sqrt(3.0) * slot_error_[w]);
  if (lambda * lambda <= kViscosityTolerance) {
    body_fluid_forces(detail::BodyForcePart::viscous);
    pool_.parallel_for(n, [&](std::size_t b, std::size_t e, int) {
      for (std::size_t i = b; i < e; ++i) {
        f.vx[i] += d.cg_rx[i], f.vy[i] += d.cg_ry[i], f.vz[i] += d.cg_rz[i];
        f.viscous_dvx[i] = 0, f.viscous_dvy[i] = 0, f.viscous_dvz[i] = 0;
      }
    });
    ++iterations_.explicit_viscosity_steps;
    return 0;
  }
  double rz = reduce(0);
  const double limit = kViscosityTolerance * kViscosityTolerance * reduce(1);
  const int max_iterations = m_.params.incompressible.max_iterations;
  int it = 0;
  double rr = 0;
  for (; it < max_iterations; ++it) {
    // Ap and p . Ap
    pool_.parallel_for(n, [&](std::size_t b, std::size_t e, int w) {
      apply(d.cg_px.data(), d.cg_py.data(), d.cg_pz.data(), d.cg_ax.data(), d.cg_ay.data(), d.cg_az.data(), b, e, w);
      double pap = 0;
      for (std::size_t i = b; i < e; ++i)
        pap += d.cg_px[i] * d.cg_ax[i] + d.cg_py[i] * d.cg_ay[i] + d.cg_pz[i] * d.cg_az[i];
      slot_dots_[2 * w] = pap;
    });
    const double pap = reduce(0);
    if (!(pap > 0)) break;  // converged to round-off (or p = 0)
    const float alpha = static_cast<float>(rz / pap);
    // v += alpha p, r -= alpha Ap, and |r|^2
    pool_.parallel_for(n, [&](std::size_t b, std::size_t e, int w) {
      double s = 0;
      for (std::size_t i = b; i < e; ++i) {
        f.vx[i] += alpha * d.cg_px[i], f.vy[i] += alpha * d.cg_py[i], f.vz[i] += alpha * d.cg_pz[i];
        d.cg_rx[i] -= alpha * d.cg_ax[i], d.cg_ry[i] -= alpha * d.cg_ay[i], d.cg_rz[i] -= alpha * d.cg_az[i];
        s += d.cg_rx[i] * d.cg_rx[i] + d.cg_ry[i] * d.cg_ry[i] + d.cg_rz[i] * d.cg_rz[i];
      }
      slot_dots_[2 * w] = s;
    });
    rr = reduce(0);
    if (rr <= limit) {
      ++it;
      break;
    }
    // z = M^-1 r (into Ap, no longer needed), r . z, then p = z + beta p
    pool_.parallel_for(n, [&](std::size_t b, std::size_t e, int w) {
      double s = 0;
      for (std::size_t i = b; i < e; ++i) {
        d.cg_ax[i] = d.visc_inv_diag_x[i] * d.cg_rx[i], d.cg_ay[i] = d.visc_inv_diag_y[i] * d.cg_ry[i],
        d.cg_az[i] = d.visc_inv_diag_z[i] * d.cg_rz[i];
        s += d.cg_rx[i] * d.cg_ax[i] + d.cg_ry[i] * d.cg_ay[i] + d.cg_rz[i] * d.cg_az[i];
      }
      slot_dots_[2 * w] = s;
    });
    const double rz_new = reduce(0);
    const float beta = static_cast<float>(rz_new / rz);
    rz = rz_new;
    pool_.parallel_for(n, [&](std::size_t b, std::size_t e, int) {
      for (std::size_t i = b; i < e; ++i)
        d.cg_px[i] = d.cg_ax[i] + beta * d.cg_px[i], d.cg_py[i] = d.cg_ay[i] + beta * d.cg_py[i],
        d.cg_pz[i] = d.cg_az[i] + beta * d.cg_pz[i];
    });
  }
  if (it >= max_iterations && rr > limit) ++iterations_.unconverged_solves;
  // The change this solve made, for the next one's start: v - v* = v - (start - last change).
  pool_.parallel_for(n, [&](std::size_t b, std::size_t e, int) {
    for (std::size_t i = b; i < e; ++i) {
      const detail::Packed4& start = d.velocity[i];
      f.viscous_dvx[i] += f.vx[i] - start.x, f.viscous_dvy[i] += f.vy[i] - start.y, f.viscous_dvz[i] += f.vz[i] - start.z;
    }
  });
  body_fluid_forces(detail::BodyForcePart::viscous);
  return it;
}

void DfsphSolver::body_contacts() {
  BodyParticles& bp = m_.body_particles;
  if (bp.size() == 0) return;
  std::fill(slot_touching_.begin(), slot_touching_.end(), 0);
  body_reach_.update(bp, m_.params.kernel.h);
  pool_.parallel_for(body_view_.size(), [&](std::size_t b, std::size_t e, int) {
    detail::body_contact_pressure(m_.params, m_.static_solids, body_view_, bp, body_reach_, b, e);
  });
  pool_.parallel_for(bp.size(), [&](std::size_t b, std::size_t e, int w) {
    slot_touching_[w] = detail::body_contact_forces(m_.params, m_.static_solids, body_view_, bp, body_reach_, b, e) ? 1 : 0;
  });
  bodies_touching_ = std::any_of(slot_touching_.begin(), slot_touching_.end(), [](char c) { return c != 0; });
}

void DfsphSolver::start_density_coupling(double dt) {
  detail::sum_body_forces(m_);
  for (std::size_t b = 0; b < m_.bodies.size(); ++b) {
    RigidBody& body = m_.bodies[b];
    if (!body.dynamic || body.particle_count == 0) continue;
    const detail::BodySolveCoupling::Vec6 f = coupling_->solve_force(b);
    body.fluid_force += Vec3{f[0], f[1], f[2]};
    body.fluid_torque += Vec3{f[3], f[4], f[5]};
    const BodySystem sys = body_system(body, couplings_of_body_[b], devices_, m_.params.gravity_m_s2, dt);
    detail::BodySolveCoupling::Vec6 u;
    solve6(sys.a, sys.rhs, u.data());
    coupling_->start_solve(b, u);
  }
  // The body particles get the prediction at the solve's end: nothing reads them before.
}

void DfsphSolver::body_forces_and_step(double dt) {
  body_fluid_forces(detail::BodyForcePart::pressure);
  detail::step_bodies(m_, couplings_of_body_, devices_, dt, pool_);
}

// x(t + dt) = x + dt v(t + dt) (symplectic Euler, as DFSPH). Last resort: a particle that reaches
// a wall's boundary layer (or leaves the box on an open side) is put back and counted.
void DfsphSolver::integrate_positions(float dt) {
  FluidParticles& f = m_.fluid;
  const SimulationParams& p = m_.params;
  pool_.parallel_for(f.size(), [&](std::size_t b, std::size_t e, int w) {
    std::uint64_t clamped = 0;
    float* pos[3] = {f.x.data(), f.y.data(), f.z.data()};
    float* vel[3] = {f.vx.data(), f.vy.data(), f.vz.data()};
    for (std::size_t i = b; i < e; ++i) {
      bool out = false;
      for (int a = 0; a < 3; ++a) {
        float v = vel[a][i];
        float x = pos[a][i] + v * dt;
        out = clamp_to_domain(p, a, x, v) || out;
        vel[a][i] = v;
        pos[a][i] = x;
      }
      clamped += out ? 1 : 0;
    }
    slot_clamped_[w] += clamped;
  });
  clamped_ = 0;
  for (auto c : slot_clamped_) clamped_ += c;
}

void DfsphSolver::step(double dt) {
  const float dtf = static_cast<float>(dt);
  auto t0 = Clock::now();
  sort_and_build_pairs();
  times_.neighbour_search_s += seconds_since(t0);

  coupled_ = !settling_ && coupling_->active();
  t0 = Clock::now();
  if (coupled_) {
    coupling_->begin_step(m_, couplings_of_body_, devices_, dt, body_view_, lists_, ranges_.data(), fields_, pool_);
    coupling_->start_solve_from_body_states(m_);
  }
  times_.bodies_s += seconds_since(t0);

  t0 = Clock::now();
  divergence_solve(dtf);
  times_.pressure_s += seconds_since(t0);

  t0 = Clock::now();
  non_pressure_forces(dtf);
  times_.forces_s += seconds_since(t0);

  t0 = Clock::now();
  if (!settling_) body_contacts();
  if (coupled_) start_density_coupling(dt);
  times_.bodies_s += seconds_since(t0);

  t0 = Clock::now();
  density_solve(dtf);
  times_.pressure_s += seconds_since(t0);

  t0 = Clock::now();
  if (!settling_) body_forces_and_step(dt);
  times_.bodies_s += seconds_since(t0);

  t0 = Clock::now();
  integrate_positions(dtf);
  times_.integration_s += seconds_since(t0);

  time_s_ += dt;
  ++steps_;
}

void DfsphSolver::sync_and_check_finite() {
  // Density and pressure for the outputs: p = k rho^2 / rho0 of the last constant-density solve
  // (k = p / (rho rho0) in the solver's normalised form), on the sorted order of that step.
  FluidParticles& f = m_.fluid;
  const float rho0 = m_.params.rest_density_kg_m3, mass = m_.params.fluid_particle_mass_kg;
  for (std::size_t i = 0; i < f.size(); ++i) {
    const float rho_hat = fields_.density_hat[i];
    f.density[i] = rho_hat * rho0;
    f.volume[i] = mass / f.density[i];
    f.pressure[i] = fields_.density_stiffness[i] * rho_hat * rho_hat * rho0;
  }
  check_finite_state(m_, time_s_);
}

ComputeDevice DfsphSolver::device() const { return cpu_threads_device(threads()); }

}  // namespace hapfluid::sim
