// The counting replacements and the seccomp watch of thread_counters.hpp.
#include "thread_counters.hpp"

#include <dlfcn.h>
#include <linux/audit.h>
#include <linux/filter.h>
#include <linux/seccomp.h>
#include <poll.h>
#include <pthread.h>
#include <sys/ioctl.h>
#include <sys/prctl.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <cerrno>
#include <cstddef>
#include <cstdlib>
#include <cstring>
#include <new>

extern "C" void* __libc_malloc(size_t);
extern "C" void* __libc_calloc(size_t, size_t);
extern "C" void* __libc_realloc(void*, size_t);
extern "C" void __libc_free(void*);

namespace {
thread_local bool t_counting = false;
std::atomic<long> g_allocations{0};
std::atomic<long> g_locks{0};
void count_allocation() {
  if (t_counting) g_allocations.fetch_add(1, std::memory_order_relaxed);
}
void count_lock() {
  if (t_counting) g_locks.fetch_add(1, std::memory_order_relaxed);
}
template <class Fn>
Fn next_symbol(const char* name) {
  return reinterpret_cast<Fn>(dlsym(RTLD_NEXT, name));
}
}  // namespace

extern "C" {
void* malloc(size_t n) {
  count_allocation();
  return __libc_malloc(n);
}
void* calloc(size_t a, size_t b) {
  count_allocation();
  return __libc_calloc(a, b);
}
void* realloc(void* p, size_t n) {
  count_allocation();
  return __libc_realloc(p, n);
}
void free(void* p) { __libc_free(p); }
int pthread_mutex_lock(pthread_mutex_t* m) {
  static auto real = next_symbol<int (*)(pthread_mutex_t*)>("pthread_mutex_lock");
  count_lock();
  return real(m);
}
int pthread_mutex_trylock(pthread_mutex_t* m) {
  static auto real = next_symbol<int (*)(pthread_mutex_t*)>("pthread_mutex_trylock");
  count_lock();
  return real(m);
}
int pthread_rwlock_rdlock(pthread_rwlock_t* l) {
  static auto real = next_symbol<int (*)(pthread_rwlock_t*)>("pthread_rwlock_rdlock");
  count_lock();
  return real(l);
}
int pthread_rwlock_wrlock(pthread_rwlock_t* l) {
  static auto real = next_symbol<int (*)(pthread_rwlock_t*)>("pthread_rwlock_wrlock");
  count_lock();
  return real(l);
}
}

