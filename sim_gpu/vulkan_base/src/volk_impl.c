// volk ships as source in Debian's libvulkan-volk-dev: its loader is compiled once, here.
#include <volk.c>
