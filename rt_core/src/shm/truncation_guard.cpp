// The SIGBUS handler behind guarded channel mappings.
#include "truncation_guard.hpp"

#include <signal.h>
#include <sys/mman.h>

#include <atomic>
#include <cstdint>
#include <mutex>

namespace hapfluid::shm::detail {
namespace {

// A process maps a handful of channels (haptic-render: 2; haptic-rt: up to 4 during a re-attach).
constexpr int kGuards = 64;

struct Guard {
  std::atomic<std::uintptr_t> base{0};  // 0: free; stored last when taken, cleared first when freed
  std::atomic<std::size_t> bytes{0};
  std::atomic<int> prot{0};
  std::atomic<bool> truncated{false};
};
Guard g_guards[kGuards];
std::mutex g_install_mutex;  // guards are taken and freed outside the real-time loop
bool g_installed = false;
struct sigaction g_previous {};

void forward_to_previous(int signal, siginfo_t* info, void* context) {
  if (g_previous.sa_flags & SA_SIGINFO) {
    if (g_previous.sa_sigaction) return g_previous.sa_sigaction(signal, info, context);
  } else if (g_previous.sa_handler != SIG_DFL && g_previous.sa_handler != SIG_IGN) {
    return g_previous.sa_handler(signal);
  }
  // Default action: restore it; the faulting access runs again and the process dies as before.
  ::sigaction(SIGBUS, &g_previous, nullptr);
}

void on_sigbus(int signal, siginfo_t* info, void* context) {
  const auto address = reinterpret_cast<std::uintptr_t>(info->si_addr);
  for (Guard& g : g_guards) {
    const std::uintptr_t base = g.base.load(std::memory_order_acquire);
    const std::size_t bytes = g.bytes.load(std::memory_order_relaxed);
    if (base == 0 || address < base || address - base >= bytes) continue;
    // mmap is a plain system call (no lock, no allocation), safe here in practice.
    void* p = ::mmap(reinterpret_cast<void*>(base), bytes, g.prot.load(std::memory_order_relaxed),
                     MAP_PRIVATE | MAP_ANONYMOUS | MAP_FIXED, -1, 0);
    if (p == MAP_FAILED) break;
    g.truncated.store(true, std::memory_order_release);
    return;
  }
  forward_to_previous(signal, info, context);
}

}  // namespace

int guard_mapping(const std::byte* base, std::size_t bytes, int prot) {
  std::lock_guard<std::mutex> lock(g_install_mutex);
  if (!g_installed) {
    struct sigaction action {};
    action.sa_sigaction = on_sigbus;
    action.sa_flags = SA_SIGINFO | SA_RESTART;
    sigemptyset(&action.sa_mask);
    if (::sigaction(SIGBUS, &action, &g_previous) != 0) return -1;
    g_installed = true;
  }
  for (int i = 0; i < kGuards; ++i) {
    Guard& g = g_guards[i];
    if (g.base.load(std::memory_order_relaxed) != 0) continue;
    g.bytes.store(bytes, std::memory_order_relaxed);
    g.prot.store(prot, std::memory_order_relaxed);
    g.truncated.store(false, std::memory_order_relaxed);
    g.base.store(reinterpret_cast<std::uintptr_t>(base), std::memory_order_release);
    return i;
  }
  return -1;
}

void unguard_mapping(int guard) {
  if (guard < 0 || guard >= kGuards) return;
  std::lock_guard<std::mutex> lock(g_install_mutex);
  g_guards[guard].base.store(0, std::memory_order_release);
}

bool mapping_truncated(int guard) {
  if (guard < 0 || guard >= kGuards) return false;
  return g_guards[guard].truncated.load(std::memory_order_acquire);
}

}  // namespace hapfluid::shm::detail
