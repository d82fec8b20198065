// Domain walls as boundary particles (Akinci et al. 2012, "Versatile rigid-fluid coupling for
// incompressible SPH"): layers of particles behind each enabled wall of the domain box, each with
// a volume V_b = 1 / sum_k W(x_b - x_k) over its own solid, so that it contributes rho0 V_b W to
// fluid density and pushes fluid back with the fluid's own pressure (pressure mirroring).
#pragma once

#include <vector>

#include "hapfluid/config/scene.hpp"
#include "hapfluid/sim/cubic_kernel.hpp"
#include "hapfluid/sim/kernels.hpp"
#include "hapfluid/sim/math.hpp"

namespace hapfluid::sim {

// Positions of the wall particles of the domain: `layers` layers behind each enabled wall,
// reaching `layers` spacings past the box so that corners are closed.
std::vector<Vec3> wall_particle_positions(const config::Domain& domain, double spacing_m, int layers);

// Akinci volumes 1 / sum_k W(x_b - x_k) of a set of particles forming one solid (self included),
// with the poly6 kernel (wcsph) or the cubic spline (dfsph).
std::vector<float> boundary_volumes(const std::vector<Vec3>& positions, const KernelConstants& kernel);
std::vector<float> boundary_volumes(const std::vector<Vec3>& positions, const CubicKernel& kernel);

}  // namespace hapfluid::sim
