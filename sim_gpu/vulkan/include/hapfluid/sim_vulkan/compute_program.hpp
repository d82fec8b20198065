// The compute passes of the backend and the one descriptor set they share: a single set layout
// (the binding table of shaders/bindings.glsl), one pipeline layout with a 16-byte push-constant
// block, one pipeline per pass. Created once per backend; descriptors written once after the
// buffers exist (every binding is written: lavapipe 22.3 crashes on unwritten bindings).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "hapfluid/sim_vulkan/base.hpp"

namespace hapfluid::sim::vulkan {

// SPIR-V of one pass, compiled from shaders/<name>.comp at build time.
struct ShaderModuleCode {
  const char* name;
  const std::uint32_t* words;
  std::size_t bytes;
};
// Every pass built into the library.
const std::vector<ShaderModuleCode>& builtin_shaders();

enum class Pass : int {
  hash_fluid, hash_bodies, scan_local, scan_blocks, scan_add, scatter, order_cells, gather_fluid,
  gather_bodies, density_cells, body_contact_pressure, fluid_forces_cells, body_forces, body_sums, body_sums_final,
  body_update, integrate_fluid, adopt_sorted, max_speed, max_speed_final,
  // The incompressible solver (dfsph_*.comp).
  dfsph_gather, dfsph_density, dfsph_rate, dfsph_check, dfsph_apply, dfsph_solve_end, dfsph_forces, dfsph_predict,
  dfsph_visc_rhs, dfsph_visc_check, dfsph_cg_apply, dfsph_cg_alpha, dfsph_cg_update, dfsph_cg_check,
  dfsph_cg_direction, dfsph_visc_end, dfsph_integrate, dfsph_adopt, count
};
const char* pass_shader_name(Pass pass);

struct PushConstants {
  std::uint32_t a = 0, b = 0, c = 0, d = 0;
};

// The memory barriers between recorded passes.
enum class Barrier {
  compute,               // a pass's writes before the next pass's reads and writes
  compute_and_indirect,  // the same, and before the group counts of the indirect dispatches that follow
  host_to_compute,       // host writes (parameters, counters) before the first pass
  compute_to_host,       // the last pass's writes, for the host after the fence
};

// Commands recorded so far by one program (summed over every command buffer it recorded into).
struct RecordedWork {
  std::uint64_t dispatches = 0, indirect_dispatches = 0, barriers = 0;
  RecordedWork& operator+=(const RecordedWork& o) {
    dispatches += o.dispatches, indirect_dispatches += o.indirect_dispatches, barriers += o.barriers;
    return *this;
  }
  RecordedWork operator-(const RecordedWork& o) const {
    return {dispatches - o.dispatches, indirect_dispatches - o.indirect_dispatches, barriers - o.barriers};
  }
};

class ComputeProgram {
 public:
  explicit ComputeProgram(Context& context);
  ~ComputeProgram();
  ComputeProgram(const ComputeProgram&) = delete;
  ComputeProgram& operator=(const ComputeProgram&) = delete;

  void bind_uniform(std::uint32_t binding, const Buffer& buffer);
  void bind_storage(std::uint32_t binding, const Buffer& buffer);
  void bind_texel(std::uint32_t binding, const TexelView& view);
  // Checks every binding was written, then writes the set.
  void commit_bindings();

  // Records: bind pipeline and set, push constants, dispatch ceil(threads / local size) groups.
  void dispatch(VkCommandBuffer cb, Pass pass, std::uint32_t groups, const PushConstants& push = {}) const;
  // The same with the group counts read by the device from `args` at `offset` (three uints)
  // when the dispatch runs: a count an earlier pass of the submission wrote, zero to skip.
  void dispatch_indirect(VkCommandBuffer cb, Pass pass, const Buffer& args, VkDeviceSize offset,
                         const PushConstants& push = {}) const;
  void barrier(VkCommandBuffer cb, Barrier kind) const;
  const RecordedWork& recorded() const { return recorded_; }

 private:
  Context& context_;
  VkDescriptorSetLayout set_layout_ = VK_NULL_HANDLE;
  VkPipelineLayout layout_ = VK_NULL_HANDLE;
  VkDescriptorPool pool_ = VK_NULL_HANDLE;
  VkDescriptorSet set_ = VK_NULL_HANDLE;
  std::vector<VkPipeline> pipelines_;
  std::vector<VkDescriptorBufferInfo> buffer_infos_;
  std::vector<VkBufferView> texel_views_;
  std::vector<bool> written_;
  mutable RecordedWork recorded_;
};

}  // namespace hapfluid::sim::vulkan
