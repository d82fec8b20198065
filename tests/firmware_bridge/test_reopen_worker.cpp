// ReopenWorker (reopen_worker.hpp): how the SocketCAN, libusb and hidapi transports get an
// unplugged device back, or find one absent at start, without the 1 kHz loop ever blocking on an
// open. Exercised with a fake handle; the real replug and late appearance are tested in the QEMU
// suite (tests/hil-kernel, t_41, t_50 and t_60).
#include <gtest/gtest.h>
#include <time.h>

#include <atomic>
#include <set>

#include "hapfluid/device/reopen_worker.hpp"

using hapfluid::device::OpenAttempt;
using hapfluid::device::ReopenWorker;

namespace {

struct FakeHandle {
  int id;
};

// The "device": absent until `present`, then each open gives a new handle.
struct FakeBus {
  std::atomic<bool> present{false};
  std::atomic<int> opens_tried{0}, next_id{1};
  std::atomic<int> closed_mask{0};  // bit id: handle `id` was closed
  FakeHandle* open() {
    ++opens_tried;
    return present ? new FakeHandle{next_id++} : nullptr;
  }
  void close(FakeHandle* h) {
    closed_mask |= 1 << h->id;
    delete h;
  }
};

void nap_ms(int ms) {
  timespec t{0, ms * 1'000'000L};
  nanosleep(&t, nullptr);
}

// Polls take() as the loop would (every ms), for at most 2 s.
FakeHandle* take_within_2s(ReopenWorker<FakeHandle>& w) {
  for (int ms = 0; ms < 2000; ++ms) {
    if (FakeHandle* h = w.take()) return h;
    nap_ms(1);
  }
  return nullptr;
}

}  // namespace

TEST(ReopenWorker, IdlesUntilADeviceIsLost) {
  FakeBus bus;
  bus.present = true;
  ReopenWorker<FakeHandle> w("fake", [&](OpenAttempt&) { return bus.open(); }, [&](FakeHandle* h) { bus.close(h); }, 10);
  nap_ms(30);
  EXPECT_EQ(bus.opens_tried, 0) << "nothing is reopened while the device works";
  EXPECT_EQ(w.take(), nullptr);
}

TEST(ReopenWorker, ClosesTheDeadHandleAndRetriesUntilTheDeviceIsBack) {
  FakeBus bus;
  ReopenWorker<FakeHandle> w("fake", [&](OpenAttempt&) { return bus.open(); }, [&](FakeHandle* h) { bus.close(h); }, 10);
  w.retire(new FakeHandle{0});  // the unplugged device's handle
  for (int ms = 0; ms < 2000 && bus.opens_tried < 3; ++ms) nap_ms(1);
  EXPECT_GE(bus.opens_tried, 3) << "retries while the device is away";
  EXPECT_EQ(bus.closed_mask & 1, 1) << "the dead handle is closed by the worker, not the loop";
  EXPECT_EQ(w.take(), nullptr);
  EXPECT_TRUE(w.reopening());
  bus.present = true;  // replugged
  FakeHandle* h = take_within_2s(w);
  ASSERT_NE(h, nullptr);
  EXPECT_EQ(h->id, 1);
  EXPECT_FALSE(w.reopening());
  const int tried = bus.opens_tried;
  nap_ms(30);
  EXPECT_EQ(bus.opens_tried, tried) << "back to idle once the device was reopened";
  EXPECT_EQ(w.take(), nullptr) << "a handle is handed over once";
  // A second unplug works the same way.
  w.retire(h);
  FakeHandle* again = take_within_2s(w);
  ASSERT_NE(again, nullptr);
  EXPECT_EQ(again->id, 2);
  EXPECT_TRUE(bus.closed_mask & (1 << 1));
  bus.close(again);
}

