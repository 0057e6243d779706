#include "dreamsense/core/blackboard.hpp"

#include <gtest/gtest.h>

#include <thread>

namespace dreamsense {
namespace {

struct Point {
  double x = 0, y = 0;
};
inline constexpr Key<Point> kPoint{"test.point"};
inline constexpr Key<int> kCount{"test.count"};
inline constexpr Key<double> kPointAsDouble{"test.point"};

Timestamp ms(int64_t v) { return Timestamp::from_ns(v * 1'000'000); }

TEST(Blackboard, WritesAreInvisibleUntilCommit) {
  Blackboard bb;
  BlackboardWriter w("face");
  w.set(kPoint, Point{1, 2}, ms(40), 0.9f);
  EXPECT_FALSE(bb.snapshot().get(kPoint).has_value());
  bb.commit(w, ms(40));
  auto e = bb.snapshot().get(kPoint);
  ASSERT_TRUE(e.has_value());
  ASSERT_TRUE(e->present());
  EXPECT_EQ(e->value->x, 1);
  EXPECT_EQ(e->stamp, ms(40));
  EXPECT_FLOAT_EQ(e->confidence, 0.9f);
  EXPECT_EQ(e->source, "face") << "provenance comes from the writer";
  EXPECT_TRUE(w.empty());
}

TEST(Blackboard, SnapshotIsImmutableWhileNewTicksCommit) {
  Blackboard bb;
  BlackboardWriter w("a");
  w.set(kPoint, Point{1, 0}, ms(0), 1.f);
  w.set(kCount, 1, ms(0), 1.f);
  bb.commit(w, ms(0));
  const BlackboardView old = bb.snapshot();
  w.set(kPoint, Point{2, 0}, ms(40), 1.f);
  w.set(kCount, 2, ms(40), 1.f);
  bb.commit(w, ms(40));
  EXPECT_EQ(old.get(kPoint)->value->x, 1);
  EXPECT_EQ(*old.get(kCount)->value, 1);
  EXPECT_EQ(old.stamp(), ms(0));
  EXPECT_EQ(bb.snapshot().get(kPoint)->value->x, 2);
  EXPECT_EQ(bb.snapshot().stamp(), ms(40));
}

TEST(Blackboard, ConcurrentReadersNeverSeeAHalfUpdatedTick) {
  Blackboard bb;
  std::atomic<bool> stop{false};
  std::atomic<int> torn{0}, reads{0};
  std::thread reader([&] {
    while (!stop) {
      const BlackboardView v = bb.snapshot();
      auto a = v.get(kPoint);
      auto b = v.get(kCount);
      if (a && b && static_cast<int>(a->value->x) != *b->value) torn++;
      reads++;
    }
  });
  // Keep committing until the reader has taken many snapshots (it may start late under load).
  for (int i = 0; i < 2000 || (reads < 1000 && i < 10'000'000); ++i) {
    BlackboardWriter w("writer");
    w.set(kPoint, Point{static_cast<double>(i), 0}, ms(i), 1.f);
    w.set(kCount, i, ms(i), 1.f);
    bb.commit(w, ms(i));
  }
  stop = true;
  reader.join();
  EXPECT_EQ(torn.load(), 0);
  EXPECT_GE(reads.load(), 1000);
}

TEST(Blackboard, HistoryIsNewestFirstAndBounded) {
  Blackboard bb(BlackboardOptions{5});
  for (int i = 0; i < 12; ++i) {
    BlackboardWriter w("a");
    w.set(kCount, i, ms(i * 40), 1.f);
    bb.commit(w, ms(i * 40));
  }
  auto h = bb.snapshot().history(kCount);
  ASSERT_EQ(h.size(), 5u);
  EXPECT_EQ(*h[0].value, 11);
  EXPECT_EQ(*h[4].value, 7);
  EXPECT_EQ(bb.snapshot().history(kCount, 2).size(), 2u);
}

TEST(Blackboard, AbsenceIsRecordedAsAValue) {
  Blackboard bb;
  BlackboardWriter w("face");
  w.set(kPoint, Point{1, 1}, ms(0), 1.f);
  bb.commit(w, ms(0));
  w.set_absent(kPoint, ms(40));
  bb.commit(w, ms(40));
  auto e = bb.snapshot().get(kPoint);
  ASSERT_TRUE(e.has_value());
  EXPECT_FALSE(e->present()) << "nothing seen at 40 ms: not the stale value from 0 ms";
  EXPECT_EQ(e->stamp, ms(40));
  EXPECT_TRUE(bb.snapshot().history(kPoint)[1].present());
}

TEST(Blackboard, TypeMismatchIsAProgrammerError) {
  Blackboard bb;
  BlackboardWriter w("a");
  w.set(kPoint, Point{}, ms(0), 1.f);
  bb.commit(w, ms(0));
  EXPECT_THROW(bb.snapshot().get(kPointAsDouble), CheckFailure);
  w.set(kPointAsDouble, 1.0, ms(40), 1.f);
  EXPECT_THROW(bb.commit(w, ms(40)), CheckFailure);
  EXPECT_EQ(bb.snapshot().stamp(), ms(0)) << "a failed commit publishes nothing";
}

}  // namespace
}  // namespace dreamsense
