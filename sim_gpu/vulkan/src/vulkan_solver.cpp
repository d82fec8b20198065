#include "hapfluid/sim_vulkan/vulkan_solver.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string>

#include "../shaders/bindings.glsl"
#include "hapfluid/sim/dfsph_solver.hpp"
#include "hapfluid/sim/finite_state.hpp"
#include "hapfluid/sim/gradient_correction.hpp"
#include "hapfluid/sim/kernels.hpp"
#include "hapfluid/sim/wall_map.hpp"
#include "recording.hpp"

namespace hapfluid::sim::vulkan {
namespace {

// The std140 block `Params` of shaders/common.glsl.
struct ParamsBlock {
  float kernel[4];       // h, h^2, poly6, spiky gradient
  float material[4];     // viscosity Laplacian, particle mass, rho0, stiffness
  float gravity_dt[4];
  float clamp_lo[4];
  float clamp_hi[4];
  float grid_origin[4];  // origin, cell size
  std::int32_t grid_dims[4];
  std::uint32_t counts[4];  // fluid, static solids, body particles, bodies
  float corrections[4];      // clamp of the first-moment correction c: min, max; contact damping, Pa s
  float dfsph_kernel[4];     // h^2, 1 / h, W scale, gradient scale
  float dfsph_a[4];          // fluid volume, density and divergence tolerances, XSPH fraction
  float dfsph_b[4];          // fewest neighbours of a divergence estimate, fluid viscosity, 0.01 h^2, velocity kept
  std::int32_t dfsph_c[4];   // fewest density and divergence iterations, most iterations, fluid workgroups of 64
  std::int32_t dfsph_d[4];   // neighbour list capacity; unused
};
static_assert(sizeof(ParamsBlock) == 224);

// The head of the solve state (shaders/dfsph_common.glsl): counters the host reads and clears.
constexpr std::uint32_t kSolveDensityIts = 7, kSolveDivergenceIts = 8, kSolveViscosityIts = 9, kSolveUnconverged = 10,
                        kSolveExplicitViscosity = 11, kSolveLastDensityError = 12, kSolveMaxDensityError = 13,
                        kSolveListOverflow = 19, kSolveMostDensityIts = 20, kSolveMostDivergenceIts = 21,
                        kSolveMostViscosityIts = 22, kSolveBudgetOverruns = 23, kSolvePartials = 32;

// Room in each particle's neighbour list: half again the neighbours of a particle in the bulk at
// rest (the lattice points within h), a multiple of 8. A fluid compressed by half again has
// failed long before; a list that would overflow stops the run with an error.
std::uint32_t list_capacity(const SimulationParams& p) {
  const double ratio = p.incompressible.kernel.h / p.particle_spacing_m;
  const std::uint32_t bulk = static_cast<std::uint32_t>(std::ceil(4.0 / 3.0 * kPi * ratio * ratio * ratio));
  return (bulk * 3 / 2 + 7) / 8 * 8;
}

// The walls' volume map as the shaders read it (dfsph_common.glsl): a header, then its tables.
std::vector<float> wall_map_words(const WallMap& w) {
  std::vector<float> out(20, 0.0f);
  for (int k = 0; k < 6; ++k) out[k] = w.enabled[k] ? 1.0f : 0.0f, out[6 + k] = w.face[k];
  out[12] = w.offset_m, out[13] = w.gradient_scale, out[14] = w.h, out[15] = w.du;
  out[16] = static_cast<float>(w.share.size());
  for (const std::vector<float>* t : {&w.share, &w.slope, &w.friction_normal, &w.friction_tangent})
    out.insert(out.end(), t->begin(), t->end());
  return out;
}

constexpr VkBufferUsageFlags kStorage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT;
constexpr VkBufferUsageFlags kTexel = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_UNIFORM_TEXEL_BUFFER_BIT;
constexpr VkFormat kVec4 = VK_FORMAT_R32G32B32A32_SFLOAT;
constexpr VkFormat kUint = VK_FORMAT_R32_UINT;

std::vector<float> pack4(std::size_t n, const float* a, const float* b, const float* c, const float* d,
                         float d_default = 0.0f) {
  std::vector<float> out(4 * std::max<std::size_t>(n, 1), 0.0f);
  for (std::size_t i = 0; i < n; ++i) {
    out[4 * i] = a[i], out[4 * i + 1] = b[i], out[4 * i + 2] = c[i];
    out[4 * i + 3] = d ? d[i] : d_default;
  }
  return out;
}

}  // namespace

// Every device array of the backend. Texel views alias the storage buffers neighbour loops read.
struct VulkanSolver::Buffers {
  Buffer params, reduce;
  Buffer f_pos, f_vel, f_id, s_pos, s_vel, s_id, s_density, s_acc;
  Buffer cell_count, cell_start, block_sums, cell_of, rank, order;
  Buffer w_a, w_b, w_c, w_cell_start;
  Buffer b_pos, b_vel, b_rest, b_force, b_contact, b_pressure, v_a, v_b, v_c;
  Buffer body_state, body_chunks, body_partials, body_sums;
  Buffer d_particle, d_solve, d_walls, d_list, d_kappa;
  TexelView t_d_walls, t_d_particle, t_d_list, t_d_kappa;
  TexelView t_s_pos, t_s_vel, t_s_density, t_cell_start, t_w_a, t_w_b, t_w_c, t_w_cell_start;
  TexelView t_v_a, t_v_b, t_v_c, t_v_cell_start;
};

VulkanSolver::VulkanSolver(SimulationModel model, const VulkanSolverOptions& options) : m_(std::move(model)) {
  dfsph_ = m_.params.solver == config::PressureSolver::dfsph;
  if (dfsph_ && m_.body_particles.size() > 0)
    throw std::runtime_error(m_.scene_name + ": the Vulkan backend runs fluid.solver = \"dfsph\" without dynamic bodies so " +
                             "far, and this scene has " + std::to_string(m_.body_particles.size()) +
                             " dynamic body particles (run it with --backend cpu)");
  if (dfsph_) {
    const int cap = m_.params.incompressible.max_iterations;
    divergence_budget_ = IterationBudget(cap), density_budget_ = IterationBudget(cap);
    viscosity_budget_ = IterationBudget(cap);
    // The fluid meets the static bodies as particles and the walls as their volume map.
    fluid_statics_ = static_solids_beside_walls(m_);
    viscous_ = m_.params.fluid_viscosity_pa_s > 0;
    for (const RigidBody& b : m_.bodies) viscous_ = viscous_ || b.viscosity_pa_s > 0;
  }
  context_ = std::make_unique<Context>(options.context);
  program_ = std::make_unique<ComputeProgram>(*context_);
  devices_.resize(m_.devices.size());
  for (std::size_t d = 0; d < m_.devices.size(); ++d)
    devices_[d] = device_state_from(config::evaluate_motion(m_.devices[d].motion, 0.0));
  couplings_of_body_.resize(m_.bodies.size());
  for (auto& c : m_.couplings) couplings_of_body_[c.body].push_back(&c);
  // Body particle velocities at start (eq. 14 with the initial body velocities), as CpuSolver.
  BodyParticles& bp = m_.body_particles;
  for (const RigidBody& body : m_.bodies) {
    if (!body.dynamic) continue;
    for (std::uint32_t i = body.first_particle; i < body.first_particle + body.particle_count; ++i) {
      const Vec3 v = body.velocity_at({bp.x[i], bp.y[i], bp.z[i]});
      bp.vx[i] = static_cast<float>(v.x), bp.vy[i] = static_cast<float>(v.y), bp.vz[i] = static_cast<float>(v.z);
    }
  }

  fluid_count_ = static_cast<std::uint32_t>(m_.fluid.size());
  solid_count_ = static_cast<std::uint32_t>(fluid_statics().size());
  body_particle_count_ = static_cast<std::uint32_t>(bp.size());
  cell_count_ = static_cast<std::uint32_t>(m_.params.grid.cell_count());
  // The body cell starts follow the fluid's in one buffer, at an offset a texel view may start at.
  const std::uint32_t align =
      std::max<std::uint32_t>(1, static_cast<std::uint32_t>(context_->properties().limits.minTexelBufferOffsetAlignment / 4));
  body_start_base_ = (cell_count_ + 1 + align - 1) / align * align;
  scan_blocks_ = groups(cell_count_, 1024);
  max_groups_ = groups(std::max<std::uint32_t>(fluid_count_ + body_particle_count_, 1), 256);
  for (const RigidBody& body : m_.bodies)
    if (body.dynamic) body_chunk_count_ += groups(body.particle_count, 256);
  check_device_limits();
  create_buffers();
  upload_model();

  VkFenceCreateInfo fence{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
  check(vkCreateFence(context_->device(), &fence, nullptr, &fence_), "vkCreateFence");
  if (options.timestamps && context_->timestamps_supported()) {
    // Timestamps: one at the start, then after sort, density, forces and integration of each
    // substep (dfsph: sort, density, divergence solve, forces and viscosity, density solve,
    // integration), and after the CFL maxima: 4 N + 2 (6 N + 2) for N substeps.
    queries_per_step_ = dfsph_ ? 6 : 4;
    query_capacity_ = queries_per_step_ * kMaxTimedSubsteps + 2;
    VkQueryPoolCreateInfo info{VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO};
    info.queryType = VK_QUERY_TYPE_TIMESTAMP;
    info.queryCount = query_capacity_;
    check(vkCreateQueryPool(context_->device(), &info, nullptr, &queries_), "vkCreateQueryPool");
  }
  // The CFL inputs of the initial state.
  write_params(0.0f);
  if (body_particle_count_ > 0) {
    write_body_states();
    if (queries_) {
      VkQueryPoolCreateInfo info{VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO};
      info.queryType = VK_QUERY_TYPE_TIMESTAMP;
      info.queryCount = kBodyStepQueries;
      check(vkCreateQueryPool(context_->device(), &info, nullptr, &body_queries_), "vkCreateQueryPool");
    }
    body_head_ = allocate_command_buffer();
    body_tail_ = allocate_command_buffer();
    body_tail_maxima_ = allocate_command_buffer();
    record_body_step(body_head_, body_tail_, false);
    record_body_step(VK_NULL_HANDLE, body_tail_maxima_, true);
  }
  if (dfsph_ && m_.params.incompressible.settle_s > 0) settle(m_.params.incompressible.settle_s);
  VkCommandBuffer cb = allocate_command_buffer();
  recorded_[recording_key(0)] = cb;
  record_steps(cb, 0);
  submit_and_wait(cb);
  read_results(0);
  work_ = {};
}

void VulkanSolver::settle(double duration_s) {
  const double dt = m_.params.fixed_dt_s > 0 ? m_.params.fixed_dt_s : m_.params.max_dt_s;
  const int steps = std::max(1, static_cast<int>(std::ceil(duration_s / dt - 1e-9)));
  velocity_kept_ = kSettleVelocityKept;
  for (int k = 0; k < steps; ++k) step_many(dt, 1);
  velocity_kept_ = 1.0f;
  time_s_ = 0;
  steps_ = 0;
  clamped_ = 0;
  pass_times_ = {};
  iterations_ = {};
  work_ = {};
}

const Buffer& VulkanSolver::dfsph_solve_buffer() const { return b_->d_solve; }

void VulkanSolver::read_solver_counters() {
  if (!dfsph_) return;
  std::uint32_t* solve = static_cast<std::uint32_t*>(b_->d_solve.mapped());
  iterations_.density_iterations += solve[kSolveDensityIts];
  iterations_.divergence_iterations += solve[kSolveDivergenceIts];
  iterations_.viscosity_iterations += solve[kSolveViscosityIts];
  iterations_.unconverged_solves += solve[kSolveUnconverged];
  iterations_.explicit_viscosity_steps += solve[kSolveExplicitViscosity];
  float last = 0, largest = 0;
  std::memcpy(&last, &solve[kSolveLastDensityError], sizeof last);
  std::memcpy(&largest, &solve[kSolveMaxDensityError], sizeof largest);
  iterations_.last_density_error = last;
  iterations_.max_density_error = std::max(iterations_.max_density_error, static_cast<double>(largest));
  const bool ran_out = solve[kSolveBudgetOverruns] > 0;
  iterations_.budget_overruns += solve[kSolveBudgetOverruns];
  divergence_budget_.observe(static_cast<int>(solve[kSolveMostDivergenceIts]), ran_out);
  density_budget_.observe(static_cast<int>(solve[kSolveMostDensityIts]), ran_out);
  viscosity_budget_.observe(static_cast<int>(solve[kSolveMostViscosityIts]), ran_out);
  for (std::uint32_t k : {kSolveDensityIts, kSolveDivergenceIts, kSolveViscosityIts, kSolveUnconverged,
                          kSolveExplicitViscosity, kSolveMaxDensityError, kSolveMostDensityIts, kSolveMostDivergenceIts,
                          kSolveMostViscosityIts, kSolveBudgetOverruns})
    solve[k] = 0;
  if (solve[kSolveListOverflow] > 0)
    throw std::runtime_error(m_.scene_name + ": a fluid particle has " + std::to_string(solve[kSolveListOverflow]) +
                             " fluid neighbours, more than the " + std::to_string(list_capacity(m_.params)) +
                             " its list holds (1.5 times the bulk at rest): the fluid is compressed far beyond rest "
                             "density at t = " + std::to_string(time_s_) + " s");
}

void VulkanSolver::note_recorded(VkCommandBuffer cb, const std::function<void()>& record) {
  const RecordedWork before = program_->recorded();
  record();
  work_of_[cb] += program_->recorded() - before;
}

VulkanSolver::~VulkanSolver() {
  if (!context_) return;
  vkDeviceWaitIdle(context_->device());
  for (auto& [n, cb] : recorded_) vkFreeCommandBuffers(context_->device(), context_->command_pool(), 1, &cb);
  for (VkCommandBuffer cb : {body_head_, body_tail_, body_tail_maxima_})
    if (cb) vkFreeCommandBuffers(context_->device(), context_->command_pool(), 1, &cb);
  if (queries_) vkDestroyQueryPool(context_->device(), queries_, nullptr);
  if (body_queries_) vkDestroyQueryPool(context_->device(), body_queries_, nullptr);
  if (fence_) vkDestroyFence(context_->device(), fence_, nullptr);
  program_.reset();
  b_.reset();
}

void VulkanSolver::check_device_limits() const {
  // The largest arrays: vec4 per particle (storage and texel views), the cell tables, and with
  // dfsph the solver's fields and neighbour lists (vec4 texels, per fluid particle).
  const VkPhysicalDeviceLimits& limits = context_->properties().limits;
  const std::uint64_t particles = std::max({fluid_count_, solid_count_, body_particle_count_});
  const std::uint64_t per_fluid = dfsph_ ? std::max<std::uint64_t>(14, list_capacity(m_.params)) : 1;
  const std::uint64_t vec4s = std::max<std::uint64_t>(particles, per_fluid * fluid_count_);
  const std::uint64_t largest_texels = std::max<std::uint64_t>(vec4s, cell_count_ + 1);
  const std::uint64_t largest_bytes = std::max<std::uint64_t>(16 * vec4s, 4ull * (body_start_base_ + cell_count_ + 1));
  // A listed neighbour's index is held as a float, exact up to 2^24.
  if (dfsph_ && fluid_count_ > (1u << 24))
    throw std::runtime_error("Vulkan backend: scene '" + m_.scene_name + "' has " + std::to_string(fluid_count_) +
                             " fluid particles, more than the 16,777,216 the incompressible solver's neighbour "
                             "lists index; use fewer particles or --backend cpu");
  if (largest_bytes > limits.maxStorageBufferRange || largest_texels > limits.maxTexelBufferElements)
    throw std::runtime_error("Vulkan backend: scene '" + m_.scene_name + "' needs arrays of " +
                             std::to_string(largest_bytes) + " bytes / " + std::to_string(largest_texels) +
                             " texels, beyond what " + context_->description().name + " allows (" +
                             std::to_string(limits.maxStorageBufferRange) + " bytes, " +
                             std::to_string(limits.maxTexelBufferElements) +
                             " texels); use fewer particles, a smaller domain, or --backend cpu");
}

void VulkanSolver::create_buffers() {
  Context& c = *context_;
  b_ = std::make_unique<Buffers>();
  Buffers& b = *b_;
  const VkDeviceSize nf = std::max<std::uint32_t>(fluid_count_, 1), ns = std::max<std::uint32_t>(solid_count_, 1);
  const VkDeviceSize nb = std::max<std::uint32_t>(body_particle_count_, 1), all = nf + nb;
  const VkDeviceSize bodies = std::max<std::size_t>(m_.bodies.size(), 1), chunks = std::max<std::uint32_t>(body_chunk_count_, 1);
  const VkDeviceSize vec4 = 16, u32 = 4;
  b.params = Buffer(c, sizeof(ParamsBlock), VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT, MemoryUse::host);
  b.reduce = Buffer(c, u32 * (4 + 2 * max_groups_), kStorage, MemoryUse::host);
  b.f_pos = Buffer(c, vec4 * nf, kStorage, MemoryUse::device);
  b.f_vel = Buffer(c, vec4 * nf, kStorage, MemoryUse::device);
  b.f_id = Buffer(c, u32 * nf, kStorage, MemoryUse::device);
  b.s_pos = Buffer(c, vec4 * nf, kTexel, MemoryUse::device);
  b.s_vel = Buffer(c, vec4 * nf, kTexel, MemoryUse::device);
  b.s_id = Buffer(c, u32 * nf, kStorage, MemoryUse::device);
  b.s_density = Buffer(c, vec4 * nf, kTexel, MemoryUse::device);
  b.s_acc = Buffer(c, vec4 * nf, kStorage, MemoryUse::device);
  b.cell_count = Buffer(c, u32 * 2 * cell_count_, kStorage, MemoryUse::device);
  b.cell_start = Buffer(c, u32 * (body_start_base_ + cell_count_ + 1), kTexel, MemoryUse::device);
  b.block_sums = Buffer(c, u32 * scan_blocks_, kStorage, MemoryUse::device);
  b.cell_of = Buffer(c, u32 * all, kStorage, MemoryUse::device);
  b.rank = Buffer(c, u32 * all, kStorage, MemoryUse::device);
  b.order = Buffer(c, u32 * all, kStorage, MemoryUse::device);
  b.w_a = Buffer(c, vec4 * ns, kTexel, MemoryUse::device);
  b.w_b = Buffer(c, vec4 * ns, kTexel, MemoryUse::device);
  b.w_c = Buffer(c, vec4 * ns, kTexel, MemoryUse::device);
  b.w_cell_start = Buffer(c, u32 * (cell_count_ + 1), kTexel, MemoryUse::device);
  b.b_pos = Buffer(c, vec4 * nb, kStorage, MemoryUse::device);
  b.b_vel = Buffer(c, vec4 * nb, kStorage, MemoryUse::device);
  b.b_rest = Buffer(c, vec4 * nb, kStorage, MemoryUse::device);
  b.b_force = Buffer(c, vec4 * nb, kStorage, MemoryUse::device);
  b.b_contact = Buffer(c, vec4 * nb, kStorage, MemoryUse::device);
  b.b_pressure = Buffer(c, u32 * nb, kStorage, MemoryUse::device);
  b.v_a = Buffer(c, vec4 * nb, kTexel, MemoryUse::device);
  b.v_b = Buffer(c, vec4 * nb, kTexel, MemoryUse::device);
  b.v_c = Buffer(c, vec4 * nb, kTexel, MemoryUse::device);
  b.body_state = Buffer(c, vec4 * 8 * bodies, kStorage, MemoryUse::host);
  b.body_chunks = Buffer(c, vec4 * chunks, kStorage, MemoryUse::device);
  b.body_partials = Buffer(c, vec4 * 4 * chunks, kStorage, MemoryUse::device);
  b.body_sums = Buffer(c, vec4 * 4 * bodies, kStorage, MemoryUse::host);
  // The incompressible solver's fields (one element each for wcsph: every binding is written).
  const VkDeviceSize nd = dfsph_ ? nf : 1;
  b.d_particle = Buffer(c, vec4 * 14 * nd, kTexel, MemoryUse::device);
  b.t_d_particle = TexelView(c, b.d_particle, kVec4);
  const VkDeviceSize listed = dfsph_ ? nf * list_capacity(m_.params) : 1;
  b.d_list = Buffer(c, vec4 * listed, kTexel, MemoryUse::device);
  b.t_d_list = TexelView(c, b.d_list, kVec4);
  b.d_kappa = Buffer(c, u32 * nd, kTexel, MemoryUse::device);
  b.t_d_kappa = TexelView(c, b.d_kappa, VK_FORMAT_R32_SFLOAT);
  b.d_solve = Buffer(c, u32 * (kSolvePartials + 4 * groups(static_cast<std::uint32_t>(nd), 64)),
                     kStorage | VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT, MemoryUse::host);
  const std::vector<float> walls = dfsph_ ? wall_map_words(domain_wall_map(m_.params)) : std::vector<float>(20, 0.0f);
  b.d_walls = Buffer(c, 4 * walls.size(), kTexel, MemoryUse::device);
  b.d_walls.upload(walls.data(), 4 * walls.size());
  b.t_d_walls = TexelView(c, b.d_walls, VK_FORMAT_R32_SFLOAT);

  b.t_s_pos = TexelView(c, b.s_pos, kVec4);
  b.t_s_vel = TexelView(c, b.s_vel, kVec4);
  b.t_s_density = TexelView(c, b.s_density, kVec4);
  b.t_cell_start = TexelView(c, b.cell_start, kUint, 0, u32 * (cell_count_ + 1));
  b.t_v_cell_start = TexelView(c, b.cell_start, kUint, u32 * body_start_base_, u32 * (cell_count_ + 1));
  b.t_v_a = TexelView(c, b.v_a, kVec4);
  b.t_v_b = TexelView(c, b.v_b, kVec4);
  b.t_v_c = TexelView(c, b.v_c, kVec4);
  b.t_w_a = TexelView(c, b.w_a, kVec4);
  b.t_w_b = TexelView(c, b.w_b, kVec4);
  b.t_w_c = TexelView(c, b.w_c, kVec4);
  b.t_w_cell_start = TexelView(c, b.w_cell_start, kUint);

  ComputeProgram& p = *program_;
  p.bind_uniform(BINDING_PARAMS, b.params);
  p.bind_storage(BINDING_F_POS, b.f_pos);
  p.bind_storage(BINDING_F_VEL, b.f_vel);
  p.bind_storage(BINDING_F_ID, b.f_id);
  p.bind_storage(BINDING_S_POS, b.s_pos);
  p.bind_storage(BINDING_S_VEL, b.s_vel);
  p.bind_storage(BINDING_S_ID, b.s_id);
  p.bind_storage(BINDING_S_DENSITY, b.s_density);
  p.bind_storage(BINDING_S_ACC, b.s_acc);
  p.bind_storage(BINDING_CELL_COUNT, b.cell_count);
  p.bind_storage(BINDING_CELL_START, b.cell_start);
  p.bind_storage(BINDING_BLOCK_SUMS, b.block_sums);
  p.bind_storage(BINDING_CELL_OF, b.cell_of);
  p.bind_storage(BINDING_RANK, b.rank);
  p.bind_storage(BINDING_ORDER, b.order);
  p.bind_storage(BINDING_REDUCE, b.reduce);
  p.bind_texel(BINDING_T_S_POS, b.t_s_pos);
  p.bind_texel(BINDING_T_S_VEL, b.t_s_vel);
  p.bind_texel(BINDING_T_S_DENSITY, b.t_s_density);
  p.bind_texel(BINDING_T_CELL_START, b.t_cell_start);
  p.bind_texel(BINDING_T_W_A, b.t_w_a);
  p.bind_texel(BINDING_T_W_B, b.t_w_b);
  p.bind_texel(BINDING_T_W_C, b.t_w_c);
  p.bind_texel(BINDING_T_W_CELL_START, b.t_w_cell_start);
  p.bind_storage(BINDING_B_POS, b.b_pos);
  p.bind_storage(BINDING_B_VEL, b.b_vel);
  p.bind_storage(BINDING_B_REST, b.b_rest);
  p.bind_storage(BINDING_B_FORCE, b.b_force);
  p.bind_storage(BINDING_B_CONTACT, b.b_contact);
  p.bind_storage(BINDING_B_PRESSURE, b.b_pressure);
  p.bind_storage(BINDING_V_A, b.v_a);
  p.bind_storage(BINDING_V_B, b.v_b);
  p.bind_storage(BINDING_V_C, b.v_c);
  p.bind_storage(BINDING_BODY_STATE, b.body_state);
  p.bind_storage(BINDING_BODY_CHUNKS, b.body_chunks);
  p.bind_storage(BINDING_BODY_PARTIALS, b.body_partials);
  p.bind_storage(BINDING_BODY_SUMS, b.body_sums);
  p.bind_texel(BINDING_T_V_A, b.t_v_a);
  p.bind_texel(BINDING_T_V_B, b.t_v_b);
  p.bind_texel(BINDING_T_V_C, b.t_v_c);
  p.bind_texel(BINDING_T_V_CELL_START, b.t_v_cell_start);
  p.bind_storage(BINDING_D_PARTICLE, b.d_particle);
  p.bind_storage(BINDING_D_SOLVE, b.d_solve);
  p.bind_texel(BINDING_T_D_WALLS, b.t_d_walls);
  p.bind_texel(BINDING_T_D_PARTICLE, b.t_d_particle);
  p.bind_storage(BINDING_D_LIST, b.d_list);
  p.bind_texel(BINDING_T_D_LIST, b.t_d_list);
  p.bind_storage(BINDING_D_KAPPA, b.d_kappa);
  p.bind_texel(BINDING_T_D_KAPPA, b.t_d_kappa);
  p.commit_bindings();
}

void VulkanSolver::upload_model() {
  Buffers& b = *b_;
  const FluidParticles& f = m_.fluid;
  const std::size_t nf = f.size();
  b.f_pos.upload(pack4(nf, f.x.data(), f.y.data(), f.z.data(), f.viscosity.data()).data(), 16 * nf);
  b.f_vel.upload(pack4(nf, f.vx.data(), f.vy.data(), f.vz.data(), nullptr).data(), 16 * nf);
  b.f_id.upload(f.id.data(), 4 * nf);
  // Accelerations of the initial state enter the first CFL bound; S_ACC holds them.
  b.s_acc.upload(pack4(nf, f.ax.data(), f.ay.data(), f.az.data(), nullptr).data(), 16 * nf);
  b.s_density.upload(pack4(nf, f.density.data(), f.pressure.data(), f.volume.data(), f.volume_correction.data()).data(),
                     16 * nf);
  if (dfsph_) {
    // The solver's per-particle memory in F order, fields 12 and 13 after the sorted ones
    // (dfsph_common.glsl): warm starts of both solves, the last viscous change.
    std::vector<float> warm(8 * nf, 0.0f);
    for (std::size_t i = 0; i < nf; ++i) {
      warm[4 * i] = f.density_stiffness_dt2[i], warm[4 * i + 1] = f.divergence_stiffness_dt[i];
      float* dv = &warm[4 * (nf + i)];
      dv[0] = f.viscous_dvx[i], dv[1] = f.viscous_dvy[i], dv[2] = f.viscous_dvz[i];
    }
    b.d_particle.upload(warm.data(), 4 * warm.size(), 16 * 12 * nf);
    const std::vector<std::uint32_t> state(b.d_solve.size() / 4, 0);
    b.d_solve.upload(state.data(), b.d_solve.size());
  }
  const std::vector<std::uint32_t> zeros(std::max<std::size_t>(body_start_base_ + cell_count_ + 1, 4 + 2 * max_groups_), 0);
  b.reduce.upload(zeros.data(), 4 * (4 + 2 * max_groups_));  // the clamp counter starts at zero
  b.cell_count.upload(zeros.data(), 4 * 2 * cell_count_);
  b.cell_start.upload(zeros.data(), 4 * zeros.size());

  const SortedSolids& s = fluid_statics();
  const std::size_t ns = s.size();
  std::vector<float> body_index(ns);
  for (std::size_t i = 0; i < ns; ++i) body_index[i] = static_cast<float>(s.body[i]);
  b.w_a.upload(pack4(ns, s.x.data(), s.y.data(), s.z.data(), s.volume.data()).data(), 16 * ns);
  b.w_b.upload(pack4(ns, s.vx.data(), s.vy.data(), s.vz.data(), s.viscosity.data()).data(), 16 * ns);
  b.w_c.upload(pack4(ns, s.no_slip.data(), s.pressure.data(), body_index.data(), nullptr).data(), 16 * ns);
  if (ns > 0) {
    if (s.cell_start.size() != cell_count_ + 1)
      throw std::logic_error("Vulkan backend: static solids were sorted on a different grid");
    b.w_cell_start.upload(s.cell_start.data(), 4 * s.cell_start.size());
  } else {
    b.w_cell_start.upload(zeros.data(), 4 * std::min<std::size_t>(zeros.size(), cell_count_ + 1));
  }

  // Dynamic body particles, grouped per body, and the reduction chunks: at most 256 particles
  // of one body each, so a chunk's workgroup sums one body.
  const BodyParticles& bp = m_.body_particles;
  const std::size_t nb = bp.size();
  if (nb == 0) return;
  std::vector<float> body_of(nb);
  for (std::size_t i = 0; i < nb; ++i) body_of[i] = static_cast<float>(bp.body[i]);
  b.b_pos.upload(pack4(nb, bp.x.data(), bp.y.data(), bp.z.data(), bp.volume.data()).data(), 16 * nb);
  b.b_vel.upload(pack4(nb, bp.vx.data(), bp.vy.data(), bp.vz.data(), bp.viscosity.data()).data(), 16 * nb);
  b.b_rest.upload(pack4(nb, bp.rx.data(), bp.ry.data(), bp.rz.data(), body_of.data()).data(), 16 * nb);
  b.b_pressure.upload(bp.pressure.data(), 4 * nb);
  std::vector<std::uint32_t> chunks;
  for (std::size_t body = 0; body < m_.bodies.size(); ++body) {
    const RigidBody& rb = m_.bodies[body];
    if (!rb.dynamic) continue;
    for (std::uint32_t first = 0; first < rb.particle_count; first += 256)
      chunks.insert(chunks.end(), {static_cast<std::uint32_t>(body), rb.first_particle + first,
                                   std::min<std::uint32_t>(256, rb.particle_count - first), 0});
  }
  b.body_chunks.upload(chunks.data(), 4 * chunks.size());
}

void VulkanSolver::write_body_states() {
  // Per body 8 vec4: centre of mass, the rows of R, linear and angular velocity (float: the
  // particles are float; the state itself stays double on the host).
  std::vector<float> state(32 * m_.bodies.size(), 0.0f);
  for (std::size_t b = 0; b < m_.bodies.size(); ++b) {
    const RigidBody& body = m_.bodies[b];
    float* s = &state[32 * b];
    const Mat3 r = body.rotation();
    const Vec3 rows[6] = {body.position, {r.m[0][0], r.m[0][1], r.m[0][2]}, {r.m[1][0], r.m[1][1], r.m[1][2]},
                          {r.m[2][0], r.m[2][1], r.m[2][2]}, body.linear_velocity, body.angular_velocity};
    for (int k = 0; k < 6; ++k)
      s[4 * k] = static_cast<float>(rows[k].x), s[4 * k + 1] = static_cast<float>(rows[k].y),
      s[4 * k + 2] = static_cast<float>(rows[k].z);
  }
  if (!state.empty()) b_->body_state.upload(state.data(), 4 * state.size());
}

void VulkanSolver::integrate_bodies(double dt) {
  // Algorithm 2, lines 6-9 on the host, in double, with CpuSolver's own integrate_body.
  const float* sums = static_cast<const float*>(b_->body_sums.mapped());
  for (std::size_t b = 0; b < m_.bodies.size(); ++b) {
    RigidBody& body = m_.bodies[b];
    if (!body.dynamic) continue;
    const float* s = sums + 16 * b;
    body.fluid_force = {s[0], s[1], s[2]};
    body.fluid_torque = {s[4], s[5], s[6]};
    body.contact_force = {s[8], s[9], s[10]};
    body.contact_torque = {s[12], s[13], s[14]};
    integrate_body(body, couplings_of_body_[b], devices_, m_.params.gravity_m_s2, dt);
  }
  write_body_states();
}

void VulkanSolver::write_params(float dt) {
  const SimulationParams& p = m_.params;
  ParamsBlock block{};
  block.kernel[0] = p.kernel.h, block.kernel[1] = p.kernel.h2, block.kernel[2] = p.kernel.poly6;
  block.kernel[3] = p.kernel.spiky_grad;
  block.material[0] = p.kernel.visc_lap, block.material[1] = p.fluid_particle_mass_kg;
  block.material[2] = p.rest_density_kg_m3, block.material[3] = p.stiffness;
  block.gravity_dt[0] = static_cast<float>(p.gravity_m_s2.x), block.gravity_dt[1] = static_cast<float>(p.gravity_m_s2.y);
  block.gravity_dt[2] = static_cast<float>(p.gravity_m_s2.z), block.gravity_dt[3] = dt;
  for (int a = 0; a < 3; ++a) {
    block.clamp_lo[a] = p.clamp_lo[a], block.clamp_hi[a] = p.clamp_hi[a];
    block.grid_origin[a] = p.grid.origin[a];
    block.grid_dims[a] = p.grid.dims[a];
  }
  block.grid_origin[3] = p.grid.cell_size;
  block.grid_dims[3] = static_cast<std::int32_t>(cell_count_);
  block.counts[0] = fluid_count_, block.counts[1] = solid_count_, block.counts[2] = body_particle_count_;
  std::uint32_t dynamic_bodies = 0;
  for (const RigidBody& body : m_.bodies) dynamic_bodies += body.dynamic ? 1 : 0;
  block.counts[3] = dynamic_bodies;
  block.corrections[0] = kGradientCorrectionMin, block.corrections[1] = kGradientCorrectionMax;
  block.corrections[2] = p.contact_damping_pa_s;
  const IncompressibleParams& ip = p.incompressible;
  block.dfsph_kernel[0] = ip.kernel.h2, block.dfsph_kernel[1] = ip.kernel.inv_h;
  block.dfsph_kernel[2] = ip.kernel.w_scale, block.dfsph_kernel[3] = ip.kernel.grad_scale;
  block.dfsph_a[0] = p.fluid_particle_mass_kg / p.rest_density_kg_m3;
  block.dfsph_a[1] = ip.max_density_error, block.dfsph_a[2] = ip.max_divergence_error, block.dfsph_a[3] = ip.xsph_fraction;
  block.dfsph_b[0] = static_cast<float>(ip.min_divergence_neighbours), block.dfsph_b[1] = p.fluid_viscosity_pa_s;
  block.dfsph_b[2] = 0.01f * ip.kernel.h2, block.dfsph_b[3] = velocity_kept_;
  block.dfsph_c[0] = ip.min_density_iterations, block.dfsph_c[1] = ip.min_divergence_iterations;
  block.dfsph_c[2] = ip.max_iterations, block.dfsph_c[3] = static_cast<std::int32_t>(groups(fluid_count_, 64));
  block.dfsph_d[0] = static_cast<std::int32_t>(list_capacity(p));
  b_->params.upload(&block, sizeof block);
}

void VulkanSolver::set_device_state(std::size_t device, const DeviceState& state) {
  if (device >= devices_.size())
    throw std::out_of_range("device index " + std::to_string(device) + " out of range (" +
                            std::to_string(devices_.size()) + " devices in the scene)");
  devices_[device] = state;
}

double VulkanSolver::stable_time_step() const {
  // CpuSolver::stable_time_step, term by term, with the maxima from the device.
  const SimulationParams& p = m_.params;
  if (p.fixed_dt_s > 0) return p.fixed_dt_s;
  if (dfsph_) return incompressible_time_step(p, max_speed2_, false);  // no bodies on the device with dfsph
  const double h = p.kernel.h;
  double dt = p.cfl * h / (p.speed_of_sound_m_s + std::sqrt(static_cast<double>(max_speed2_)));
  double mu_max = p.fluid_viscosity_pa_s;
  for (const RigidBody& b : m_.bodies) mu_max = std::max(mu_max, b.viscosity_pa_s);
  if (mu_max > 0) dt = std::min(dt, 0.125 * h * h * p.rest_density_kg_m3 / mu_max);
  if (max_accel2_ > 0) dt = std::min(dt, 0.25 * std::sqrt(h / std::sqrt(static_cast<double>(max_accel2_))));
  return std::min(dt, p.max_dt_s);
}

int VulkanSolver::advance(double duration_s, const std::function<void(double)>& before_substep) {
  if (duration_s <= 0) return 0;
  const double dt_max = stable_time_step();
  const int substeps = std::max(1, static_cast<int>(std::ceil(duration_s / dt_max - 1e-9)));
  const double dt = duration_s / substeps;
  if (!before_substep) {
    step_many(dt, substeps);
    return substeps;
  }
  const double t0 = time_s_;
  for (int i = 0; i < substeps; ++i) {
    before_substep(t0 + i * dt);
    step_many(dt, 1);
  }
  return substeps;
}

void VulkanSolver::step_many(double dt, int substeps) {
  if (substeps <= 0) return;
  if (body_particle_count_ > 0) {
    std::uint32_t* reduce = static_cast<std::uint32_t*>(b_->reduce.mapped());
    reduce[0] = 0;  // clamped-particle counter of these substeps
    for (int s = 0; s < substeps; ++s) step_with_bodies(dt, s + 1 == substeps);
    read_results(0);
    return;
  }
  write_params(static_cast<float>(dt));
  std::uint32_t* reduce = static_cast<std::uint32_t*>(b_->reduce.mapped());
  reduce[0] = 0;  // clamped-particle counter of this submission
  VkCommandBuffer cb = command_buffer_for(substeps);
  submit_and_wait(cb);
  read_results(substeps);
  for (int s = 0; s < substeps; ++s) time_s_ += dt;
  steps_ += static_cast<std::uint64_t>(substeps);
}

void VulkanSolver::step_with_bodies(double dt, bool last_of_frame) {
  write_params(static_cast<float>(dt));
  submit_and_wait(body_head_);
  integrate_bodies(dt);
  submit_and_wait(last_of_frame ? body_tail_maxima_ : body_tail_);
  if (body_queries_) {
    std::uint64_t ticks[kBodyStepQueries];
    check(vkGetQueryPoolResults(context_->device(), body_queries_, 0, kBodyStepQueries, sizeof ticks, ticks,
                                sizeof(std::uint64_t), VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT),
          "vkGetQueryPoolResults");
    const double s_per_tick = context_->timestamp_period_ns() * 1e-9;
    auto span = [&](int a, int b) { return static_cast<double>(ticks[b] - ticks[a]) * s_per_tick; };
    pass_times_.sort_s += span(0, 1);
    pass_times_.density_s += span(1, 2);
    pass_times_.forces_s += span(2, 3);
    pass_times_.bodies_s += span(3, 4) + span(5, 6);
    pass_times_.integration_s += span(6, 7);
    pass_times_.reductions_s += span(7, 8);
    pass_times_.steps += 1;
  }
  time_s_ += dt;
  ++steps_;
}

VkCommandBuffer VulkanSolver::allocate_command_buffer() {
  VkCommandBufferAllocateInfo alloc{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
  alloc.commandPool = context_->command_pool();
  alloc.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
  alloc.commandBufferCount = 1;
  VkCommandBuffer cb = VK_NULL_HANDLE;
  check(vkAllocateCommandBuffers(context_->device(), &alloc, &cb), "vkAllocateCommandBuffers");
  return cb;
}

VulkanSolver::RecordingKey VulkanSolver::recording_key(int substeps) const {
  if (!dfsph_ || substeps == 0) return {substeps, 0, 0, 0};
  return {substeps, divergence_budget_.budget(), density_budget_.budget(), viscosity_budget_.budget()};
}

VkCommandBuffer VulkanSolver::command_buffer_for(int substeps) {
  const RecordingKey key = recording_key(substeps);
  auto found = recorded_.find(key);
  if (found != recorded_.end()) return found->second;
  // A handful of substep counts occur in a run (the CFL bound moves slowly); keep them all
  // recorded, but bound the cache.
  if (recorded_.size() > 16) {
    for (auto& [n, cb] : recorded_)
      if (n[0] != 0) {
        work_of_.erase(cb);
        vkFreeCommandBuffers(context_->device(), context_->command_pool(), 1, &cb);
      }
    std::erase_if(recorded_, [](const auto& e) { return e.first[0] != 0; });
  }
  VkCommandBufferAllocateInfo alloc{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
  alloc.commandPool = context_->command_pool();
  alloc.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
  alloc.commandBufferCount = 1;
  VkCommandBuffer cb = VK_NULL_HANDLE;
  check(vkAllocateCommandBuffers(context_->device(), &alloc, &cb), "vkAllocateCommandBuffers");
  note_recorded(cb, [&] { record_steps(cb, substeps); });
  recorded_[key] = cb;
  return cb;
}

void VulkanSolver::submit_and_wait(VkCommandBuffer cb) {
  VkSubmitInfo submit{VK_STRUCTURE_TYPE_SUBMIT_INFO};
  submit.commandBufferCount = 1;
  submit.pCommandBuffers = &cb;
  check(vkQueueSubmit(context_->queue(), 1, &submit, fence_), "vkQueueSubmit");
  const auto recorded = work_of_.find(cb);
  if (recorded != work_of_.end()) {
    work_.dispatches += recorded->second.dispatches;
    work_.indirect_dispatches += recorded->second.indirect_dispatches;
    work_.barriers += recorded->second.barriers;
  }
  ++work_.submissions;
  ++work_.host_waits;
  const VkResult r = vkWaitForFences(context_->device(), 1, &fence_, VK_TRUE, UINT64_MAX);
  vkResetFences(context_->device(), 1, &fence_);
  check(r, "vkWaitForFences");
}

void VulkanSolver::read_results(int substeps) {
  const std::uint32_t* reduce = static_cast<const std::uint32_t*>(b_->reduce.mapped());
  clamped_ += reduce[0];  // cumulative, as CpuSolver::clamped_particle_count
  std::memcpy(&max_speed2_, &reduce[1], sizeof(float));
  std::memcpy(&max_accel2_, &reduce[2], sizeof(float));
  read_solver_counters();
  if (queries_ && substeps > 0 && timed(substeps)) {
    const std::uint32_t n = queries_per_step_ * static_cast<std::uint32_t>(substeps) + 2;
    std::vector<std::uint64_t> ticks(n);
    check(vkGetQueryPoolResults(context_->device(), queries_, 0, n, n * sizeof(std::uint64_t), ticks.data(),
                                sizeof(std::uint64_t), VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT),
          "vkGetQueryPoolResults");
    const double s_per_tick = context_->timestamp_period_ns() * 1e-9;
    auto span = [&](std::uint32_t a, std::uint32_t b) { return static_cast<double>(ticks[b] - ticks[a]) * s_per_tick; };
    for (int s = 0; s < substeps && dfsph_; ++s) {
      const std::uint32_t q = static_cast<std::uint32_t>(s) * queries_per_step_;
      pass_times_.sort_s += span(q, q + 1);
      pass_times_.density_s += span(q + 1, q + 2);
      pass_times_.pressure_s += span(q + 2, q + 3) + span(q + 4, q + 5);
      pass_times_.forces_s += span(q + 3, q + 4);
      pass_times_.integration_s += span(q + 5, q + 6);
    }
    for (int s = 0; s < substeps && !dfsph_; ++s) {
      const std::uint32_t q = static_cast<std::uint32_t>(s) * queries_per_step_;
      pass_times_.sort_s += span(q, q + 1);
      pass_times_.density_s += span(q + 1, q + 2);
      pass_times_.forces_s += span(q + 2, q + 3);
      pass_times_.integration_s += span(q + 3, q + 4);
    }
    pass_times_.reductions_s += span(n - 2, n - 1);
    pass_times_.steps += static_cast<std::uint64_t>(substeps);
  }
}

PhaseTimes VulkanSolver::phase_times() const {
  PhaseTimes t;
  t.neighbour_search_s = pass_times_.sort_s;
  t.density_s = pass_times_.density_s;
  t.forces_s = pass_times_.forces_s;
  t.pressure_s = pass_times_.pressure_s;
  t.bodies_s = pass_times_.bodies_s;
  t.integration_s = pass_times_.integration_s + pass_times_.reductions_s;
  return t;
}

void VulkanSolver::sync_particles() {
  Buffers& b = *b_;
  const std::size_t n = fluid_count_;
  std::vector<float> pos(4 * n), vel(4 * n), acc(4 * n), density(4 * n);
  b.f_pos.download(pos.data(), 16 * n);
  b.f_vel.download(vel.data(), 16 * n);
  b.s_acc.download(acc.data(), 16 * n);
  b.s_density.download(density.data(), 16 * n);
  FluidParticles& f = m_.fluid;
  b.f_id.download(f.id.data(), 4 * n);
  for (std::size_t i = 0; i < n; ++i) {
    f.x[i] = pos[4 * i], f.y[i] = pos[4 * i + 1], f.z[i] = pos[4 * i + 2], f.viscosity[i] = pos[4 * i + 3];
    f.vx[i] = vel[4 * i], f.vy[i] = vel[4 * i + 1], f.vz[i] = vel[4 * i + 2];
    f.ax[i] = acc[4 * i], f.ay[i] = acc[4 * i + 1], f.az[i] = acc[4 * i + 2];
    f.density[i] = density[4 * i], f.pressure[i] = density[4 * i + 1], f.volume[i] = density[4 * i + 2];
    f.volume_correction[i] = density[4 * i + 3];
  }
  BodyParticles& bp = m_.body_particles;
  const std::size_t nb = body_particle_count_;
  if (nb == 0) return;
  std::vector<float> bpos(4 * nb), bvel(4 * nb), force(4 * nb), contact(4 * nb);
  b.b_pos.download(bpos.data(), 16 * nb);
  b.b_vel.download(bvel.data(), 16 * nb);
  b.b_force.download(force.data(), 16 * nb);
  b.b_contact.download(contact.data(), 16 * nb);
  b.b_pressure.download(bp.pressure.data(), 4 * nb);
  for (std::size_t i = 0; i < nb; ++i) {
    bp.x[i] = bpos[4 * i], bp.y[i] = bpos[4 * i + 1], bp.z[i] = bpos[4 * i + 2];
    bp.vx[i] = bvel[4 * i], bp.vy[i] = bvel[4 * i + 1], bp.vz[i] = bvel[4 * i + 2];
    bp.fx[i] = force[4 * i], bp.fy[i] = force[4 * i + 1], bp.fz[i] = force[4 * i + 2];
    bp.cx[i] = contact[4 * i], bp.cy[i] = contact[4 * i + 1], bp.cz[i] = contact[4 * i + 2];
  }
}

void VulkanSolver::check_finite() {
  sync_particles();
  check_finite_state(m_, time_s_);
}

}  // namespace hapfluid::sim::vulkan
