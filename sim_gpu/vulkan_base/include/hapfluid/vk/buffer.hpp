// Buffers and their memory. On a unified-memory device (lavapipe, integrated GPUs) device-local
// memory is also host-visible and is mapped directly; on a discrete GPU uploads and read-backs go
// through a staging buffer. One allocation per buffer: the simulator owns a few dozen buffers,
// created once per scene, the renderer a handful (vertices, uniforms, read-backs).
#pragma once

#include <cstddef>
#include <cstdint>

#include "hapfluid/vk/context.hpp"

namespace hapfluid::vk {

enum class MemoryUse {
  device,  // particle arrays: device-local, mapped when the device-local heap is host-visible
  host,    // per-step inputs and results: host-visible and coherent, always mapped
};

class Buffer {
 public:
  Buffer() = default;
  Buffer(Context& context, VkDeviceSize bytes, VkBufferUsageFlags usage, MemoryUse use);
  ~Buffer();
  Buffer(Buffer&& other) noexcept;
  Buffer& operator=(Buffer&& other) noexcept;
  Buffer(const Buffer&) = delete;
  Buffer& operator=(const Buffer&) = delete;

  VkBuffer handle() const { return buffer_; }
  VkDeviceSize size() const { return size_; }
  void* mapped() const { return mapped_; }

  // Copies between host memory and the buffer; the device must be idle for this buffer
  // (set-up, or after the fence of the last submission that used it).
  void upload(const void* data, VkDeviceSize bytes, VkDeviceSize offset = 0);
  void download(void* data, VkDeviceSize bytes, VkDeviceSize offset = 0) const;

 private:
  void release();

  Context* context_ = nullptr;
  VkBuffer buffer_ = VK_NULL_HANDLE;
  VkDeviceMemory memory_ = VK_NULL_HANDLE;
  VkDeviceSize size_ = 0;
  void* mapped_ = nullptr;
};

// A texel view of a buffer (samplerBuffer / usamplerBuffer in the shaders): on lavapipe texel
// fetches are about ten times faster than storage-buffer loads on lavapipe, so every array that
// neighbour loops read is also bound through one of these.
class TexelView {
 public:
  TexelView() = default;
  TexelView(Context& context, const Buffer& buffer, VkFormat format, VkDeviceSize offset = 0,
            VkDeviceSize range = VK_WHOLE_SIZE);
  ~TexelView();
  TexelView(TexelView&& other) noexcept;
  TexelView& operator=(TexelView&& other) noexcept;
  TexelView(const TexelView&) = delete;
  TexelView& operator=(const TexelView&) = delete;
  VkBufferView handle() const { return view_; }

 private:
  Context* context_ = nullptr;
  VkBufferView view_ = VK_NULL_HANDLE;
};

}  // namespace hapfluid::vk
