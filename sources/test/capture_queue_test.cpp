// The live sources' hand-over queue (CameraSource, AlsaAudioSource): drop-oldest when full, a
// waiting consumer woken by the capture thread, the capture error reported once, then the end.

#include "../src/capture_queue.hpp"

#include <gtest/gtest.h>

#include <thread>

namespace dreamsense::sources::detail {
namespace {

FramePtr frame(uint64_t sequence) {
  return make_frame("mic", Timestamp::from_ns(static_cast<int64_t>(sequence) * 1000), sequence,
                    AudioChunk{});
}

TEST(CaptureQueue, DropsTheOldestWhenTheConsumerFallsBehind) {
  CaptureQueue q(2);
  EXPECT_EQ(q.push(frame(0)), 0u);
  EXPECT_EQ(q.push(frame(1)), 0u);
  EXPECT_EQ(q.push(frame(2)), 1u);  // frame 0 goes
  auto a = q.pop("mic: capture stopped");
  ASSERT_TRUE(a);
  EXPECT_EQ((*a)->sequence, 1u);
  auto b = q.pop("mic: capture stopped");
  ASSERT_TRUE(b);
  EXPECT_EQ((*b)->sequence, 2u);
}

TEST(CaptureQueue, AWaitingConsumerGetsTheFrameThenTheErrorOnceThenTheEnd) {
  CaptureQueue q(4);
  std::thread producer([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    q.push(frame(7));
    q.finish(Error{ErrorCode::kIoError, "device unplugged"});
  });
  auto f = q.pop("audio 'mic': capture stopped");  // blocks until the producer delivers
  producer.join();
  ASSERT_TRUE(f);
  EXPECT_EQ((*f)->sequence, 7u);
  auto e = q.pop("audio 'mic': capture stopped");
  ASSERT_FALSE(e);
  EXPECT_EQ(e.error().code, ErrorCode::kIoError);
  EXPECT_EQ(e.error().message, "device unplugged");
  auto end = q.pop("audio 'mic': capture stopped");
  ASSERT_FALSE(end);
  EXPECT_EQ(end.error().code, ErrorCode::kEndOfStream);
  EXPECT_EQ(end.error().message, "audio 'mic': capture stopped");
}

TEST(CaptureQueue, StoppedWithoutErrorIsJustTheEnd) {
  CaptureQueue q(1);
  q.finish(std::nullopt);
  auto end = q.pop("camera 'c': capture stopped");
  ASSERT_FALSE(end);
  EXPECT_EQ(end.error().code, ErrorCode::kEndOfStream);
}

}  // namespace
}  // namespace dreamsense::sources::detail