void* operator new(std::size_t n) {
  count_allocation();
  if (void* p = __libc_malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t n) { return operator new(n); }
void operator delete(void* p) noexcept { __libc_free(p); }
void operator delete[](void* p) noexcept { __libc_free(p); }
void operator delete(void* p, std::size_t) noexcept { __libc_free(p); }
void operator delete[](void* p, std::size_t) noexcept { __libc_free(p); }

namespace hapfluid::counters {

void count_on_this_thread(bool on) { t_counting = on; }
long allocations() { return g_allocations.load(); }
long locks() { return g_locks.load(); }
void reset_counts() {
  g_allocations.store(0);
  g_locks.store(0);
}

namespace {

#if defined(__x86_64__)
constexpr std::uint32_t kArch = AUDIT_ARCH_X86_64;
#elif defined(__aarch64__)
constexpr std::uint32_t kArch = AUDIT_ARCH_AARCH64;
#else
#error "thread_counters: add this architecture's AUDIT_ARCH value"
#endif

const char* syscall_name(long nr) {
  switch (nr) {
#define NAME(n) \
  case SYS_##n: return #n;
    NAME(read) NAME(write) NAME(ioctl) NAME(ppoll) NAME(futex) NAME(recvfrom) NAME(sendto) NAME(recvmsg)
    NAME(sendmsg) NAME(openat) NAME(close) NAME(nanosleep) NAME(mmap) NAME(munmap) NAME(epoll_pwait)
    NAME(pselect6) NAME(sched_yield) NAME(getpid) NAME(gettid) NAME(rt_sigprocmask) NAME(readv) NAME(writev)
#if defined(SYS_poll)
    NAME(poll) NAME(select) NAME(epoll_wait)
#endif
#undef NAME
    default: return nullptr;
  }
}

}  // namespace

SyscallWatch::SyscallWatch() : supervisor_([this] { supervise(); }) {}

SyscallWatch::~SyscallWatch() {
  stop_.store(true);
  supervisor_.join();
  if (listener_.load() >= 0) ::close(listener_.load());
}

bool SyscallWatch::watch_this_thread(std::string& why, const std::vector<std::string>& allowed) {
  std::vector<std::uint32_t> pass = {SYS_clock_nanosleep, SYS_clock_gettime};
  for (const std::string& name : allowed) {
    long nr = 0;
    while (nr < kSyscalls && (!syscall_name(nr) || name != syscall_name(nr))) ++nr;
    if (nr == kSyscalls) {
      why = "unknown system call name '" + name + "'";
      return false;
    }
    pass.push_back(static_cast<std::uint32_t>(nr));
  }
  if (prctl(PR_SET_NO_NEW_PRIVS, 1, 0, 0, 0) != 0) {
    why = std::string("prctl(PR_SET_NO_NEW_PRIVS): ") + std::strerror(errno);
    return false;
  }
  // Other architectures pass; on ours every call but those in `pass` goes to the supervisor.
  std::vector<sock_filter> filter = {
      BPF_STMT(BPF_LD | BPF_W | BPF_ABS, offsetof(seccomp_data, arch)),
      BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, kArch, 1, 0),
      BPF_STMT(BPF_RET | BPF_K, SECCOMP_RET_ALLOW),
      BPF_STMT(BPF_LD | BPF_W | BPF_ABS, offsetof(seccomp_data, nr)),
  };
  for (std::size_t i = 0; i < pass.size(); ++i)  // a match jumps over the rest to the final ALLOW
    filter.push_back(BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, pass[i], static_cast<std::uint8_t>(pass.size() - i), 0));
  filter.push_back(BPF_STMT(BPF_RET | BPF_K, SECCOMP_RET_USER_NOTIF));
  filter.push_back(BPF_STMT(BPF_RET | BPF_K, SECCOMP_RET_ALLOW));
  sock_fprog program{static_cast<unsigned short>(filter.size()), filter.data()};
  const long fd = syscall(SYS_seccomp, SECCOMP_SET_MODE_FILTER, SECCOMP_FILTER_FLAG_NEW_LISTENER, &program);
  if (fd < 0) {
    why = std::string("seccomp(SECCOMP_SET_MODE_FILTER, NEW_LISTENER): ") + std::strerror(errno);
    return false;
  }
  listener_.store(static_cast<int>(fd));
  return true;
}

void SyscallWatch::supervise() {
  while (!stop_.load()) {
    const int fd = listener_.load();
    pollfd p{fd, POLLIN, 0};
    if (fd < 0 || ::poll(&p, 1, 50) <= 0 || !(p.revents & POLLIN)) {
      if (fd < 0 || (p.revents & (POLLHUP | POLLERR | POLLNVAL))) {  // not watching yet, or the thread is gone
        timespec nap{0, 5'000'000};
        nanosleep(&nap, nullptr);
      }
      continue;
    }
    seccomp_notif request;
    std::memset(&request, 0, sizeof request);
    if (ioctl(fd, SECCOMP_IOCTL_NOTIF_RECV, &request) != 0) continue;
    if (counting_.load() && request.data.nr >= 0 && request.data.nr < kSyscalls) counts_[request.data.nr].fetch_add(1);
    seccomp_notif_resp response;
    std::memset(&response, 0, sizeof response);
    response.id = request.id;
    response.flags = SECCOMP_USER_NOTIF_FLAG_CONTINUE;
    ioctl(fd, SECCOMP_IOCTL_NOTIF_SEND, &response);
  }
}

long SyscallWatch::total() const {
  long n = 0;
  for (const auto& c : counts_) n += c.load();
  return n;
}

std::string SyscallWatch::summary() const {
  std::string out;
  for (int nr = 0; nr < kSyscalls; ++nr) {
    const long n = counts_[nr].load();
    if (!n) continue;
    const char* name = syscall_name(nr);
    if (!out.empty()) out += ", ";
    out += (name ? std::string(name) : "syscall " + std::to_string(nr)) + " " + std::to_string(n);
  }
  return out;
}

}  // namespace hapfluid::counters
