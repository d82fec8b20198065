// volk is shipped as source in Debian's libvulkan-volk-dev: compile its loader once, here.
#include <volk.c>
