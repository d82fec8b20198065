// Rigid bodies from triangle meshes (§4.1): surface sampling into particles, and mass, centre of
// mass and inertia tensor of the closed mesh by the divergence theorem (Eberly, "Polyhedral Mass
// Properties (Revisited)", 2002: volume integrals as sums over triangles, exact for polyhedra).
#pragma once

#include <string>
#include <vector>

#include "hapfluid/config/mesh.hpp"
#include "hapfluid/sim/math.hpp"

namespace hapfluid::sim {

struct MassProperties {
  double volume_m3 = 0;
  Vec3 centre_of_mass_m;           // in the (scaled) mesh frame
  Mat3 inertia_per_density;        // about the centre of mass, mesh axes, m^5 (times density: kg m^2)
};

// Scaled mesh vertices (double).
std::vector<Vec3> scaled_vertices(const config::TriangleMesh& mesh, double scale);

// Throws std::runtime_error naming `what` when the mesh is not closed and consistently oriented
// (each edge used exactly twice, once in each direction) or encloses no positive volume.
void check_closed_mesh(const config::TriangleMesh& mesh, const std::string& what);

MassProperties mass_properties(const config::TriangleMesh& mesh, double scale);

inline constexpr double kSampleRadiusFactor = 0.8;

// Points on the surface with no two closer than 0.8 spacing_m and no surface point farther than
// that from a sample (greedy Poisson-disk thinning of a fine barycentric lattice; the
// candidate order is fixed, so the result is deterministic). Mesh frame, scaled.
// inset_m moves the samples inward along the surface normal (vertex normals for vertices, face
// normals elsewhere): boundary particles placed inside the surface put the fluid's effective
// boundary on the mesh surface itself, so a body displaces its true volume (Archimedes) and a
// container holds its true capacity. Walls thinner than twice the inset end up as two sheets
// that have crossed, still about the mid-surface.
std::vector<Vec3> sample_surface(const config::TriangleMesh& mesh, double scale, double spacing_m, double inset_m = 0);

// Crossings of the ray p + t dir (t > 0) with the mesh's triangles, scaled mesh frame.
int ray_crossings(const std::vector<Vec3>& vertices, const config::TriangleMesh& mesh, const Vec3& p, const Vec3& dir);

// Inside test for a closed mesh (parity of crossings of a ray), scaled mesh frame.
bool inside_closed_mesh(const std::vector<Vec3>& vertices, const config::TriangleMesh& mesh, const Vec3& p);

}  // namespace hapfluid::sim
