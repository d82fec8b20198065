// tests/sim_gpu/test_hydrostatic.cpp, unchanged, on the Vulkan backend with the validation layer on
// (see cpu_suite_on_vulkan.hpp): hydrostatic tank: pressure within 10% of rho0 g d in the bulk (every snapshot and their average) and dp/dd within 5% of rho0 g, the pressure gradient's first moment exact in the settled bulk, kinetic energy decays, no particle leaves.
#include "cpu_suite_on_vulkan.hpp"

#include "../sim_gpu/test_hydrostatic.cpp"
