// The hand-off between the 1 kHz loop and a transport's I/O thread (frame_handoff.hpp): frames
// in order while the consumer keeps up, the newest once it fell a whole ring behind (a stale
// command is worth less than the one computed since), never a frame read half overwritten.
#include <gtest/gtest.h>

#include <atomic>
#include <thread>

#include "hapfluid/device/frame_handoff.hpp"

namespace {

using namespace hapfluid::device;

WireFrame numbered(std::uint32_t n) {
  WireFrame f;
  f.can_id = n;
  f.length = 64;
  for (int i = 0; i < 64; ++i) f.data[i] = static_cast<std::uint8_t>(n + i);
  return f;
}

// Every byte follows from can_id: a frame mixed from two writes fails this.
bool whole(const WireFrame& f) {
  if (f.length != 64) return false;
  for (int i = 0; i < 64; ++i)
    if (f.data[i] != static_cast<std::uint8_t>(f.can_id + i)) return false;
  return true;
}

TEST(FrameRing, DeliversEveryFrameInOrderWhileTheConsumerKeepsUp) {
  FrameRing<4> ring;
  WireFrame out;
  EXPECT_FALSE(ring.pop(out)) << "nothing pushed yet";
  for (std::uint32_t n = 0; n < 4; ++n) ring.push(numbered(n));  // a whole ring behind, not lapped
  for (std::uint32_t n = 0; n < 4; ++n) {
    ASSERT_TRUE(ring.pop(out));
    EXPECT_EQ(out.can_id, n);
    EXPECT_TRUE(whole(out));
  }
  EXPECT_FALSE(ring.pop(out));
  EXPECT_EQ(ring.dropped(), 0u);
}

TEST(FrameRing, AConsumerThatWasLappedGetsTheNewestFrameNotABacklog) {
  // A device that took no transfer for 20 ms while the loop sent a command every 1 ms: what it
  // gets next is the newest command; the 19 older ones are gone and counted.
  FrameRing<4> ring;
  for (std::uint32_t n = 0; n < 20; ++n) ring.push(numbered(n));
  WireFrame out;
  ASSERT_TRUE(ring.pop(out));
  EXPECT_EQ(out.can_id, 19u);
  EXPECT_TRUE(whole(out));
  EXPECT_EQ(ring.dropped(), 19u);
  EXPECT_FALSE(ring.pop(out));
  ring.push(numbered(20));  // and in order again from there
  ASSERT_TRUE(ring.pop(out));
  EXPECT_EQ(out.can_id, 20u);
}

TEST(FrameRing, DiscardForgetsWhatWasNotTaken) {
  FrameRing<4> ring;
  ring.push(numbered(1));
  ring.push(numbered(2));
  ring.discard();
  WireFrame out;
  EXPECT_FALSE(ring.pop(out));
  EXPECT_EQ(ring.dropped(), 2u);
  ring.push(numbered(3));
  ASSERT_TRUE(ring.pop(out));
  EXPECT_EQ(out.can_id, 3u);
}

TEST(FrameRing, ConcurrentProducerAndConsumerNeverTearAFrameNorGoBackwards) {
  // The producer overwrites slots the consumer may be copying; the stamps must catch every such
  // copy. 200000 frames through a 4-frame ring with a consumer that keeps falling behind.
  constexpr std::uint32_t kFrames = 200'000;
  FrameRing<4> ring;
  std::atomic<bool> done{false};
  std::thread producer([&] {
    for (std::uint32_t n = 1; n <= kFrames; ++n) ring.push(numbered(n));
    done.store(true);
  });
  std::uint64_t taken = 0, torn = 0, backwards = 0;
  std::uint32_t last = 0;
  WireFrame out;
  for (;;) {
    const bool finished = done.load();
    while (ring.pop(out)) {
      ++taken;
      if (!whole(out)) ++torn;
      if (out.can_id <= last) ++backwards;
      last = out.can_id;
    }
    if (finished) break;
  }
  producer.join();
  EXPECT_EQ(torn, 0u);
  EXPECT_EQ(backwards, 0u);
  EXPECT_EQ(last, kFrames) << "the newest frame always arrives";
  EXPECT_EQ(taken + ring.dropped(), kFrames) << "every frame is either taken or counted as dropped";
}

// A transport built on the hand-off, driven from both sides as its I/O thread and the loop would.
class Handoff final : public HandoffTransport {
 public:
  std::string describe() const override { return "hand-off under test"; }
  using HandoffTransport::discard_unsent;
  using HandoffTransport::lower;
  using HandoffTransport::next_to_send;
  using HandoffTransport::raise;
  using HandoffTransport::received;
  using HandoffTransport::reconnected;
};

TEST(HandoffTransport, CommandsAreRefusedWhileDisconnectedAndFlowOnceTheDeviceIsBack) {
  Handoff t;
  t.raise(kDisconnected);
  EXPECT_EQ(t.send(numbered(1)), Io::error) << "a command queued now would be stale when the device is back";
  WireFrame out;
  EXPECT_EQ(t.receive(out), Io::error);
  EXPECT_FALSE(t.next_to_send(out));
  t.clear_error_flags();
  EXPECT_TRUE(t.error_flags() & kDisconnected) << "disconnected is the link's state, not an event to clear";
  t.reconnected();
  t.lower(kDisconnected);
  EXPECT_EQ(t.reconnects(), 1u);
  EXPECT_EQ(t.send(numbered(2)), Io::ok);
  ASSERT_TRUE(t.next_to_send(out));
  EXPECT_EQ(out.can_id, 2u);
  EXPECT_EQ(t.receive(out), Io::empty);
  t.received(numbered(3));
  ASSERT_EQ(t.receive(out), Io::ok);
  EXPECT_EQ(out.can_id, 3u);
}

TEST(HandoffTransport, SupersededCommandsAndAStalledLoopAreReported) {
  Handoff t;
  for (std::uint32_t n = 0; n < 10; ++n) t.send(numbered(n));  // a device that took none of them
  WireFrame out;
  ASSERT_TRUE(t.next_to_send(out));
  EXPECT_EQ(out.can_id, 9u);
  EXPECT_TRUE(t.error_flags() & kTxFailed) << "commands the device never got are transmit failures";
  EXPECT_FALSE(t.error_flags() & kRxOverflow);
  for (std::uint32_t n = 0; n < kReceiveRingFrames + 5; ++n) t.received(numbered(n));  // the loop stalled
  ASSERT_EQ(t.receive(out), Io::ok);
  EXPECT_EQ(out.can_id, kReceiveRingFrames + 4);
  EXPECT_TRUE(t.error_flags() & kRxOverflow);
  t.send(numbered(11));
  t.discard_unsent();
  EXPECT_FALSE(t.next_to_send(out)) << "discarded: queued for a connection that was lost";
}

}  // namespace
