#include "hapfluid/sim/cpu_solver.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>

#include "hapfluid/sim/contact_damping.hpp"
#include "hapfluid/sim/finite_state.hpp"
#include "body_contacts.hpp"
#include "body_step.hpp"
#include "sph_passes.hpp"

namespace hapfluid::sim {
namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

}  // namespace

CpuSolver::CpuSolver(SimulationModel model, int threads) : m_(std::move(model)), pool_(threads) {
  devices_.resize(m_.devices.size());
  for (std::size_t d = 0; d < m_.devices.size(); ++d)
    devices_[d] = device_state_from(config::evaluate_motion(m_.devices[d].motion, 0.0));
  couplings_of_body_.resize(m_.bodies.size());
  for (auto& c : m_.couplings) couplings_of_body_[c.body].push_back(&c);
  slot_max_accel_.assign(pool_.slots(), 0);
  slot_clamped_.assign(pool_.slots(), 0);
  neighbour_lists_.resize(pool_.slots());
  body_reach_.resize(m_.bodies.size());
  // Density and pressure of the initial state, so that a frame exported before the first step
  // shows them (the step recomputes them from the same positions).
  sort_fluid();
  if (m_.body_particles.size() > 0) build_body_view();
  neighbour_ranges_.resize(m_.fluid.size());
  pool_.parallel_for(m_.fluid.size(), [&](std::size_t b, std::size_t e, int w) { compute_density(b, e, w); });
  detail::set_body_particle_velocities(m_);
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

void CpuSolver::sort_fluid() {
  FluidParticles& f = m_.fluid;
  fluid_sort_.sort(m_.params.grid, f.x.data(), f.y.data(), f.z.data(), f.size());
  f.permute(fluid_sort_.order);
}

void CpuSolver::build_body_view() { detail::sort_body_view(m_.params.grid, m_.body_particles, body_sort_, body_view_); }

// Eq. 2 over fluid neighbours, plus the boundary contribution rho0 V_b W of wall and body
// particles (Akinci et al. 2012), then eq. 7. Negative pressures are clamped to zero: a free
// surface must not pull particles together (tensile instability).
void CpuSolver::compute_density(std::size_t begin, std::size_t end, int slot) {
  detail::density_pass(m_.params, m_.fluid, fluid_sort_.cell_start.data(), m_.static_solids, body_view_, begin, end,
                       neighbour_lists_[slot], neighbour_ranges_.data());
}

// Rigid particles have constant density (§4.1); what they get is the contact pressure from
// other solids (body_contacts.hpp), the same force law as the fluid's pressure.
// Forces on fluid particles (Algorithm 1, lines 4-12). With V = m / rho:
//   pressure (eq. 5): f_p = -(V_p / c_p) sum_i (V_i / c_i) (P_p + P_i) grad W
//   viscosity (eqs. 6, 9): f_p = V_p sum_i V_i (mu_p + mu_i) / 2 (v_i - v_p) lap W
// The pressure pair term is (P_p + P_i), not the paper's (P_p + P_i) / 2: with the half, the sum
// estimates only half of grad P (sum_i V_i grad W vanishes in the bulk), and a column at rest
// would settle at twice the hydrostatic pressure. c is the first-moment correction of the fluid
// volumes (gradient_correction.hpp); wall and body particles keep their volumes (c = 1) and
// take the fluid particle's own pressure (pressure mirroring, Akinci et al. 2012).
void CpuSolver::compute_fluid_forces(std::size_t begin, std::size_t end, int slot) {
  slot_max_accel_[slot] = detail::fluid_force_pass(m_.params, m_.fluid, m_.static_solids, body_view_, begin, end,
                                                       neighbour_lists_[slot], neighbour_ranges_.data());
}

// Forces on the particles of dynamic bodies: from the fluid (f^haptic, eq. 8: the exact opposite
// of each pair term the fluid particle receives above, so momentum is conserved) and from other
// solids (contact): contact pressure, eq. 9 with the solids' viscosities and the artificial
// viscosity of approaching pairs (contact_damping.hpp).
void CpuSolver::compute_body_particle_forces(std::size_t begin, std::size_t end) {
  const SimulationParams& p = m_.params;
  const FluidParticles& f = m_.fluid;
  BodyParticles& bp = m_.body_particles;
  const KernelConstants& k = p.kernel;
  for (std::size_t i = begin; i < end; ++i) {
    const float xi = bp.x[i], yi = bp.y[i], zi = bp.z[i];
    const float vxi = bp.vx[i], vyi = bp.vy[i], vzi = bp.vz[i];
    const float vol = bp.volume[i], mui = bp.viscosity[i];
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
  }
  detail::body_contact_forces(p, m_.static_solids, body_view_, bp, body_reach_, begin, end);
}

// Leap-frog (Algorithm 1, lines 13-16): v(t + dt/2) = v(t - dt/2) + a dt, x(t + dt) = x + v dt.
// Last resort: a particle that reaches a wall's first particle layer (or leaves the box on an
// open side) is put back (counted; the walls alone must hold the fluid in every validation
// scene, where the count stays zero).
void CpuSolver::integrate_fluid(std::size_t begin, std::size_t end, int slot, float dt) {
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
      out = clamp_to_domain(p, a, x, v) || out;
      vel[a][i] = v;
      pos[a][i] = x;
    }
    clamped += out ? 1 : 0;
  }
  slot_clamped_[slot] += clamped;
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
  if (body_view_.size() > 0) {
    body_reach_.update(m_.body_particles, m_.params.kernel.h);
    pool_.parallel_for(body_view_.size(), [&](std::size_t b, std::size_t e, int) {
      detail::body_contact_pressure(m_.params, m_.static_solids, body_view_, m_.body_particles, body_reach_, b, e);
    });
  }
  times_.density_s += seconds_since(t0);

  t0 = Clock::now();
  std::fill(slot_max_accel_.begin(), slot_max_accel_.end(), 0.0f);
  pool_.parallel_for(m_.fluid.size(), [&](std::size_t b, std::size_t e, int w) { compute_fluid_forces(b, e, w); });
  if (body_view_.size() > 0)
    pool_.parallel_for(m_.body_particles.size(), [&](std::size_t b, std::size_t e, int) { compute_body_particle_forces(b, e); });
  times_.forces_s += seconds_since(t0);

  t0 = Clock::now();
  detail::step_bodies(m_, couplings_of_body_, devices_, dt, pool_);
  times_.bodies_s += seconds_since(t0);

  t0 = Clock::now();
  pool_.parallel_for(m_.fluid.size(), [&](std::size_t b, std::size_t e, int w) { integrate_fluid(b, e, w, dtf); });
  clamped_ = 0;
  for (auto c : slot_clamped_) clamped_ += c;
  times_.integration_s += seconds_since(t0);

  time_s_ += dt;
  ++steps_;
}

void CpuSolver::check_finite() const { check_finite_state(m_, time_s_); }

ComputeDevice CpuSolver::device() const { return cpu_threads_device(threads()); }

}  // namespace hapfluid::sim
