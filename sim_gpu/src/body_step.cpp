#include "body_step.hpp"

namespace hapfluid::sim::detail {

void sort_body_view(const GridGeometry& grid, const BodyParticles& bp, CellSort& sort, SortedSolids& v) {
  sort.sort(grid, bp.x.data(), bp.y.data(), bp.z.data(), bp.size());
  v.resize(bp.size());
  for (std::size_t k = 0; k < bp.size(); ++k) {
    const std::uint32_t i = sort.order[k];
    v.x[k] = bp.x[i], v.y[k] = bp.y[i], v.z[k] = bp.z[i];
    v.vx[k] = bp.vx[i], v.vy[k] = bp.vy[i], v.vz[k] = bp.vz[i];
    v.volume[k] = bp.volume[i], v.viscosity[k] = bp.viscosity[i], v.no_slip[k] = 1.0f;
    v.body[k] = bp.body[i];
    v.source[k] = i;
  }
  v.cell_start = sort.cell_start;
}

void sum_body_forces(SimulationModel& m) {
  const BodyParticles& bp = m.body_particles;
  for (RigidBody& body : m.bodies) {
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
  }
}

void step_bodies(SimulationModel& m, std::vector<std::vector<VirtualCoupling*>>& couplings_of_body,
                 const std::vector<DeviceState>& devices, double dt, ThreadPool& pool) {
  BodyParticles& bp = m.body_particles;
  sum_body_forces(m);
  for (std::size_t b = 0; b < m.bodies.size(); ++b)
    if (m.bodies[b].dynamic) integrate_body(m.bodies[b], couplings_of_body[b], devices, m.params.gravity_m_s2, dt);
  if (bp.size() == 0) return;
  pool.parallel_for(bp.size(), [&](std::size_t begin, std::size_t end, int) {
    for (std::size_t i = begin; i < end; ++i) {
      const RigidBody& body = m.bodies[bp.body[i]];
      const Vec3 world = body.position + rotate(body.orientation, Vec3{bp.rx[i], bp.ry[i], bp.rz[i]});
      const Vec3 v = body.velocity_at(world);
      bp.x[i] = static_cast<float>(world.x), bp.y[i] = static_cast<float>(world.y), bp.z[i] = static_cast<float>(world.z);
      bp.vx[i] = static_cast<float>(v.x), bp.vy[i] = static_cast<float>(v.y), bp.vz[i] = static_cast<float>(v.z);
    }
  });
}

void set_body_particle_velocities(SimulationModel& m) {
  BodyParticles& bp = m.body_particles;
  for (const RigidBody& body : m.bodies) {
    if (!body.dynamic) continue;
    for (std::uint32_t i = body.first_particle; i < body.first_particle + body.particle_count; ++i) {
      const Vec3 v = body.velocity_at({bp.x[i], bp.y[i], bp.z[i]});
      bp.vx[i] = static_cast<float>(v.x), bp.vy[i] = static_cast<float>(v.y), bp.vz[i] = static_cast<float>(v.z);
    }
  }
}

}  // namespace hapfluid::sim::detail
