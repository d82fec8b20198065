#include "hapfluid/sim/cpu_solver.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>

#include "hapfluid/sim/contact_damping.hpp"
#include "hapfluid/sim/finite_state.hpp"
#include "sph_passes.hpp"

namespace hapfluid::sim {
namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// sum over a run of grid candidates of w_j W-shape (the poly6 shape, zero beyond h).
inline float poly6_run_weighted(const float* x, const float* y, const float* z, const float* w, std::uint32_t b,
                                std::uint32_t e, float xi, float yi, float zi, const KernelConstants& k) {
  float sum = 0;
  for (std::uint32_t j = b; j < e; ++j) {
    const float dx = xi - x[j], dy = yi - y[j], dz = zi - z[j];
    sum += w[j] * poly6_shape(k, dx * dx + dy * dy + dz * dz);
  }
  return sum;
}

}  // namespace

CpuSolver::CpuSolver(SimulationModel model, int threads) : m_(std::move(model)), pool_(threads) {
  devices_.resize(m_.devices.size());
  for (std::size_t d = 0; d < m_.devices.size(); ++d)
    devices_[d] = device_state_from(config::evaluate_motion(m_.devices[d].motion, 0.0));
  couplings_of_body_.resize(m_.bodies.size());
  for (auto& c : m_.couplings) couplings_of_body_[c.body].push_back(&c);
  worker_max_accel_.assign(threads, 0);
  worker_clamped_.assign(threads, 0);
  neighbour_lists_.resize(threads);
  // Density and pressure of the initial state, so that a frame exported before the first step
  // shows them (the step recomputes them from the same positions).
  sort_fluid();
  if (m_.body_particles.size() > 0) build_body_view();
  neighbour_ranges_.resize(m_.fluid.size());
  pool_.parallel_for(m_.fluid.size(), [&](std::size_t b, std::size_t e, int w) { compute_density(b, e, w); });
  // Body particle velocities at start (eq. 14 with the initial body velocities).
  for (const RigidBody& body : m_.bodies) {
    if (!body.dynamic) continue;
    BodyParticles& bp = m_.body_particles;
    for (std::uint32_t i = body.first_particle; i < body.first_particle + body.particle_count; ++i) {
      const Vec3 v = body.velocity_at({bp.x[i], bp.y[i], bp.z[i]});
      bp.vx[i] = static_cast<float>(v.x), bp.vy[i] = static_cast<float>(v.y), bp.vz[i] = static_cast<float>(v.z);
    }
  }
}

void CpuSolver::set_device_state(std::size_t device, const DeviceState& state) {
  if (device >= devices_.size())
    throw std::out_of_range("device index " + std::to_string(device) + " out of range (" +
                            std::to_string(devices_.size()) + " devices in the scene)");
  devices_[device] = state;
}

double CpuSolver::stable_time_step() const {
  const SimulationParams& p = m_.params;
  if (p.fixed_dt_s > 0) return p.fixed_dt_s;
  float v_max = 0, a_max = 0;
  const FluidParticles& f = m_.fluid;
  for (std::size_t i = 0; i < f.size(); ++i) {
    v_max = std::max(v_max, f.vx[i] * f.vx[i] + f.vy[i] * f.vy[i] + f.vz[i] * f.vz[i]);
    a_max = std::max(a_max, f.ax[i] * f.ax[i] + f.ay[i] * f.ay[i] + f.az[i] * f.az[i]);
  }
  const BodyParticles& bp = m_.body_particles;
  for (std::size_t i = 0; i < bp.size(); ++i)
    v_max = std::max(v_max, bp.vx[i] * bp.vx[i] + bp.vy[i] * bp.vy[i] + bp.vz[i] * bp.vz[i]);
  const double h = p.kernel.h;
  double dt = p.cfl * h / (p.speed_of_sound_m_s + std::sqrt(static_cast<double>(v_max)));
  double mu_max = p.fluid_viscosity_pa_s;
  for (const RigidBody& b : m_.bodies) mu_max = std::max(mu_max, b.viscosity_pa_s);
  if (mu_max > 0) dt = std::min(dt, 0.125 * h * h * p.rest_density_kg_m3 / mu_max);  // viscous diffusion limit
  if (a_max > 0) dt = std::min(dt, 0.25 * std::sqrt(h / std::sqrt(static_cast<double>(a_max))));
  return std::min(dt, p.max_dt_s);
}

