// A CPU solver step allocates nothing once the scene's neighbourhoods have been seen: the
// neighbour lists, pair lists and fields are sized at construction or grow in the first steps,
// then every step reuses them. This binary replaces malloc & co. and operator new with counting
// versions (on every thread: the solver's workers allocate as much as its caller could), warms a
// scene with a fluid, walls and a floating body up for a while, then counts over further steps.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <new>

#include "test_support.hpp"

extern "C" void* __libc_malloc(size_t);
extern "C" void* __libc_calloc(size_t, size_t);
extern "C" void* __libc_realloc(void*, size_t);
extern "C" void __libc_free(void*);

namespace {
std::atomic<bool> g_counting{false};
std::atomic<long> g_allocations{0};
void count_allocation() {
  if (g_counting.load(std::memory_order_relaxed)) g_allocations.fetch_add(1, std::memory_order_relaxed);
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

using namespace hapfluid::sim;

namespace {

// A tank with a floating ball: fluid, wall and body neighbours, two-way coupling, contacts.
hapfluid::config::Scene tank_with_a_ball(const char* method) {
  const auto dir = test::temp_dir(std::string("alloc_") + method);
  std::string extra = std::string(method) == "dfsph" ? "solver = \"dfsph\"\nsettle_s = 0.05\n"
                                                     : "solver = \"wcsph\"\nspeed_of_sound_m_s = 12.0\n";
  return test::write_scene(dir, R"(name = "alloc"
[domain]
min_m = [0.0, 0.0, 0.0]
max_m = [0.12, 0.12, 0.16]
[fluid]
particle_spacing_m = 0.01
viscosity_pa_s = 0.01
)" + extra + R"([[fluid.blocks]]
min_m = [0.0, 0.0, 0.0]
max_m = [0.12, 0.12, 0.08]
[[bodies]]
name = "ball"
mesh = "ball.obj"
position_m = [0.06, 0.06, 0.09]
density_kg_m3 = 500.0
[time]
cfl = 0.3
)", {{"ball.obj", test::sphere_mesh(0.025, 2)}});
}

long allocations_per_steps(Solver& solver, int warm_steps, int counted_steps) {
  for (int k = 0; k < warm_steps; ++k) solver.step(solver.stable_time_step());
  g_allocations = 0;
  g_counting = true;
  for (int k = 0; k < counted_steps; ++k) solver.step(solver.stable_time_step());
  g_counting = false;
  return g_allocations.load();
}

}  // namespace

TEST(StepAllocations, CountersSeeAnAllocationOnAWorkerThread) {
  // The counter is live on every thread (a test of this test).
  g_allocations = 0;
  g_counting = true;
  ThreadPool pool(2);
  pool.parallel_for(2, [](std::size_t, std::size_t, int) { delete new int(1); });
  g_counting = false;
  EXPECT_GE(g_allocations.load(), 2);
}

TEST(StepAllocations, NeitherCpuMethodAllocatesInAStepOnceWarm) {
  for (const char* method : {"wcsph", "dfsph"}) {
    auto solver = make_cpu_solver(build_model(tank_with_a_ball(method)), 2);
    ASSERT_STREQ(solver->method(), method);
    EXPECT_EQ(allocations_per_steps(*solver, 40, 40), 0) << method;
  }
}
