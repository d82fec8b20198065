// tests/sim_gpu/test_dam_break.cpp, unchanged, on the Vulkan backend with the validation layer on
// (see cpu_suite_on_vulkan.hpp): dam break: surge front within -5%/+20% of Martin \& Moyce (1952) at every data point from T = 0.5 and the residual column (mass within 4 spacings of the wall) within 10% while it collapses (tau <= 1.3), -35%/+10% up to tau = 2.45, mass exact; the wall clamp's events are reported (648 on Vulkan, 737 on the CPU).
#include "cpu_suite_on_vulkan.hpp"

#include "../sim_gpu/test_dam_break.cpp"