int CpuSolver::advance(double duration_s, const std::function<void(double)>& before_substep) {
  if (duration_s <= 0) return 0;
  const double dt_max = stable_time_step();
  const int substeps = std::max(1, static_cast<int>(std::ceil(duration_s / dt_max - 1e-9)));
  const double dt = duration_s / substeps;
  const double t0 = time_s_;
  for (int i = 0; i < substeps; ++i) {
    if (before_substep) before_substep(t0 + i * dt);
    step(dt);
  }
  return substeps;
}

void CpuSolver::sort_fluid() {
  FluidParticles& f = m_.fluid;
  fluid_sort_.sort(m_.params.grid, f.x.data(), f.y.data(), f.z.data(), f.size());
  f.permute(fluid_sort_.order);
}

void CpuSolver::build_body_view() {
  const BodyParticles& bp = m_.body_particles;
  body_sort_.sort(m_.params.grid, bp.x.data(), bp.y.data(), bp.z.data(), bp.size());
  SortedSolids& v = body_view_;
  v.resize(bp.size());
  for (std::size_t k = 0; k < bp.size(); ++k) {
    const std::uint32_t i = body_sort_.order[k];
    v.x[k] = bp.x[i], v.y[k] = bp.y[i], v.z[k] = bp.z[i];
    v.vx[k] = bp.vx[i], v.vy[k] = bp.vy[i], v.vz[k] = bp.vz[i];
    v.volume[k] = bp.volume[i], v.viscosity[k] = bp.viscosity[i], v.no_slip[k] = 1.0f;
    v.body[k] = bp.body[i];
    v.source[k] = i;
  }
  v.cell_start = body_sort_.cell_start;
}

// Eq. 2 over fluid neighbours, plus the boundary contribution rho0 V_b W of wall and body
// particles (Akinci et al. 2012), then eq. 7. Negative pressures are clamped to zero: a free
// surface must not pull particles together (tensile instability).
void CpuSolver::compute_density(std::size_t begin, std::size_t end, int worker) {
  detail::density_pass(m_.params, m_.fluid, fluid_sort_.cell_start.data(), m_.static_solids, body_view_, begin, end,
                       neighbour_lists_[worker], neighbour_ranges_.data());
}

// Rigid particles have constant density (§4.1); what they get here is the contact pressure
// from other solids: k rho0 sum_c V_c W over particles of other bodies and walls. It is zero
// when the body touches nothing and makes body<->body and body<->wall contacts push apart with
// the same pressure force as the fluid.
void CpuSolver::compute_body_contact_pressure(std::size_t begin, std::size_t end) {
  const SimulationParams& p = m_.params;
  const SortedSolids& st = m_.static_solids;
  SortedSolids& bv = body_view_;
  for (std::size_t k = begin; k < end; ++k) {
    const float xi = bv.x[k], yi = bv.y[k], zi = bv.z[k];
    const std::int32_t own = bv.body[k];
    float sum = 0;
    for_each_neighbour_run(p.grid, st.cell_start.data(), xi, yi, zi, [&](std::uint32_t b, std::uint32_t e) {
      sum += poly6_run_weighted(st.x.data(), st.y.data(), st.z.data(), st.volume.data(), b, e, xi, yi, zi, p.kernel);
    });
    for_each_neighbour_run(p.grid, bv.cell_start.data(), xi, yi, zi, [&](std::uint32_t b, std::uint32_t e) {
      for (std::uint32_t j = b; j < e; ++j) {
        if (bv.body[j] == own) continue;
        const float dx = xi - bv.x[j], dy = yi - bv.y[j], dz = zi - bv.z[j];
        sum += bv.volume[j] * poly6_shape(p.kernel, dx * dx + dy * dy + dz * dz);
      }
    });
    const float pressure = p.stiffness * p.rest_density_kg_m3 * p.kernel.poly6 * sum;
    bv.pressure[k] = pressure;
    m_.body_particles.pressure[bv.source[k]] = pressure;
  }
}