TEST(ReopenWorker, StopsPromptlyAndClosesWhatTheLoopNeverTook) {
  FakeBus bus;
  timespec t0, t1;
  {
    ReopenWorker<FakeHandle> w("fake", [&](OpenAttempt&) { return bus.open(); }, [&](FakeHandle* h) { bus.close(h); }, 10'000);
    w.retire(nullptr);  // reopening, with a 10 s retry period: the destructor must not wait for it
    for (int ms = 0; ms < 2000 && bus.opens_tried < 1; ++ms) nap_ms(1);
    clock_gettime(CLOCK_MONOTONIC, &t0);
  }
  clock_gettime(CLOCK_MONOTONIC, &t1);
  EXPECT_EQ(bus.opens_tried, 1);
  // Not a speed figure: a worker that sat out its retry period would take 10 s; half is the bound.
  EXPECT_LT(t1.tv_sec - t0.tv_sec, 5) << "closing a transport waited for the reopen period";
  {
    ReopenWorker<FakeHandle> w("fake", [&](OpenAttempt&) { return bus.open(); }, [&](FakeHandle* h) { bus.close(h); }, 10);
    bus.present = true;
    w.retire(nullptr);
    for (int ms = 0; ms < 2000 && bus.opens_tried < 2; ++ms) nap_ms(1);
    nap_ms(5);
  }  // reopened but never taken: closed, not leaked
  EXPECT_TRUE(bus.closed_mask & (1 << 1));
}

TEST(ReopenWorker, ADeviceAbsentAtTheFirstOpenIsSearchedForUntilItAppears) {
  // A rig's services start at boot, before the arm is powered: the transport's constructor gets
  // nothing back and reports a link fault; the worker keeps looking and hands the device over.
  FakeBus bus;
  ReopenWorker<FakeHandle> w("fake", [&](OpenAttempt&) { return bus.open(); }, [&](FakeHandle* h) { bus.close(h); }, 10);
  OpenAttempt attempt;
  EXPECT_EQ(w.first_open(attempt), nullptr);
  EXPECT_EQ(attempt.failure, hapfluid::device::OpenFailure::absent);
  for (int ms = 0; ms < 2000 && bus.opens_tried < 3; ++ms) nap_ms(1);
  EXPECT_GE(bus.opens_tried, 3) << "the worker searches on its own thread";
  EXPECT_TRUE(w.reopening());
  bus.present = true;  // powered on, enumerated
  FakeHandle* h = take_within_2s(w);
  ASSERT_NE(h, nullptr);
  EXPECT_FALSE(w.reopening());
  bus.close(h);
}

TEST(ReopenWorker, APermanentFailureAtTheFirstOpenIsLeftToTheCallerAndNotSearched) {
  // No permission, not a device of that kind: the constructor throws and haptic-rt exits 2;
  // searching in the background would hide the cause behind a link fault.
  FakeBus bus;
  ReopenWorker<FakeHandle> w("fake",
                             [&](OpenAttempt& a) {
                               ++bus.opens_tried;
                               a = {hapfluid::device::OpenFailure::permanent, "Permission denied"};
                               return static_cast<FakeHandle*>(nullptr);
                             },
                             [&](FakeHandle* h) { bus.close(h); }, 10);
  OpenAttempt attempt;
  EXPECT_EQ(w.first_open(attempt), nullptr);
  EXPECT_EQ(attempt.why, "Permission denied");
  nap_ms(30);
  EXPECT_EQ(bus.opens_tried, 1) << "no search";
  EXPECT_FALSE(w.reopening());
}

TEST(ReopenWorker, APresentDeviceOpensOnTheCallingThreadAndIsNotSearchedFor) {
  FakeBus bus;
  bus.present = true;
  ReopenWorker<FakeHandle> w("fake", [&](OpenAttempt&) { return bus.open(); }, [&](FakeHandle* h) { bus.close(h); }, 10);
  OpenAttempt attempt;
  FakeHandle* h = w.first_open(attempt);
  ASSERT_NE(h, nullptr);
  nap_ms(30);
  EXPECT_EQ(bus.opens_tried, 1);
  EXPECT_EQ(w.take(), nullptr);
  bus.close(h);
}
