// tests/sim_gpu/test_rigid_bodies.cpp, unchanged, on the Vulkan backend with the validation layer on
// (see cpu_suite_on_vulkan.hpp): rigid bodies and couplings: free fall follows g, momentum of body+fluid conserved in zero gravity (angular momentum too without viscosity), a torque-free box tumbles keeping L = I_world w, a 0.5 rho0 sphere floats half submerged, a static cup holds fluid, bodies collide without passing through, a ball dropped on the floor stops bouncing (restitution < 0.5) and rests on it, a spun cup's opposing torque grows with its viscosity (fig. 10), a stirring paddle feels a force against its motion (fig. 8), two devices share a bar's weight (bimanual).
#include "cpu_suite_on_vulkan.hpp"

#include "../sim_gpu/test_rigid_bodies.cpp"