// Forces on fluid particles (Algorithm 1, lines 4-12). With V = m / rho:
//   pressure (eq. 5): f_p = -(V_p / c_p) sum_i (V_i / c_i) (P_p + P_i) grad W
//   viscosity (eqs. 6, 9): f_p = V_p sum_i V_i (mu_p + mu_i) / 2 (v_i - v_p) lap W
// The pressure pair term is (P_p + P_i), not the paper's (P_p + P_i) / 2: with the half, the sum
// estimates only half of grad P (sum_i V_i grad W vanishes in the bulk), and a column at rest
// would settle at twice the hydrostatic pressure. c is the first-moment correction of the fluid
// volumes (gradient_correction.hpp); wall and body particles keep their volumes (c = 1) and
// take the fluid particle's own pressure (pressure mirroring, Akinci et al. 2012).
void CpuSolver::compute_fluid_forces(std::size_t begin, std::size_t end, int worker) {
  worker_max_accel_[worker] = detail::fluid_force_pass(m_.params, m_.fluid, m_.static_solids, body_view_, begin, end,
                                                       neighbour_lists_[worker], neighbour_ranges_.data());
}

// Forces on the particles of dynamic bodies: from the fluid (f^haptic, eq. 8: the exact opposite
// of each pair term the fluid particle receives above, so momentum is conserved) and from other
// solids (contact): contact pressure, eq. 9 with the solids' viscosities and the artificial
// viscosity of approaching pairs (contact_damping.hpp).
void CpuSolver::compute_body_particle_forces(std::size_t begin, std::size_t end) {
  const SimulationParams& p = m_.params;
  const FluidParticles& f = m_.fluid;
  const SortedSolids& st = m_.static_solids;
  const SortedSolids& bv = body_view_;
  BodyParticles& bp = m_.body_particles;
  const KernelConstants& k = p.kernel;
  const float damping_scale = p.contact_damping_pa_s;
  for (std::size_t i = begin; i < end; ++i) {
    const float xi = bp.x[i], yi = bp.y[i], zi = bp.z[i];
    const float vxi = bp.vx[i], vyi = bp.vy[i], vzi = bp.vz[i];
    const float vol = bp.volume[i], mui = bp.viscosity[i], pb = bp.pressure[i];
    const std::int32_t own = bp.body[i];
    float fx = 0, fy = 0, fz = 0;
    for_each_neighbour_run(p.grid, fluid_sort_.cell_start.data(), xi, yi, zi, [&](std::uint32_t b, std::uint32_t e) {
      for (std::uint32_t j = b; j < e; ++j) {
        const float dx = xi - f.x[j], dy = yi - f.y[j], dz = zi - f.z[j];
        const float r2 = dx * dx + dy * dy + dz * dz;
        if (r2 >= k.h2 || r2 <= 0) continue;
        const float r = std::sqrt(r2);
        const float hr = k.h - r;
        const float pj = f.pressure[j];
        const float pterm = -f.volume[j] * (2.0f * pj * f.volume_correction[j]) * spiky_grad_factor(k, r, hr);
        const float vterm = f.volume[j] * 0.5f * (f.viscosity[j] + mui) * viscosity_laplacian_of(k, hr);
        fx += pterm * dx + vterm * (f.vx[j] - vxi);
        fy += pterm * dy + vterm * (f.vy[j] - vyi);
        fz += pterm * dz + vterm * (f.vz[j] - vzi);
      }
    });
    bp.fx[i] = fx * vol;
    bp.fy[i] = fy * vol;
    bp.fz[i] = fz * vol;
    float cx = 0, cy = 0, cz = 0;
    for_each_neighbour_run(p.grid, st.cell_start.data(), xi, yi, zi, [&](std::uint32_t b, std::uint32_t e) {
      for (std::uint32_t j = b; j < e; ++j) {
        const float dx = xi - st.x[j], dy = yi - st.y[j], dz = zi - st.z[j];
        const float r2 = dx * dx + dy * dy + dz * dz;
        if (r2 >= k.h2 || r2 <= 0) continue;
        const float r = std::sqrt(r2);
        const float hr = k.h - r;
        const float dvx = st.vx[j] - vxi, dvy = st.vy[j] - vyi, dvz = st.vz[j] - vzi;
        const float damping = contact_viscous_pressure(damping_scale, -(dvx * dx + dvy * dy + dvz * dz), r2, k.h2);
        const float pterm = -st.volume[j] * (pb + pb + damping) * spiky_grad_factor(k, r, hr);
        const float vterm = st.volume[j] * 0.5f * (st.viscosity[j] + mui) * viscosity_laplacian_of(k, hr);
        cx += pterm * dx + vterm * dvx;
        cy += pterm * dy + vterm * dvy;
        cz += pterm * dz + vterm * dvz;
      }
    });
    for_each_neighbour_run(p.grid, bv.cell_start.data(), xi, yi, zi, [&](std::uint32_t b, std::uint32_t e) {
      for (std::uint32_t j = b; j < e; ++j) {
        if (bv.body[j] == own) continue;
        const float dx = xi - bv.x[j], dy = yi - bv.y[j], dz = zi - bv.z[j];
        const float r2 = dx * dx + dy * dy + dz * dz;
        if (r2 >= k.h2 || r2 <= 0) continue;
        const float r = std::sqrt(r2);
        const float hr = k.h - r;
        const float dvx = bv.vx[j] - vxi, dvy = bv.vy[j] - vyi, dvz = bv.vz[j] - vzi;
        const float damping = contact_viscous_pressure(damping_scale, -(dvx * dx + dvy * dy + dvz * dz), r2, k.h2);
        const float pterm = -bv.volume[j] * (pb + bv.pressure[j] + damping) * spiky_grad_factor(k, r, hr);
        const float vterm = bv.volume[j] * 0.5f * (bv.viscosity[j] + mui) * viscosity_laplacian_of(k, hr);
        cx += pterm * dx + vterm * dvx;
        cy += pterm * dy + vterm * dvy;
        cz += pterm * dz + vterm * dvz;
      }
    });
    bp.cx[i] = cx * vol;
    bp.cy[i] = cy * vol;
    bp.cz[i] = cz * vol;
  }
}

