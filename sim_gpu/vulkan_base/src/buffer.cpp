#include "hapfluid/vk/buffer.hpp"

#include <cstring>
#include <utility>

namespace hapfluid::vk {
namespace {

// First memory type allowed by `type_bits` that has all of `required` (and, if possible, all of
// `preferred`); UINT32_MAX when none fits.
std::uint32_t find_memory_type(const VkPhysicalDeviceMemoryProperties& props, std::uint32_t type_bits,
                               VkMemoryPropertyFlags required, VkMemoryPropertyFlags preferred) {
  std::uint32_t fallback = UINT32_MAX;
  for (std::uint32_t i = 0; i < props.memoryTypeCount; ++i) {
    if (!(type_bits & (1u << i))) continue;
    const VkMemoryPropertyFlags flags = props.memoryTypes[i].propertyFlags;
    if ((flags & required) != required) continue;
    if ((flags & preferred) == preferred) return i;
    if (fallback == UINT32_MAX) fallback = i;
  }
  return fallback;
}

}  // namespace

Buffer::Buffer(Context& context, VkDeviceSize bytes, VkBufferUsageFlags usage, MemoryUse use) : context_(&context) {
  size_ = bytes > 0 ? bytes : 16;  // zero-sized buffers are invalid; empty sets still bind one
  VkBufferCreateInfo info{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
  info.size = size_;
  info.usage = usage | VK_BUFFER_USAGE_TRANSFER_SRC_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT;
  info.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
  check(vkCreateBuffer(context.device(), &info, nullptr, &buffer_), "vkCreateBuffer");
  VkMemoryRequirements req;
  vkGetBufferMemoryRequirements(context.device(), buffer_, &req);
  const auto& props = context.memory_properties();
  const VkMemoryPropertyFlags host = VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
  std::uint32_t type = UINT32_MAX;
  if (use == MemoryUse::host) {
    type = find_memory_type(props, req.memoryTypeBits, host, 0);
  } else {
    // Device-local, and mappable too where the device offers it (unified memory).
    type = find_memory_type(props, req.memoryTypeBits, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT, host);
    if (type == UINT32_MAX) type = find_memory_type(props, req.memoryTypeBits, 0, 0);
  }
  if (type == UINT32_MAX) {
    release();
    throw VulkanError("Vulkan: no memory type for a buffer of " + std::to_string(bytes) + " bytes");
  }
  VkMemoryAllocateInfo alloc{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
  alloc.allocationSize = req.size;
  alloc.memoryTypeIndex = type;
  const VkResult r = vkAllocateMemory(context.device(), &alloc, nullptr, &memory_);
  if (r != VK_SUCCESS) {
    release();
    check(r, ("vkAllocateMemory (" + std::to_string(req.size) + " bytes)").c_str());
  }
  // A constructor that throws runs no destructor: free what exists before saying why.
  VkResult bound = vkBindBufferMemory(context.device(), buffer_, memory_, 0);
  if (bound == VK_SUCCESS && (props.memoryTypes[type].propertyFlags & host) == host) {
    bound = vkMapMemory(context.device(), memory_, 0, VK_WHOLE_SIZE, 0, &mapped_);
    if (bound != VK_SUCCESS) mapped_ = nullptr;
  }
  if (bound != VK_SUCCESS) {
    release();
    check(bound, "vkBindBufferMemory / vkMapMemory");
  }
}

Buffer::~Buffer() { release(); }

void Buffer::release() {
  if (!context_) return;
  if (mapped_) vkUnmapMemory(context_->device(), memory_);
  if (buffer_) vkDestroyBuffer(context_->device(), buffer_, nullptr);
  if (memory_) vkFreeMemory(context_->device(), memory_, nullptr);
  buffer_ = VK_NULL_HANDLE, memory_ = VK_NULL_HANDLE, mapped_ = nullptr, context_ = nullptr;
}

Buffer::Buffer(Buffer&& o) noexcept { *this = std::move(o); }

Buffer& Buffer::operator=(Buffer&& o) noexcept {
  if (this != &o) {
    release();
    std::swap(context_, o.context_);
    std::swap(buffer_, o.buffer_);
    std::swap(memory_, o.memory_);
    std::swap(size_, o.size_);
    std::swap(mapped_, o.mapped_);
  }
  return *this;
}

void Buffer::upload(const void* data, VkDeviceSize bytes, VkDeviceSize offset) {
  if (bytes == 0) return;
  if (offset + bytes > size_) throw VulkanError("Vulkan: upload past the end of a buffer");
  if (mapped_) {
    std::memcpy(static_cast<char*>(mapped_) + offset, data, bytes);
    return;
  }
  Buffer staging(*context_, bytes, VK_BUFFER_USAGE_TRANSFER_SRC_BIT, MemoryUse::host);
  std::memcpy(staging.mapped(), data, bytes);
  context_->run_once([&](VkCommandBuffer cb) {
    const VkBufferCopy region{0, offset, bytes};
    vkCmdCopyBuffer(cb, staging.handle(), buffer_, 1, &region);
  });
}

void Buffer::download(void* data, VkDeviceSize bytes, VkDeviceSize offset) const {
  if (bytes == 0) return;
  if (offset + bytes > size_) throw VulkanError("Vulkan: download past the end of a buffer");
  if (mapped_) {
    std::memcpy(data, static_cast<const char*>(mapped_) + offset, bytes);
    return;
  }
  Buffer staging(*context_, bytes, VK_BUFFER_USAGE_TRANSFER_DST_BIT, MemoryUse::host);
  context_->run_once([&](VkCommandBuffer cb) {
    const VkBufferCopy region{offset, 0, bytes};
    vkCmdCopyBuffer(cb, buffer_, staging.handle(), 1, &region);
    VkMemoryBarrier barrier{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
    barrier.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
    barrier.dstAccessMask = VK_ACCESS_HOST_READ_BIT;
    vkCmdPipelineBarrier(cb, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &barrier, 0, nullptr, 0,
                         nullptr);
  });
  std::memcpy(data, staging.mapped(), bytes);
}

TexelView::TexelView(Context& context, const Buffer& buffer, VkFormat format, VkDeviceSize offset, VkDeviceSize range)
    : context_(&context) {
  VkBufferViewCreateInfo info{VK_STRUCTURE_TYPE_BUFFER_VIEW_CREATE_INFO};
  info.buffer = buffer.handle();
  info.format = format;
  info.offset = offset;
  info.range = range;
  check(vkCreateBufferView(context.device(), &info, nullptr, &view_), "vkCreateBufferView");
}

TexelView::~TexelView() {
  if (context_ && view_) vkDestroyBufferView(context_->device(), view_, nullptr);
}

TexelView::TexelView(TexelView&& o) noexcept { *this = std::move(o); }

TexelView& TexelView::operator=(TexelView&& o) noexcept {
  if (this != &o) {
    if (context_ && view_) vkDestroyBufferView(context_->device(), view_, nullptr);
    context_ = o.context_, view_ = o.view_;
    o.context_ = nullptr, o.view_ = VK_NULL_HANDLE;
  }
  return *this;
}

}  // namespace hapfluid::vk
