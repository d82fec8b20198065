#include "hapfluid/sim_vulkan/compute_program.hpp"

#include <stdexcept>
#include <string>

#include "../shaders/bindings.glsl"

namespace hapfluid::sim::vulkan {
namespace {

VkDescriptorType binding_type(std::uint32_t binding) {
  if (binding == BINDING_PARAMS) return VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER;
  switch (binding) {
    case BINDING_T_S_POS: case BINDING_T_S_VEL: case BINDING_T_S_DENSITY: case BINDING_T_CELL_START:
    case BINDING_T_W_A: case BINDING_T_W_B: case BINDING_T_W_C: case BINDING_T_W_CELL_START:
    case BINDING_T_V_A: case BINDING_T_V_B: case BINDING_T_V_C: case BINDING_T_V_CELL_START: case BINDING_T_D_WALLS: case BINDING_T_D_PARTICLE:
    case BINDING_T_D_LIST: case BINDING_T_D_KAPPA:
      return VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER;
    default:
      return VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
  }
}

constexpr const char* kPassShaders[] = {
    "hash", "hash_bodies", "scan_local", "scan_blocks", "scan_add", "scatter", "order_cells", "gather_fluid",
    "gather_bodies", "density_cells", "body_contact_pressure", "fluid_forces_cells", "body_forces", "body_sums",
    "body_sums_final",
    "body_update", "integrate_fluid", "adopt_sorted", "max_speed", "max_speed_final", "dfsph_gather", "dfsph_density",
    "dfsph_rate", "dfsph_check", "dfsph_apply", "dfsph_solve_end", "dfsph_forces", "dfsph_predict", "dfsph_visc_rhs",
    "dfsph_visc_check", "dfsph_cg_apply", "dfsph_cg_alpha", "dfsph_cg_update", "dfsph_cg_check", "dfsph_cg_direction",
    "dfsph_visc_end", "dfsph_integrate", "dfsph_adopt"};
static_assert(sizeof(kPassShaders) / sizeof(kPassShaders[0]) == static_cast<int>(Pass::count));

}  // namespace

const char* pass_shader_name(Pass pass) { return kPassShaders[static_cast<int>(pass)]; }

ComputeProgram::ComputeProgram(Context& context) : context_(context) {
  VkDevice device = context.device();
  std::vector<VkDescriptorSetLayoutBinding> bindings(BINDING_COUNT);
  std::uint32_t storage = 0, texel = 0;
  for (std::uint32_t b = 0; b < BINDING_COUNT; ++b) {
    bindings[b] = {b, binding_type(b), 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr};
    (binding_type(b) == VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER ? texel : storage) += 1;
  }
  VkDescriptorSetLayoutCreateInfo set_info{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
  set_info.bindingCount = BINDING_COUNT;
  set_info.pBindings = bindings.data();
  check(vkCreateDescriptorSetLayout(device, &set_info, nullptr, &set_layout_), "vkCreateDescriptorSetLayout");

  const VkPushConstantRange push{VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(PushConstants)};
  VkPipelineLayoutCreateInfo layout_info{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
  layout_info.setLayoutCount = 1;
  layout_info.pSetLayouts = &set_layout_;
  layout_info.pushConstantRangeCount = 1;
  layout_info.pPushConstantRanges = &push;
  check(vkCreatePipelineLayout(device, &layout_info, nullptr, &layout_), "vkCreatePipelineLayout");

  const VkDescriptorPoolSize sizes[] = {{VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, 1},
                                        {VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, storage},
                                        {VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER, texel}};
  VkDescriptorPoolCreateInfo pool_info{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
  pool_info.maxSets = 1;
  pool_info.poolSizeCount = 3;
  pool_info.pPoolSizes = sizes;
  check(vkCreateDescriptorPool(device, &pool_info, nullptr, &pool_), "vkCreateDescriptorPool");
  VkDescriptorSetAllocateInfo alloc{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
  alloc.descriptorPool = pool_;
  alloc.descriptorSetCount = 1;
  alloc.pSetLayouts = &set_layout_;
  check(vkAllocateDescriptorSets(device, &alloc, &set_), "vkAllocateDescriptorSets");
  buffer_infos_.resize(BINDING_COUNT);
  texel_views_.resize(BINDING_COUNT, VK_NULL_HANDLE);
  written_.assign(BINDING_COUNT, false);

  for (int p = 0; p < static_cast<int>(Pass::count); ++p) {
    const std::string name = kPassShaders[p];
    const ShaderModuleCode* code = nullptr;
    for (const auto& s : builtin_shaders())
      if (name == s.name) code = &s;
    if (!code) throw VulkanError("Vulkan backend: no SPIR-V for pass '" + name + "' was built");
    VkShaderModuleCreateInfo module_info{VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
    module_info.codeSize = code->bytes;
    module_info.pCode = code->words;
    VkShaderModule module = VK_NULL_HANDLE;
    check(vkCreateShaderModule(device, &module_info, nullptr, &module), ("vkCreateShaderModule " + name).c_str());
    VkComputePipelineCreateInfo info{VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO};
    info.stage = {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO};
    info.stage.stage = VK_SHADER_STAGE_COMPUTE_BIT;
    info.stage.module = module;
    info.stage.pName = "main";
    info.layout = layout_;
    VkPipeline pipeline = VK_NULL_HANDLE;
    const VkResult r = vkCreateComputePipelines(device, VK_NULL_HANDLE, 1, &info, nullptr, &pipeline);
    vkDestroyShaderModule(device, module, nullptr);
    check(r, ("vkCreateComputePipelines " + name).c_str());
    pipelines_.push_back(pipeline);
  }
}

ComputeProgram::~ComputeProgram() {
  VkDevice device = context_.device();
  for (VkPipeline p : pipelines_) vkDestroyPipeline(device, p, nullptr);
  if (pool_) vkDestroyDescriptorPool(device, pool_, nullptr);
  if (layout_) vkDestroyPipelineLayout(device, layout_, nullptr);
  if (set_layout_) vkDestroyDescriptorSetLayout(device, set_layout_, nullptr);
}

void ComputeProgram::bind_uniform(std::uint32_t binding, const Buffer& buffer) {
  if (binding_type(binding) != VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER) throw std::logic_error("binding is not a uniform buffer");
  buffer_infos_[binding] = {buffer.handle(), 0, VK_WHOLE_SIZE};
  written_[binding] = true;
}

void ComputeProgram::bind_storage(std::uint32_t binding, const Buffer& buffer) {
  if (binding_type(binding) != VK_DESCRIPTOR_TYPE_STORAGE_BUFFER)
    throw std::logic_error("binding " + std::to_string(binding) + " is not a storage buffer");
  buffer_infos_[binding] = {buffer.handle(), 0, VK_WHOLE_SIZE};
  written_[binding] = true;
}

void ComputeProgram::bind_texel(std::uint32_t binding, const TexelView& view) {
  if (binding_type(binding) != VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER)
    throw std::logic_error("binding " + std::to_string(binding) + " is not a texel buffer");
  texel_views_[binding] = view.handle();
  written_[binding] = true;
}

void ComputeProgram::commit_bindings() {
  std::vector<VkWriteDescriptorSet> writes;
  for (std::uint32_t b = 0; b < BINDING_COUNT; ++b) {
    if (!written_[b]) throw std::logic_error("Vulkan backend: descriptor binding " + std::to_string(b) + " was never written");
    VkWriteDescriptorSet w{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
    w.dstSet = set_;
    w.dstBinding = b;
    w.descriptorCount = 1;
    w.descriptorType = binding_type(b);
    if (w.descriptorType == VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER) w.pTexelBufferView = &texel_views_[b];
    else w.pBufferInfo = &buffer_infos_[b];
    writes.push_back(w);
  }
  vkUpdateDescriptorSets(context_.device(), static_cast<std::uint32_t>(writes.size()), writes.data(), 0, nullptr);
}

void ComputeProgram::dispatch(VkCommandBuffer cb, Pass pass, std::uint32_t groups, const PushConstants& push) const {
  if (groups == 0) return;
  vkCmdBindPipeline(cb, VK_PIPELINE_BIND_POINT_COMPUTE, pipelines_[static_cast<int>(pass)]);
  vkCmdBindDescriptorSets(cb, VK_PIPELINE_BIND_POINT_COMPUTE, layout_, 0, 1, &set_, 0, nullptr);
  vkCmdPushConstants(cb, layout_, VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(PushConstants), &push);
  vkCmdDispatch(cb, groups, 1, 1);
  ++recorded_.dispatches;
}

void ComputeProgram::dispatch_indirect(VkCommandBuffer cb, Pass pass, const Buffer& args, VkDeviceSize offset,
                                       const PushConstants& push) const {
  vkCmdBindPipeline(cb, VK_PIPELINE_BIND_POINT_COMPUTE, pipelines_[static_cast<int>(pass)]);
  vkCmdBindDescriptorSets(cb, VK_PIPELINE_BIND_POINT_COMPUTE, layout_, 0, 1, &set_, 0, nullptr);
  vkCmdPushConstants(cb, layout_, VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(PushConstants), &push);
  vkCmdDispatchIndirect(cb, args.handle(), offset);
  ++recorded_.indirect_dispatches;
}

void ComputeProgram::barrier(VkCommandBuffer cb, Barrier kind) const {
  VkMemoryBarrier b{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
  VkPipelineStageFlags src = VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, dst = VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT;
  b.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_SHADER_READ_BIT;
  b.dstAccessMask = VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT;
  switch (kind) {
    case Barrier::compute:
      break;
    case Barrier::compute_and_indirect:
      b.dstAccessMask |= VK_ACCESS_INDIRECT_COMMAND_READ_BIT;
      dst |= VK_PIPELINE_STAGE_DRAW_INDIRECT_BIT;
      break;
    case Barrier::host_to_compute:
      b.srcAccessMask = VK_ACCESS_HOST_WRITE_BIT;
      b.dstAccessMask |= VK_ACCESS_UNIFORM_READ_BIT;
      src = VK_PIPELINE_STAGE_HOST_BIT;
      break;
    case Barrier::compute_to_host:
      b.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT;
      b.dstAccessMask = VK_ACCESS_HOST_READ_BIT | VK_ACCESS_TRANSFER_READ_BIT;
      dst = VK_PIPELINE_STAGE_HOST_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT;
      break;
  }
  vkCmdPipelineBarrier(cb, src, dst, 0, 1, &b, 0, nullptr, 0, nullptr);
  ++recorded_.barriers;
}

}  // namespace hapfluid::sim::vulkan