// Algorithm 2: per body, sum particle forces and torques (eqs. 10-12, in double, in particle
// order), add gravity and the couplings, integrate, then place the particles (eq. 14).
void CpuSolver::step_bodies(double dt) {
  BodyParticles& bp = m_.body_particles;
  for (std::size_t b = 0; b < m_.bodies.size(); ++b) {
    RigidBody& body = m_.bodies[b];
    if (!body.dynamic) continue;
    Vec3 ff, ft, cf, ct;
    for (std::uint32_t i = body.first_particle; i < body.first_particle + body.particle_count; ++i) {
      const Vec3 arm = Vec3{bp.x[i], bp.y[i], bp.z[i]} - body.position;
      const Vec3 fluid{bp.fx[i], bp.fy[i], bp.fz[i]}, contact{bp.cx[i], bp.cy[i], bp.cz[i]};
      ff += fluid;
      ft += cross(arm, fluid);
      cf += contact;
      ct += cross(arm, contact);
    }
    body.fluid_force = ff, body.fluid_torque = ft, body.contact_force = cf, body.contact_torque = ct;
    integrate_body(body, couplings_of_body_[b], devices_, m_.params.gravity_m_s2, dt);
  }
  if (bp.size() == 0) return;
  pool_.parallel_for(bp.size(), [&](std::size_t begin, std::size_t end, int) {
    for (std::size_t i = begin; i < end; ++i) {
      const RigidBody& body = m_.bodies[bp.body[i]];
      const Vec3 world = body.position + rotate(body.orientation, Vec3{bp.rx[i], bp.ry[i], bp.rz[i]});
      const Vec3 v = body.velocity_at(world);
      bp.x[i] = static_cast<float>(world.x), bp.y[i] = static_cast<float>(world.y), bp.z[i] = static_cast<float>(world.z);
      bp.vx[i] = static_cast<float>(v.x), bp.vy[i] = static_cast<float>(v.y), bp.vz[i] = static_cast<float>(v.z);
    }
  });
}

