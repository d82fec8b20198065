// tests/sim_gpu/test_hydrostatic.cpp, unchanged, on the Vulkan backend with the validation layer on
// (see cpu_suite_on_vulkan.hpp): hydrostatic tank: pressure within 15% of rho0 g d in the bulk and dp/dd within 10% of rho0 g, kinetic energy decays, no particle leaves.
#include "cpu_suite_on_vulkan.hpp"

#include "../sim_gpu/test_hydrostatic.cpp"
