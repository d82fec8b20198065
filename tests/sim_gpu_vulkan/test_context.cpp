// The Vulkan base (sim_gpu/vulkan_base) the compute backend and the renderer share: device
// choice, both queue kinds, GPU timers, the validation layer, and a clean failure (never a crash)
// when no Vulkan driver exists, so `auto` can fall back to the CPU backend.
#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <vector>

#include "hapfluid/sim_vulkan/base.hpp"
#include "hapfluid/vk/gpu_timer.hpp"

namespace hv = hapfluid::sim::vulkan;

namespace {
hv::ContextOptions validated() {
  hv::ContextOptions o;
  o.validation = true;
  return o;
}
}  // namespace

TEST(VulkanContext, AutoPicksADeviceWithComputeAndReportsIt) {
  hv::Context context(validated());
  EXPECT_FALSE(context.description().name.empty());
  EXPECT_TRUE(context.description().has_compute_queue);
  EXPECT_GE(context.description().api_version, VK_API_VERSION_1_2);
  EXPECT_TRUE(context.validation_enabled());
  // The device list names the chosen device too (what `--list-devices` shows a user).
  bool listed = false;
  for (const auto& d : hv::list_devices()) listed = listed || d.name == context.description().name;
  EXPECT_TRUE(listed);
  EXPECT_EQ(context.validation_counts().errors, 0u);
  EXPECT_EQ(context.validation_counts().warnings, 0u);
}

TEST(VulkanContext, AGraphicsContextIsVulkan13WithAGraphicsAndComputeQueue) {
  // What the renderer asks for; the compute context above may take a compute-only family.
  hv::ContextOptions o = validated();
  o.queue = hapfluid::vk::QueueKind::graphics;
  hv::Context context(o);
  EXPECT_GE(context.description().api_version, VK_API_VERSION_1_3);
  EXPECT_TRUE(context.description().has_graphics_compute_queue);
  std::uint32_t families = 0;
  vkGetPhysicalDeviceQueueFamilyProperties(context.physical_device(), &families, nullptr);
  std::vector<VkQueueFamilyProperties> family(families);
  vkGetPhysicalDeviceQueueFamilyProperties(context.physical_device(), &families, family.data());
  const VkQueueFlags both = VK_QUEUE_GRAPHICS_BIT | VK_QUEUE_COMPUTE_BIT;
  EXPECT_EQ(family[context.queue_family()].queueFlags & both, both);
  context.destroy_device();
  EXPECT_EQ(context.validation_counts().errors, 0u);
  EXPECT_EQ(context.validation_counts().warnings, 0u);
}

TEST(VulkanContext, GpuTimerMeasuresPassesOnAComputeContext) {
  hv::Context context(validated());
  hapfluid::vk::GpuTimer timer(context);
  hv::Buffer buffer(context, 1 << 20, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, hv::MemoryUse::device);
  context.run_once([&](VkCommandBuffer cb) {
    timer.begin(cb);
    // Two halves: two passes with no hazard between them (the layer checks synchronization).
    vkCmdFillBuffer(cb, buffer.handle(), 0, 1 << 19, 7u);
    timer.stamp(cb);
    vkCmdFillBuffer(cb, buffer.handle(), 1 << 19, 1 << 19, 9u);
    timer.stamp(cb);
  });
  std::array<double, hapfluid::vk::GpuTimer::capacity - 1> ms{};
  std::uint32_t count = 0;
  // A device without timestamps (lavapipe has them) gets no intervals, and says so.
  ASSERT_EQ(timer.intervals_ms(ms, count), context.timestamps_supported()) << context.description().name;
  if (!context.timestamps_supported()) return;
  ASSERT_EQ(count, 2u);
  EXPECT_GE(ms[0], 0.0);
  EXPECT_GE(ms[1], 0.0);
  EXPECT_EQ(context.validation_counts().errors, 0u);
  EXPECT_EQ(context.validation_counts().warnings, 0u);
}

TEST(VulkanContext, CpuPreferenceSelectsLavapipeOrSaysWhyNot) {
  // CI has only lavapipe; on a rig with a GPU this still must pick the CPU implementation.
  try {
    hv::ContextOptions o = validated();
    o.device = hv::DevicePreference::cpu;
    hv::Context context(o);
    EXPECT_EQ(context.description().vk_type, VK_PHYSICAL_DEVICE_TYPE_CPU);
  } catch (const hv::VulkanUnavailable& e) {
    EXPECT_NE(std::string(e.what()).find("CPU device"), std::string::npos) << e.what();
  }
}

TEST(VulkanContext, ValidationLayerCountsMisuse) {
  // The messenger must really see errors, or "no validation errors" in every other test would
  // prove nothing: a buffer of size 0 is invalid usage (VUID-VkBufferCreateInfo-size-00912).
  hv::ContextOptions o = validated();
  o.print_validation_messages = false;
  hv::Context context(o);
  VkBufferCreateInfo info{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
  info.size = 0;
  info.usage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT;
  VkBuffer buffer = VK_NULL_HANDLE;
  // lavapipe accepts it; the layer reports it. Destroy whatever came back.
  if (vkCreateBuffer(context.device(), &info, nullptr, &buffer) == VK_SUCCESS && buffer)
    vkDestroyBuffer(context.device(), buffer, nullptr);
  EXPECT_GE(context.validation_counts().errors, 1u);
  ASSERT_FALSE(context.validation_messages().empty());
}

TEST(VulkanContext, NoDriverGivesAClearErrorNotACrash) {
  // A machine without a Vulkan driver: the loader finds no ICD (it reads these variables at
  // every vkCreateInstance; they are restored at the end for the other tests of the process).
  struct RestoreEnvironment {
    ~RestoreEnvironment() { unsetenv("VK_ICD_FILENAMES"), unsetenv("VK_DRIVER_FILES"); }
  } restore;
  ASSERT_EQ(std::getenv("VK_ICD_FILENAMES"), nullptr) << "the test environment already redirects the loader";
  setenv("VK_ICD_FILENAMES", "/nonexistent/icd.json", 1);
  setenv("VK_DRIVER_FILES", "/nonexistent/icd.json", 1);
  try {
    hv::Context context(hv::ContextOptions{});
    FAIL() << "a context was created without any Vulkan driver";
  } catch (const hv::VulkanUnavailable& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("driver"), std::string::npos) << message;
    EXPECT_NE(message.find("mesa-vulkan-drivers"), std::string::npos) << message;
  }
  std::string why;
  EXPECT_TRUE(hv::list_devices(&why).empty());
  EXPECT_FALSE(why.empty());
}

TEST(VulkanContext, DevicePreferenceNamesAreParsedStrictly) {
  EXPECT_EQ(hv::parse_device_preference("auto"), hv::DevicePreference::automatic);
  EXPECT_EQ(hv::parse_device_preference("gpu"), hv::DevicePreference::gpu);
  EXPECT_EQ(hv::parse_device_preference("lavapipe"), hv::DevicePreference::cpu);
  EXPECT_THROW(hv::parse_device_preference("fastest"), std::invalid_argument);
}