// Leap-frog (Algorithm 1, lines 13-16): v(t + dt/2) = v(t - dt/2) + a dt, x(t + dt) = x + v dt.
// Last resort: a particle that reaches a wall's first particle layer (or leaves the box on an
// open side) is put back (counted; the walls alone must hold the fluid in every validation
// scene, where the count stays zero).
void CpuSolver::integrate_fluid(std::size_t begin, std::size_t end, int worker, float dt) {
  FluidParticles& f = m_.fluid;
  const SimulationParams& p = m_.params;
  std::uint64_t clamped = 0;
  float* pos[3] = {f.x.data(), f.y.data(), f.z.data()};
  float* vel[3] = {f.vx.data(), f.vy.data(), f.vz.data()};
  const float* acc[3] = {f.ax.data(), f.ay.data(), f.az.data()};
  for (std::size_t i = begin; i < end; ++i) {
    bool out = false;
    for (int a = 0; a < 3; ++a) {
      float v = vel[a][i] + acc[a][i] * dt;
      float x = pos[a][i] + v * dt;
      if (x < p.clamp_lo[a]) {
        x = p.clamp_lo[a], v = v < 0 ? 0 : v, out = true;
      } else if (x > p.clamp_hi[a]) {
        x = p.clamp_hi[a], v = v > 0 ? 0 : v, out = true;
      }
      vel[a][i] = v;
      pos[a][i] = x;
    }
    clamped += out ? 1 : 0;
  }
  worker_clamped_[worker] += clamped;
}

void CpuSolver::step(double dt) {
  const float dtf = static_cast<float>(dt);
  auto t0 = Clock::now();
  sort_fluid();
  if (m_.body_particles.size() > 0) {
    build_body_view();
  } else {
    body_view_.resize(0);
    body_view_.cell_start.clear();
  }
  times_.neighbour_search_s += seconds_since(t0);

  t0 = Clock::now();
  neighbour_ranges_.resize(m_.fluid.size());
  pool_.parallel_for(m_.fluid.size(), [&](std::size_t b, std::size_t e, int w) { compute_density(b, e, w); });
  if (body_view_.size() > 0)
    pool_.parallel_for(body_view_.size(), [&](std::size_t b, std::size_t e, int) { compute_body_contact_pressure(b, e); });
  times_.density_s += seconds_since(t0);

  t0 = Clock::now();
  std::fill(worker_max_accel_.begin(), worker_max_accel_.end(), 0.0f);
  pool_.parallel_for(m_.fluid.size(), [&](std::size_t b, std::size_t e, int w) { compute_fluid_forces(b, e, w); });
  if (body_view_.size() > 0)
    pool_.parallel_for(m_.body_particles.size(), [&](std::size_t b, std::size_t e, int) { compute_body_particle_forces(b, e); });
  times_.forces_s += seconds_since(t0);

  t0 = Clock::now();
  step_bodies(dt);
  times_.bodies_s += seconds_since(t0);

  t0 = Clock::now();
  pool_.parallel_for(m_.fluid.size(), [&](std::size_t b, std::size_t e, int w) { integrate_fluid(b, e, w, dtf); });
  clamped_ = 0;
  for (auto c : worker_clamped_) clamped_ += c;
  times_.integration_s += seconds_since(t0);

  time_s_ += dt;
  ++steps_;
}

void CpuSolver::check_finite() const { check_finite_state(m_, time_s_); }

}  // namespace hapfluid::sim
