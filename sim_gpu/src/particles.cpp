#include "hapfluid/sim/particles.hpp"

namespace hapfluid::sim {
namespace {

template <class T>
void apply(std::vector<T>& values, const std::vector<std::uint32_t>& order, std::vector<T>& scratch) {
  scratch.resize(values.size());
  for (std::size_t k = 0; k < order.size(); ++k) scratch[k] = values[order[k]];
  values.swap(scratch);
}

}  // namespace

void FluidParticles::resize(std::size_t n) {
  for (auto* v : {&x, &y, &z, &vx, &vy, &vz, &ax, &ay, &az, &density, &pressure, &volume, &viscosity,
                  &density_stiffness_dt2, &divergence_stiffness_dt, &viscous_dvx, &viscous_dvy, &viscous_dvz})
    v->resize(n, 0.0f);
  volume_correction.resize(n, 1.0f);
  id.resize(n, 0);
}

void FluidParticles::permute(const std::vector<std::uint32_t>& order) {
  // Density, pressure, volume and volume correction are recomputed after the sort, so only
  // state is moved.
  for (auto* v : {&x, &y, &z, &vx, &vy, &vz, &ax, &ay, &az, &viscosity, &density_stiffness_dt2, &divergence_stiffness_dt,
                  &viscous_dvx, &viscous_dvy, &viscous_dvz})
    apply(*v, order, scratch_f_);
  apply(id, order, scratch_u_);
}

void SortedSolids::resize(std::size_t n) {
  for (auto* v : {&x, &y, &z, &vx, &vy, &vz, &volume, &viscosity, &no_slip, &pressure}) v->resize(n, 0.0f);
  body.resize(n, kWall);
  source.resize(n, 0);
}

void BodyParticles::resize(std::size_t n) {
  for (auto* v : {&x, &y, &z, &vx, &vy, &vz, &rx, &ry, &rz, &volume, &viscosity, &pressure, &fx, &fy, &fz, &cx, &cy, &cz})
    v->resize(n, 0.0f);
  body.resize(n, 0);
}

}  // namespace hapfluid::sim
