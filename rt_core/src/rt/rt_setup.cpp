#include "hapfluid/rt/rt_setup.hpp"

#include <malloc.h>
#include <sched.h>
#include <sys/mman.h>
#include <sys/resource.h>
#include <unistd.h>

#include <sys/syscall.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>

namespace hapfluid::rt {

bool kernel_is_preempt_rt() {
  std::ifstream f("/sys/kernel/realtime");
  int value = 0;
  return f && (f >> value) && value == 1;
}

void prefault_stack(std::size_t bytes) {
  // A volatile buffer the compiler cannot elide; touching one byte per page is enough.
  volatile unsigned char* buffer = static_cast<volatile unsigned char*>(alloca(bytes));
  for (std::size_t i = 0; i < bytes; i += 4096) buffer[i] = 0;
}

void prefault_heap(std::size_t bytes) {
  // Freed memory stays in the process (no trim), and large blocks come from the heap, not mmap.
  mallopt(M_TRIM_THRESHOLD, -1);
  mallopt(M_MMAP_MAX, 0);
  auto* block = static_cast<volatile unsigned char*>(malloc(bytes));
  if (!block) return;
  for (std::size_t i = 0; i < bytes; i += 4096) block[i] = 0;
  free(const_cast<unsigned char*>(block));
}

int keep_other_threads_off_cpu(int cpu) {
  long cpus = sysconf(_SC_NPROCESSORS_ONLN);
  if (cpu < 0 || cpus < 2) return 0;
  cpu_set_t others;
  CPU_ZERO(&others);
  for (long c = 0; c < cpus && c < CPU_SETSIZE; ++c)
    if (c != cpu) CPU_SET(c, &others);
  const long self = syscall(SYS_gettid);
  int moved = 0;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator("/proc/self/task", ec)) {
    long tid = std::strtol(entry.path().filename().c_str(), nullptr, 10);
    if (tid > 0 && tid != self && sched_setaffinity(static_cast<pid_t>(tid), sizeof others, &others) == 0) ++moved;
  }
  return moved;
}

RtSetupReport setup_realtime(const config::RtSettings& rt) {
  RtSetupReport r;
  auto fail = [&](std::uint32_t flag, const std::string& what) {
    r.degraded_flags |= flag;
    r.messages += what + "\n";
  };

  if (mlockall(MCL_CURRENT | MCL_FUTURE) != 0) {
    int e = errno;
    rlimit lim{};
    getrlimit(RLIMIT_MEMLOCK, &lim);
    fail(loop_no_mlock, std::string("mlockall failed: ") + std::strerror(e) +
                            (e == ENOMEM || e == EPERM
                                 ? " (RLIMIT_MEMLOCK is " + std::to_string(lim.rlim_cur) +
                                       " bytes: set LimitMEMLOCK=infinity in the unit, or memlock in "
                                       "/etc/security/limits.conf, or grant CAP_IPC_LOCK)"
                                 : ""));
  }

  sched_param param{};
  param.sched_priority = rt.priority;
  if (sched_setscheduler(0, SCHED_FIFO, &param) != 0) {
    int e = errno;
    rlimit lim{};
    getrlimit(RLIMIT_RTPRIO, &lim);
    fail(loop_no_fifo, "SCHED_FIFO priority " + std::to_string(rt.priority) + " refused: " + std::strerror(e) +
                           (e == EPERM ? " (RLIMIT_RTPRIO is " + std::to_string(lim.rlim_cur) +
                                             ": set LimitRTPRIO=" + std::to_string(rt.priority) +
                                             " in the unit, rtprio in /etc/security/limits.conf, or grant "
                                             "CAP_SYS_NICE; in a container also check the runtime's rt limits)"
                                       : e == EINVAL ? " (priority out of range for this kernel)" : ""));
  }

  if (rt.cpu >= 0) {
    cpu_set_t set;
    CPU_ZERO(&set);
    CPU_SET(rt.cpu, &set);
    if (sched_setaffinity(0, sizeof set, &set) != 0) {
      int e = errno;
      fail(loop_no_affinity, "pinning to CPU " + std::to_string(rt.cpu) + " failed: " + std::strerror(e) +
                                 (e == EINVAL ? " (that CPU is offline, absent, or outside this cgroup's "
                                                "cpuset; this machine has " +
                                                    std::to_string(sysconf(_SC_NPROCESSORS_ONLN)) + " online)"
                                              : ""));
    }
  }

  if (!kernel_is_preempt_rt()) {
    r.degraded_flags |= loop_not_preempt_rt;
    r.messages += "kernel is not PREEMPT_RT (/sys/kernel/realtime absent or 0): expect occasional wake-up "
                  "latencies of hundreds of microseconds; use a PREEMPT_RT kernel on a rig\n";
  }
  r.refused = rt.policy == config::RtPolicy::enforce && (r.degraded_flags & kDegradedMask) != 0;
  return r;
}

}  // namespace hapfluid::rt
