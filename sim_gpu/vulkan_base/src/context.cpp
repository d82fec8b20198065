#include "hapfluid/vk/context.hpp"

#include <cstdio>
#include <cstring>
#include <mutex>

#include "hapfluid/config/log.hpp"

namespace hapfluid::vk {
namespace {

constexpr const char* kValidationLayer = "VK_LAYER_KHRONOS_validation";
constexpr std::size_t kKeptMessages = 32;

// volk loads libvulkan.so.1 at run time, so a machine without the loader still runs the CPU
// backend; initialising once per process is enough.
void load_vulkan_loader() {
  static std::once_flag once;
  static VkResult result = VK_SUCCESS;
  std::call_once(once, [] { result = volkInitialize(); });
  if (result != VK_SUCCESS)
    throw VulkanUnavailable(
        "Vulkan: the Vulkan loader (libvulkan.so.1) was not found; install libvulkan1 and a driver "
        "(mesa-vulkan-drivers provides lavapipe, a CPU implementation)");
}

std::string type_name(VkPhysicalDeviceType type) {
  switch (type) {
    case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU: return "discrete GPU";
    case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU: return "integrated GPU";
    case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU: return "virtual GPU";
    case VK_PHYSICAL_DEVICE_TYPE_CPU: return "CPU";
    default: return "other";
  }
}

// Lower is better for `auto`: the paper's point is the GPU, lavapipe is the portable floor.
int preference_rank(VkPhysicalDeviceType type) {
  switch (type) {
    case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU: return 0;
    case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU: return 1;
    case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU: return 2;
    case VK_PHYSICAL_DEVICE_TYPE_OTHER: return 3;
    default: return 4;  // CPU
  }
}

bool layer_available(const char* name) {
  std::uint32_t count = 0;
  vkEnumerateInstanceLayerProperties(&count, nullptr);
  std::vector<VkLayerProperties> layers(count);
  vkEnumerateInstanceLayerProperties(&count, layers.data());
  for (const auto& l : layers)
    if (std::strcmp(l.layerName, name) == 0) return true;
  return false;
}

VKAPI_ATTR VkBool32 VKAPI_CALL debug_callback(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                              VkDebugUtilsMessageTypeFlagsEXT,
                                              const VkDebugUtilsMessengerCallbackDataEXT* data, void* user) {
  static_cast<Context*>(user)->on_validation_message(severity, data && data->pMessage ? data->pMessage : "");
  return VK_FALSE;
}

VkDebugUtilsMessengerCreateInfoEXT messenger_info(Context* context) {
  VkDebugUtilsMessengerCreateInfoEXT info{VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT};
  info.messageSeverity = VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
  info.messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT |
                     VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT;
  info.pfnUserCallback = debug_callback;
  info.pUserData = context;
  return info;
}

// Entry points are looked up on `instance` (not volk's globals), so this works for any instance.
DeviceDescription describe(VkInstance instance, VkPhysicalDevice device) {
  auto get_properties = reinterpret_cast<PFN_vkGetPhysicalDeviceProperties>(
      vkGetInstanceProcAddr(instance, "vkGetPhysicalDeviceProperties"));
  auto get_properties2 = reinterpret_cast<PFN_vkGetPhysicalDeviceProperties2>(
      vkGetInstanceProcAddr(instance, "vkGetPhysicalDeviceProperties2"));
  auto get_families = reinterpret_cast<PFN_vkGetPhysicalDeviceQueueFamilyProperties>(
      vkGetInstanceProcAddr(instance, "vkGetPhysicalDeviceQueueFamilyProperties"));
  VkPhysicalDeviceDriverProperties driver{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_DRIVER_PROPERTIES};
  VkPhysicalDeviceProperties2 props2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2};
  VkPhysicalDeviceProperties props{};
  get_properties(device, &props);
  DeviceDescription d;
  d.name = props.deviceName;
  d.vk_type = props.deviceType;
  d.type = type_name(props.deviceType);
  d.api_version = props.apiVersion;
  if (props.apiVersion >= VK_API_VERSION_1_2 && get_properties2) {
    props2.pNext = &driver;
    get_properties2(device, &props2);
    d.driver = std::string(driver.driverName) + " " + driver.driverInfo;
  }
  std::uint32_t families = 0;
  get_families(device, &families, nullptr);
  std::vector<VkQueueFamilyProperties> family(families);
  get_families(device, &families, family.data());
  const VkQueueFlags both = VK_QUEUE_GRAPHICS_BIT | VK_QUEUE_COMPUTE_BIT;
  for (const auto& f : family) {
    d.has_compute_queue = d.has_compute_queue || (f.queueFlags & VK_QUEUE_COMPUTE_BIT);
    d.has_graphics_compute_queue = d.has_graphics_compute_queue || (f.queueFlags & both) == both;
  }
  return d;
}

VkResult create_bare_instance(VkInstance* instance) {
  VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
  app.pApplicationName = "haptic-sim";
  app.apiVersion = VK_API_VERSION_1_2;
  VkInstanceCreateInfo info{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
  info.pApplicationInfo = &app;
  return vkCreateInstance(&info, nullptr, instance);
}

const char* kNoDriverHint =
    "no Vulkan driver (ICD) is installed or found; install mesa-vulkan-drivers (lavapipe) or the GPU's "
    "driver, and check VK_ICD_FILENAMES / VK_DRIVER_FILES if set";

}  // namespace

const char* result_name(VkResult r) {
  switch (r) {
    case VK_SUCCESS: return "VK_SUCCESS";
    case VK_NOT_READY: return "VK_NOT_READY";
    case VK_TIMEOUT: return "VK_TIMEOUT";
    case VK_INCOMPLETE: return "VK_INCOMPLETE";
    case VK_ERROR_OUT_OF_HOST_MEMORY: return "VK_ERROR_OUT_OF_HOST_MEMORY";
    case VK_ERROR_OUT_OF_DEVICE_MEMORY: return "VK_ERROR_OUT_OF_DEVICE_MEMORY";
    case VK_ERROR_INITIALIZATION_FAILED: return "VK_ERROR_INITIALIZATION_FAILED";
    case VK_ERROR_DEVICE_LOST: return "VK_ERROR_DEVICE_LOST";
    case VK_ERROR_MEMORY_MAP_FAILED: return "VK_ERROR_MEMORY_MAP_FAILED";
    case VK_ERROR_LAYER_NOT_PRESENT: return "VK_ERROR_LAYER_NOT_PRESENT";
    case VK_ERROR_EXTENSION_NOT_PRESENT: return "VK_ERROR_EXTENSION_NOT_PRESENT";
    case VK_ERROR_FEATURE_NOT_PRESENT: return "VK_ERROR_FEATURE_NOT_PRESENT";
    case VK_ERROR_INCOMPATIBLE_DRIVER: return "VK_ERROR_INCOMPATIBLE_DRIVER";
    case VK_ERROR_TOO_MANY_OBJECTS: return "VK_ERROR_TOO_MANY_OBJECTS";
    case VK_ERROR_FORMAT_NOT_SUPPORTED: return "VK_ERROR_FORMAT_NOT_SUPPORTED";
    case VK_ERROR_OUT_OF_POOL_MEMORY: return "VK_ERROR_OUT_OF_POOL_MEMORY";
    case VK_SUBOPTIMAL_KHR: return "VK_SUBOPTIMAL_KHR";
    case VK_ERROR_SURFACE_LOST_KHR: return "VK_ERROR_SURFACE_LOST_KHR";
    case VK_ERROR_OUT_OF_DATE_KHR: return "VK_ERROR_OUT_OF_DATE_KHR";
    case VK_ERROR_NATIVE_WINDOW_IN_USE_KHR: return "VK_ERROR_NATIVE_WINDOW_IN_USE_KHR";
    default: return "VkResult(unknown)";
  }
}

void check(VkResult result, const char* what) {
  if (result != VK_SUCCESS) throw VulkanError(std::string("Vulkan: ") + what + " failed: " + result_name(result));
}

DevicePreference parse_device_preference(const std::string& text) {
  if (text == "auto") return DevicePreference::automatic;
  if (text == "gpu") return DevicePreference::gpu;
  if (text == "cpu" || text == "lavapipe") return DevicePreference::cpu;
  throw std::invalid_argument("Vulkan device '" + text + "': expected auto, gpu or cpu (lavapipe)");
}

std::string DeviceDescription::version_string() const {
  return std::to_string(VK_API_VERSION_MAJOR(api_version)) + "." + std::to_string(VK_API_VERSION_MINOR(api_version)) +
         "." + std::to_string(VK_API_VERSION_PATCH(api_version));
}

std::vector<DeviceDescription> list_devices(std::string* why_empty) {
  std::vector<DeviceDescription> out;
  try {
    load_vulkan_loader();
  } catch (const VulkanUnavailable& e) {
    if (why_empty) *why_empty = e.what();
    return out;
  }
  VkInstance instance = VK_NULL_HANDLE;
  const VkResult r = create_bare_instance(&instance);
  if (r != VK_SUCCESS) {
    if (why_empty) *why_empty = std::string("vkCreateInstance returned ") + result_name(r) + ": " + kNoDriverHint;
    return out;
  }
  // volk's function pointers are process-wide and belong to the contexts: this short-lived
  // instance gets its own few entry points instead of reloading them.
  auto enumerate = reinterpret_cast<PFN_vkEnumeratePhysicalDevices>(vkGetInstanceProcAddr(instance, "vkEnumeratePhysicalDevices"));
  auto destroy = reinterpret_cast<PFN_vkDestroyInstance>(vkGetInstanceProcAddr(instance, "vkDestroyInstance"));
  std::uint32_t count = 0;
  enumerate(instance, &count, nullptr);
  std::vector<VkPhysicalDevice> devices(count);
  enumerate(instance, &count, devices.data());
  for (VkPhysicalDevice d : devices) out.push_back(describe(instance, d));
  if (out.empty() && why_empty) *why_empty = kNoDriverHint;
  destroy(instance, nullptr);
  return out;
}

Context::Context(const ContextOptions& options)
    : validation_(options.validation),
      print_messages_(options.print_validation_messages),
      queue_kind_(options.queue) {
  load_vulkan_loader();
  try {
    create_instance(options);
    choose_physical_device(options);
    create_device(options);
  } catch (...) {
    release();
    throw;
  }
}

Context::~Context() { release(); }

void Context::destroy_device() {
  if (!device_) return;
  vkDeviceWaitIdle(device_);
  if (one_time_fence_) vkDestroyFence(device_, one_time_fence_, nullptr);
  if (command_pool_) vkDestroyCommandPool(device_, command_pool_, nullptr);
  vkDestroyDevice(device_, nullptr);
  device_ = VK_NULL_HANDLE, command_pool_ = VK_NULL_HANDLE, one_time_fence_ = VK_NULL_HANDLE;
}

void Context::release() {
  destroy_device();
  if (messenger_) vkDestroyDebugUtilsMessengerEXT(instance_, messenger_, nullptr);
  messenger_ = VK_NULL_HANDLE;
  if (instance_) vkDestroyInstance(instance_, nullptr);
  instance_ = VK_NULL_HANDLE;
}

void Context::create_instance(const ContextOptions& options) {
  std::vector<const char*> layers, extensions;
  for (const auto& e : options.instance_extensions) extensions.push_back(e.c_str());
  VkDebugUtilsMessengerCreateInfoEXT debug_info = messenger_info(this);
  VkValidationFeaturesEXT features{VK_STRUCTURE_TYPE_VALIDATION_FEATURES_EXT};
  const VkValidationFeatureEnableEXT sync = VK_VALIDATION_FEATURE_ENABLE_SYNCHRONIZATION_VALIDATION_EXT;
  if (validation_) {
    if (!layer_available(kValidationLayer))
      throw VulkanError(std::string("Vulkan: validation was requested but the layer ") + kValidationLayer +
                        " is not installed (Debian: apt-get install vulkan-validationlayers)");
    layers.push_back(kValidationLayer);
    extensions.push_back(VK_EXT_DEBUG_UTILS_EXTENSION_NAME);
    extensions.push_back(VK_EXT_VALIDATION_FEATURES_EXTENSION_NAME);
    if (options.synchronization_validation) {
      features.enabledValidationFeatureCount = 1;
      features.pEnabledValidationFeatures = &sync;
    }
    features.pNext = &debug_info;  // messages of vkCreateInstance itself are counted too
  }
  VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
  app.pApplicationName = options.application.c_str();
  app.pEngineName = "hapfluid";
  app.apiVersion = options.queue == QueueKind::graphics ? VK_API_VERSION_1_3 : VK_API_VERSION_1_2;
  VkInstanceCreateInfo info{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
  info.pNext = validation_ ? &features : nullptr;
  info.pApplicationInfo = &app;
  info.enabledLayerCount = static_cast<std::uint32_t>(layers.size());
  info.ppEnabledLayerNames = layers.data();
  info.enabledExtensionCount = static_cast<std::uint32_t>(extensions.size());
  info.ppEnabledExtensionNames = extensions.data();
  const VkResult r = vkCreateInstance(&info, nullptr, &instance_);
  if (r == VK_ERROR_INCOMPATIBLE_DRIVER || r == VK_ERROR_INITIALIZATION_FAILED)
    throw VulkanUnavailable(std::string("Vulkan: vkCreateInstance returned ") + result_name(r) + ": " + kNoDriverHint);
  check(r, "vkCreateInstance");
  volkLoadInstance(instance_);
  if (validation_) check(vkCreateDebugUtilsMessengerEXT(instance_, &debug_info, nullptr, &messenger_), "vkCreateDebugUtilsMessengerEXT");
}

void Context::choose_physical_device(const ContextOptions& options) {
  const DevicePreference preference = options.device;
  const bool graphics = options.queue == QueueKind::graphics;
  // The renderer draws with dynamic rendering and synchronization2 (Vulkan 1.3).
  const std::uint32_t min_api = graphics ? VK_API_VERSION_1_3 : VK_API_VERSION_1_2;
  std::uint32_t count = 0;
  check(vkEnumeratePhysicalDevices(instance_, &count, nullptr), "vkEnumeratePhysicalDevices");
  std::vector<VkPhysicalDevice> devices(count);
  check(vkEnumeratePhysicalDevices(instance_, &count, devices.data()), "vkEnumeratePhysicalDevices");
  if (devices.empty()) throw VulkanUnavailable(std::string("Vulkan: no physical device: ") + kNoDriverHint);

  int best_rank = 1 << 30;
  std::string seen;
  for (VkPhysicalDevice d : devices) {
    const DeviceDescription desc = describe(instance_, d);
    seen += (seen.empty() ? "" : ", ") + desc.name + " (" + desc.type + ", Vulkan " + desc.version_string() + ")";
    if (!desc.has_compute_queue || desc.api_version < min_api) continue;
    if (graphics && !desc.has_graphics_compute_queue) continue;
    const bool is_cpu = desc.vk_type == VK_PHYSICAL_DEVICE_TYPE_CPU;
    if (preference == DevicePreference::gpu && is_cpu) continue;
    if (preference == DevicePreference::cpu && !is_cpu) continue;
    const int rank = preference_rank(desc.vk_type);
    if (rank < best_rank) {
      best_rank = rank;
      physical_device_ = d;
      description_ = desc;
    }
  }
  if (!physical_device_) {
    const char* wanted = preference == DevicePreference::gpu ? "a GPU" : preference == DevicePreference::cpu ? "a CPU device (lavapipe)" : "a device";
    throw VulkanUnavailable(std::string("Vulkan: no suitable device: wanted ") + wanted +
                            (graphics ? " with Vulkan 1.3 and a graphics+compute queue" : " with Vulkan 1.2 and a compute queue") +
                            "; found: " + (seen.empty() ? "none" : seen));
  }
  vkGetPhysicalDeviceProperties(physical_device_, &properties_);
  vkGetPhysicalDeviceMemoryProperties(physical_device_, &memory_properties_);
  VkPhysicalDeviceSubgroupProperties subgroup{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SUBGROUP_PROPERTIES};
  VkPhysicalDeviceProperties2 props2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2};
  props2.pNext = &subgroup;
  vkGetPhysicalDeviceProperties2(physical_device_, &props2);
  subgroup_size_ = subgroup.subgroupSize;
}

void Context::create_device(const ContextOptions& options) {
  const bool graphics = options.queue == QueueKind::graphics;
  std::uint32_t families = 0;
  vkGetPhysicalDeviceQueueFamilyProperties(physical_device_, &families, nullptr);
  std::vector<VkQueueFamilyProperties> family(families);
  vkGetPhysicalDeviceQueueFamilyProperties(physical_device_, &families, family.data());
  // Compute: prefer a compute-only family (async compute on GPUs), else any family with compute.
  // Graphics: the first family with both.
  int chosen = -1;
  const VkQueueFlags both = VK_QUEUE_GRAPHICS_BIT | VK_QUEUE_COMPUTE_BIT;
  for (std::uint32_t i = 0; i < families; ++i) {
    if (graphics) {
      if ((family[i].queueFlags & both) == both) {
        chosen = static_cast<int>(i);
        break;
      }
      continue;
    }
    if (!(family[i].queueFlags & VK_QUEUE_COMPUTE_BIT)) continue;
    if (chosen < 0 || !(family[i].queueFlags & VK_QUEUE_GRAPHICS_BIT)) chosen = static_cast<int>(i);
  }
  queue_family_ = static_cast<std::uint32_t>(chosen);
  timestamp_valid_bits_ = family[queue_family_].timestampValidBits;
  if (properties_.limits.timestampPeriod <= 0) timestamp_valid_bits_ = 0;

  const float priority = 1.0f;
  VkDeviceQueueCreateInfo queue_info{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
  queue_info.queueFamilyIndex = queue_family_;
  queue_info.queueCount = 1;
  queue_info.pQueuePriorities = &priority;
  VkDeviceCreateInfo info{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
  info.queueCreateInfoCount = 1;
  info.pQueueCreateInfos = &queue_info;
  VkPhysicalDeviceVulkan13Features v13{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_3_FEATURES};
  VkPhysicalDeviceFeatures2 features{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2};
  std::vector<const char*> extensions;
  if (graphics) {
    VkPhysicalDeviceFeatures supported{};
    vkGetPhysicalDeviceFeatures(physical_device_, &supported);
    if (!supported.shaderStorageImageWriteWithoutFormat)
      throw VulkanUnavailable("Vulkan: " + description_.name +
                              " lacks shaderStorageImageWriteWithoutFormat (the renderer's filter passes need it)");
    v13.dynamicRendering = VK_TRUE;
    v13.synchronization2 = VK_TRUE;
    features.pNext = &v13;
    features.features.shaderStorageImageWriteWithoutFormat = VK_TRUE;
    info.pNext = &features;
    if (options.swapchain) extensions.push_back(VK_KHR_SWAPCHAIN_EXTENSION_NAME);
  }
  info.enabledExtensionCount = static_cast<std::uint32_t>(extensions.size());
  info.ppEnabledExtensionNames = extensions.data();
  check(vkCreateDevice(physical_device_, &info, nullptr, &device_), "vkCreateDevice");
  // Device functions stay the loader's dispatching trampolines (no volkLoadDevice): volk's
  // pointers are process-wide, and trampolines are right for every device of every context.
  vkGetDeviceQueue(device_, queue_family_, 0, &queue_);

  VkCommandPoolCreateInfo pool{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
  pool.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
  pool.queueFamilyIndex = queue_family_;
  check(vkCreateCommandPool(device_, &pool, nullptr, &command_pool_), "vkCreateCommandPool");
  VkFenceCreateInfo fence{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
  check(vkCreateFence(device_, &fence, nullptr, &one_time_fence_), "vkCreateFence");
}

VkCommandBuffer Context::begin_one_time() {
  VkCommandBufferAllocateInfo alloc{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
  alloc.commandPool = command_pool_;
  alloc.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
  alloc.commandBufferCount = 1;
  VkCommandBuffer cb = VK_NULL_HANDLE;
  check(vkAllocateCommandBuffers(device_, &alloc, &cb), "vkAllocateCommandBuffers");
  VkCommandBufferBeginInfo begin{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
  begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  check(vkBeginCommandBuffer(cb, &begin), "vkBeginCommandBuffer");
  return cb;
}

void Context::end_one_time(VkCommandBuffer cb) {
  check(vkEndCommandBuffer(cb), "vkEndCommandBuffer");
  VkSubmitInfo submit{VK_STRUCTURE_TYPE_SUBMIT_INFO};
  submit.commandBufferCount = 1;
  submit.pCommandBuffers = &cb;
  check(vkQueueSubmit(queue_, 1, &submit, one_time_fence_), "vkQueueSubmit (one-time)");
  const VkResult wait = vkWaitForFences(device_, 1, &one_time_fence_, VK_TRUE, UINT64_MAX);
  vkResetFences(device_, 1, &one_time_fence_);
  vkFreeCommandBuffers(device_, command_pool_, 1, &cb);
  check(wait, "vkWaitForFences (one-time)");
}

std::uint32_t Context::memory_type(std::uint32_t type_bits, VkMemoryPropertyFlags wanted) const {
  for (std::uint32_t i = 0; i < memory_properties_.memoryTypeCount; ++i)
    if ((type_bits & (1u << i)) && (memory_properties_.memoryTypes[i].propertyFlags & wanted) == wanted) return i;
  throw VulkanError("Vulkan: no memory type with the wanted properties on " + description_.name);
}

VkFormatFeatureFlags Context::format_features(VkFormat format) const {
  VkFormatProperties p;
  vkGetPhysicalDeviceFormatProperties(physical_device_, format, &p);
  return p.optimalTilingFeatures;
}

ValidationCounts Context::validation_counts() const { return {warnings_.load(), errors_.load()}; }

std::vector<std::string> Context::validation_messages() const {
  std::lock_guard<std::mutex> lock(messages_mutex_);
  return messages_;
}

void Context::on_validation_message(VkDebugUtilsMessageSeverityFlagBitsEXT severity, const char* message) {
  const bool error = severity & VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
  (error ? errors_ : warnings_).fetch_add(1);
  if (print_messages_) (error ? log::error : log::warning)("Vulkan validation %s: %s", error ? "error" : "warning", message);
  std::lock_guard<std::mutex> lock(messages_mutex_);
  if (messages_.size() < kKeptMessages) messages_.push_back(std::string(error ? "error: " : "warning: ") + message);
}

}  // namespace hapfluid::vk
