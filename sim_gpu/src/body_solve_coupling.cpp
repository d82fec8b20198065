#include "body_solve_coupling.hpp"

#include <algorithm>

namespace hapfluid::sim::detail {
namespace {

using Vec6 = BodySolveCoupling::Vec6;
using Mat6 = BodySolveCoupling::Mat6;

Mat6 inverse6(const double a[6][6]) {
  Mat6 inv{};
  for (int c = 0; c < 6; ++c) {
    double e[6] = {}, x[6];
    e[c] = 1;
    solve6(a, e, x);
    for (int r = 0; r < 6; ++r) inv[6 * r + c] = x[r];
  }
  return inv;
}

// Adds the wrench of force (fx, fy, fz) at body particle p to w: the force and its torque
// about the body's centre of mass c.
inline void add_wrench(double* w, const SortedSolids& bodies, std::uint32_t p, const float* c, double fx, double fy,
                       double fz) {
  const double rx = bodies.x[p] - c[0], ry = bodies.y[p] - c[1], rz = bodies.z[p] - c[2];
  w[0] += fx, w[1] += fy, w[2] += fz;
  w[3] += ry * fz - rz * fy, w[4] += rz * fx - rx * fz, w[5] += rx * fy - ry * fx;
}

Vec6 times(const Mat6& a, const Vec6& v) {
  Vec6 out{};
  for (int r = 0; r < 6; ++r)
    for (int c = 0; c < 6; ++c) out[r] += a[6 * r + c] * v[c];
  return out;
}

}  // namespace

void BodySolveCoupling::init(const SimulationModel& m, int slots) {
  slots_ = slots;
  bodies_ = m.bodies.size();
  particle_mass_ = m.params.fluid_particle_mass_kg;
  dynamic_.assign(bodies_, 0);
  for (std::size_t b = 0; b < bodies_; ++b) dynamic_[b] = m.bodies[b].dynamic && m.bodies[b].particle_count > 0;
  active_ = std::any_of(dynamic_.begin(), dynamic_.end(), [](char c) { return c != 0; });
  mobility_.assign(bodies_, Mat6{});
  relax_.assign(bodies_, Mat6{});
  u_start_.assign(bodies_, Vec6{});
  u_.assign(bodies_, Vec6{});
  force_.assign(bodies_, Vec6{});
  com_.assign(3 * bodies_, 0.0f);
  slot_force_.assign(6 * bodies_ * slots, 0.0);
  slot_response_.assign(36 * bodies_ * slots, 0.0);
  slot_j_.assign(6 * bodies_ * slots, 0.0);
  // Room for every particle of a slot next to two bodies at once: a step allocates only where
  // more than that meet in one slot.
  const std::size_t dynamic_bodies = static_cast<std::size_t>(std::count(dynamic_.begin(), dynamic_.end(), 1));
  slot_jacobians_.assign(static_cast<std::size_t>(slots), {});
  if (active_)
    for (auto& j : slot_jacobians_)
      j.reserve((m.fluid.size() / static_cast<std::size_t>(slots) + 1) * std::min<std::size_t>(dynamic_bodies, 2));
}

void BodySolveCoupling::begin_step(const SimulationModel& m,
                                   const std::vector<std::vector<VirtualCoupling*>>& couplings_of_body,
                                   const std::vector<DeviceState>& devices, double dt, const SortedSolids& bodies,
                                   const std::vector<PairLists>& lists, const PairRange* ranges,
                                   const DfsphFields& fields, ThreadPool& pool) {
  if (!active_) return;
  for (std::size_t b = 0; b < bodies_; ++b) {
    const Vec3& c = m.bodies[b].position;
    com_[3 * b] = static_cast<float>(c.x), com_[3 * b + 1] = static_cast<float>(c.y), com_[3 * b + 2] = static_cast<float>(c.z);
  }
  // sum_i factor_i J_i J_i^T per body; J_i from particle i's pairs with that body's particles.
  std::fill(slot_response_.begin(), slot_response_.end(), 0.0);
  pool.parallel_for(m.fluid.size(), [&](std::size_t begin, std::size_t end, int w) {
    const PairLists& l = lists[w];
    double* j6 = slot_j_.data() + 6 * bodies_ * w;
    double* s36 = slot_response_.data() + 36 * bodies_ * w;
    std::vector<ParticleJacobian>& jacobians = slot_jacobians_[static_cast<std::size_t>(w)];
    jacobians.clear();
    for (std::size_t i = begin; i < end; ++i) {
      const PairRange& r = ranges[i];
      if (r.bodies == 0) continue;
      const std::uint32_t first = r.offset + r.fluid + r.statics, last = first + r.bodies;
      for (std::uint32_t q = first; q < last; ++q) {
        const std::uint32_t p = l.index[q];
        const std::size_t b = static_cast<std::size_t>(bodies.body[p]);
        add_wrench(j6 + 6 * b, bodies, p, &com_[3 * b], l.term[q].x, l.term[q].y, l.term[q].z);
      }
      const double factor = fields.factor[i];
      for (std::uint32_t q = first; q < last; ++q) {
        const std::size_t b = static_cast<std::size_t>(bodies.body[l.index[q]]);
        double* j = j6 + 6 * b;
        if (j[0] == 0 && j[1] == 0 && j[2] == 0 && j[3] == 0 && j[4] == 0 && j[5] == 0) continue;  // done
        double* s = s36 + 36 * b;
        for (int a = 0; a < 6; ++a)
          for (int c = 0; c < 6; ++c) s[6 * a + c] += factor * j[a] * j[c];
        ParticleJacobian& e = jacobians.emplace_back();
        e.particle = static_cast<std::uint32_t>(i), e.body = static_cast<std::uint32_t>(b);
        std::copy(j, j + 6, e.j);
        std::fill(j, j + 6, 0.0);
      }
    }
  });
  for (std::size_t b = 0; b < bodies_; ++b) {
    if (!dynamic_[b]) continue;
    const BodySystem sys = body_system(m.bodies[b], couplings_of_body[b], devices, m.params.gravity_m_s2, dt);
    const Mat6 a_inv = inverse6(sys.a);
    Mat6 s{};
    for (int w = 0; w < slots_; ++w)
      for (int k = 0; k < 36; ++k) s[k] += slot_response_[36 * (bodies_ * w + b) + k];
    double i_plus_l[6][6];
    for (int r = 0; r < 6; ++r)
      for (int c = 0; c < 6; ++c) {
        double l = 0;
        for (int k = 0; k < 6; ++k) l += a_inv[6 * r + k] * s[6 * k + c];
        i_plus_l[r][c] = (r == c ? 1.0 : 0.0) + particle_mass_ * l;
      }
    relax_[b] = inverse6(i_plus_l);
    for (int k = 0; k < 36; ++k) mobility_[b][k] = dt * a_inv[k];
  }
}

void BodySolveCoupling::start_solve(std::size_t body, const Vec6& u_start) {
  u_start_[body] = u_start;
  u_[body] = u_start;
  force_[body] = Vec6{};
}

void BodySolveCoupling::start_solve_from_body_states(const SimulationModel& m) {
  for (std::size_t b = 0; b < bodies_; ++b) {
    if (!dynamic_[b]) continue;
    const RigidBody& body = m.bodies[b];
    const Vec3 &v = body.linear_velocity, &w = body.angular_velocity;
    start_solve(b, Vec6{v.x, v.y, v.z, w.x, w.y, w.z});
  }
  std::fill(slot_force_.begin(), slot_force_.end(), 0.0);
}

void BodySolveCoupling::add_forces(int slot, const float* k) {
  double* acc = slot_force_.data() + 6 * bodies_ * static_cast<std::size_t>(slot);
  for (const ParticleJacobian& e : slot_jacobians_[static_cast<std::size_t>(slot)]) {
    const float ki = k[e.particle];
    if (ki == 0) continue;
    const double mk = static_cast<double>(particle_mass_) * ki;
    double* a = acc + 6 * static_cast<std::size_t>(e.body);
    for (int c = 0; c < 6; ++c) a[c] += mk * e.j[c];
  }
}

void BodySolveCoupling::subtract_flux(int slot, float* rate) const {
  for (const ParticleJacobian& e : slot_jacobians_[static_cast<std::size_t>(slot)]) {
    const Vec6& u = u_[e.body];
    double flux = 0;
    for (int c = 0; c < 6; ++c) flux += e.j[c] * u[c];
    rate[e.particle] -= static_cast<float>(flux);
  }
}

void BodySolveCoupling::update_velocities() {
  for (std::size_t b = 0; b < bodies_; ++b) {
    if (!dynamic_[b]) continue;
    for (int w = 0; w < slots_; ++w) {
      double* f = slot_force_.data() + 6 * (bodies_ * w + b);
      for (int k = 0; k < 6; ++k) force_[b][k] += f[k], f[k] = 0;
    }
    const Vec6 pushed = times(mobility_[b], force_[b]);
    Vec6 gap;
    for (int k = 0; k < 6; ++k) gap[k] = u_start_[b][k] + pushed[k] - u_[b][k];
    const Vec6 step = times(relax_[b], gap);
    for (int k = 0; k < 6; ++k) u_[b][k] += step[k];
  }
}

void BodySolveCoupling::write_particle_velocities(SimulationModel& m, SortedSolids& bodies) const {
  // On the calling thread: a few flops per body particle, less than a hand-off to the pool costs.
  BodyParticles& bp = m.body_particles;
  for (std::size_t p = 0; p < bodies.size(); ++p) {
    const std::size_t b = static_cast<std::size_t>(bodies.body[p]);
    const Vec6& u = u_[b];
    const double rx = bodies.x[p] - com_[3 * b], ry = bodies.y[p] - com_[3 * b + 1], rz = bodies.z[p] - com_[3 * b + 2];
    const float vx = static_cast<float>(u[0] + u[4] * rz - u[5] * ry);
    const float vy = static_cast<float>(u[1] + u[5] * rx - u[3] * rz);
    const float vz = static_cast<float>(u[2] + u[3] * ry - u[4] * rx);
    bodies.vx[p] = vx, bodies.vy[p] = vy, bodies.vz[p] = vz;
    const std::uint32_t s = bodies.source[p];
    bp.vx[s] = vx, bp.vy[s] = vy, bp.vz[s] = vz;
  }
}

}  // namespace hapfluid::sim::detail
