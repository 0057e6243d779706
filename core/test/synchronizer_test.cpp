#include "dreamsense/core/synchronizer.hpp"

#include <gtest/gtest.h>

namespace dreamsense {
namespace {

FramePtr skel(const std::string& id, int64_t ms, uint64_t seq = 0) {
  return make_frame(id, Timestamp::from_ns(ms * 1'000'000), seq, Skeleton{});
}
FramePtr audio(const std::string& id, int64_t ms) {
  AudioChunk c;
  c.samples.assign(640, 0.f);
  return make_frame(id, Timestamp::from_ns(ms * 1'000'000), 0, std::move(c));
}
int64_t ms(Timestamp t) { return t.ns() / 1'000'000; }

SynchronizerOptions settled_options() {
  SynchronizerOptions o;
  o.start = Timestamp::from_ns(0);
  return o;
}

TEST(SynchronizerSettled, WaitsUntilEveryStreamPassedTheTick) {
  Synchronizer sync(settled_options(), {{"a"}, {"b"}});
  ASSERT_TRUE(sync.push(skel("a", 0)));
  ASSERT_TRUE(sync.push(skel("a", 40)));
  EXPECT_TRUE(sync.poll().empty()) << "b has not delivered anything: tick 0 is not settled";
  ASSERT_TRUE(sync.push(skel("b", 5)));
  EXPECT_TRUE(sync.poll().empty()) << "b could still deliver a frame nearer to tick 0";
  ASSERT_TRUE(sync.push(skel("b", 38)));
  auto out = sync.poll();
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(ms(out[0].stamp), 0);
  EXPECT_EQ(ms(out[0].frame("a")->stamp), 0);
  EXPECT_EQ(ms(out[0].frame("b")->stamp), 5);
}

TEST(SynchronizerSettled, MatchesNearestWithinToleranceAtDifferentRates) {
  // 30 Hz stream on a 25 Hz clock: every tick gets the nearest frame, ~1 in 6 frames is unused.
  Synchronizer sync(settled_options(), {{"cam"}, {"kinect"}});
  for (int i = 0; i < 25; ++i) ASSERT_TRUE(sync.push(skel("cam", i * 40)));
  for (int i = 0; i < 30; ++i) ASSERT_TRUE(sync.push(skel("kinect", i * 1000 / 30)));
  sync.end_all();
  auto out = sync.poll();
  ASSERT_EQ(out.size(), 25u);
  for (const auto& mf : out) {
    ASSERT_TRUE(mf.frame("cam"));
    ASSERT_TRUE(mf.frame("kinect")) << "tick " << ms(mf.stamp);
    EXPECT_LE(std::abs(ms(mf.frame("kinect")->stamp) - ms(mf.stamp)), 17);
  }
  EXPECT_TRUE(sync.finished());
  const auto& st = sync.stats().streams.at("kinect");
  EXPECT_EQ(st.received, 30u);
  EXPECT_EQ(st.delivered + st.unmatched, 30u);
  EXPECT_EQ(st.dropped, 0u) << "settled replay never drops";
  EXPECT_EQ(sync.stats().dropped_frames(), 0u);
}

TEST(SynchronizerSettled, ResultDoesNotDependOnArrivalInterleaving) {
  auto run = [](bool a_first) {
    Synchronizer sync(settled_options(), {{"a"}, {"b"}});
    std::vector<std::pair<int64_t, int64_t>> got;
    for (int i = 0; i < 10; ++i) {
      auto fa = skel("a", i * 40 + 3), fb = skel("b", i * 33);
      Status s1 = sync.push(a_first ? fa : fb);
      Status s2 = sync.push(a_first ? fb : fa);
      EXPECT_TRUE(s1 && s2);
      for (auto& mf : sync.poll())
        got.emplace_back(mf.frame("a") ? ms(mf.frame("a")->stamp) : -1,
                         mf.frame("b") ? ms(mf.frame("b")->stamp) : -1);
    }
    sync.end_all();
    for (auto& mf : sync.poll())
      got.emplace_back(mf.frame("a") ? ms(mf.frame("a")->stamp) : -1,
                       mf.frame("b") ? ms(mf.frame("b")->stamp) : -1);
    return got;
  };
  EXPECT_EQ(run(true), run(false));
  EXPECT_GE(run(true).size(), 8u);
}

TEST(SynchronizerSettled, MissingFrameLeavesEntryEmptyNotStale) {
  Synchronizer sync(settled_options(), {{"a"}, {"b"}});
  ASSERT_TRUE(sync.push(skel("a", 0)));
  ASSERT_TRUE(sync.push(skel("b", 0)));
  ASSERT_TRUE(sync.push(skel("a", 40)));
  ASSERT_TRUE(sync.push(skel("b", 80)));  // b skipped tick 40
  ASSERT_TRUE(sync.push(skel("a", 80)));
  sync.end_all();
  auto out = sync.poll();
  ASSERT_EQ(out.size(), 3u);
  EXPECT_TRUE(out[1].frame("a"));
  EXPECT_FALSE(out[1].frame("b")) << "the 0 ms frame is 40 ms away: outside tolerance";
}

TEST(SynchronizerSettled, AudioChunksAreDeliveredExactlyOnce) {
  Synchronizer sync(settled_options(), {{"cam"}, {"mic", StreamMode::kContinuous}});
  for (int i = 0; i < 10; ++i) ASSERT_TRUE(sync.push(skel("cam", i * 40)));
  for (int i = 0; i < 20; ++i) ASSERT_TRUE(sync.push(audio("mic", i * 20)));
  sync.end_all();
  size_t chunks = 0;
  for (auto& mf : sync.poll()) {
    for (auto& c : mf.chunks_of("mic")) {
      EXPECT_LE(c->stamp, mf.stamp);
      ++chunks;
    }
  }
  EXPECT_EQ(chunks, 20u);
}

TEST(SynchronizerSettled, RejectsNonIncreasingStamps) {
  Synchronizer sync(settled_options(), {{"a"}});
  ASSERT_TRUE(sync.push(skel("a", 40)));
  auto st = sync.push(skel("a", 40));
  ASSERT_FALSE(st);
  EXPECT_EQ(st.error().code, ErrorCode::kCorruptData);
  EXPECT_FALSE(sync.push(skel("zzz", 80))) << "unknown sensor";
}

TEST(SynchronizerLive, EmitsNewestTickAtOnceAndCountsDroppedFrames) {
  SynchronizerOptions o;
  o.policy = SyncPolicy::kLatestWithinTolerance;
  o.start = Timestamp::from_ns(0);
  Synchronizer sync(o, {{"cam"}});
  // Simulated clock: frames every 40 ms; the pipeline is slow (busy for 100 ms per tick).
  int64_t busy_until = -1;
  int processed = 0;
  for (int64_t now = 0; now <= 2000; now += 5) {
    if (now % 40 == 0) {
      ASSERT_TRUE(sync.push(skel("cam", now)));
    }
    if (busy_until >= 0 && now >= busy_until) {
      sync.done();
      busy_until = -1;
    }
    for (auto& mf : sync.poll(Timestamp::from_ns(now * 1'000'000))) {
      EXPECT_TRUE(mf.frame("cam"));
      EXPECT_LE(now - ms(mf.stamp), 40) << "live ticks are never old";
      ++processed;
      busy_until = now + 100;
    }
  }
  const auto& st = sync.stats();
  EXPECT_GT(st.ticks_dropped, 0u);
  EXPECT_GT(processed, 10);
  EXPECT_LT(processed, 40);
  const auto& cam = st.streams.at("cam");
  EXPECT_EQ(cam.received, 51u);
  EXPECT_GT(cam.dropped, 20u) << "frames the busy pipeline could not take are counted";
  EXPECT_LE(cam.delivered + cam.dropped + cam.unmatched, cam.received);
}

TEST(SynchronizerLive, FastPipelineDropsNothing) {
  SynchronizerOptions o;
  o.policy = SyncPolicy::kLatestWithinTolerance;
  o.start = Timestamp::from_ns(0);
  Synchronizer sync(o, {{"cam"}});
  int processed = 0;
  for (int64_t now = 0; now < 1000; now += 5) {
    if (now % 40 == 0) {
      ASSERT_TRUE(sync.push(skel("cam", now)));
    }
    for (auto& mf : sync.poll(Timestamp::from_ns(now * 1'000'000))) {
      (void)mf;
      ++processed;
      sync.done();
    }
  }
  EXPECT_EQ(processed, 25);
  EXPECT_EQ(sync.stats().dropped_frames(), 0u);
  EXPECT_EQ(sync.stats().ticks_dropped, 0u);
}

TEST(SynchronizerOptions, CheckRejectsBadValues) {
  SynchronizerOptions o;
  EXPECT_TRUE(o.check());
  o.tick_period = Duration::from_ns(0);
  o.max_in_flight = 0;
  auto st = o.check();
  ASSERT_FALSE(st);
  EXPECT_NE(st.error().message.find("tick_period"), std::string::npos);
  EXPECT_NE(st.error().message.find("max_in_flight"), std::string::npos);
}

}  // namespace
}  // namespace dreamsense
