#include "dreamsense/core/pipeline.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <map>
#include <stdexcept>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

namespace dreamsense {
namespace {

inline constexpr Key<int> kSeen{"test.seen"};
inline constexpr Key<int> kDoubled{"test.doubled"};

// A source of skeleton frames at 30 Hz and audio chunks every 20 ms, in stamp order.
class FakeSource : public Source {
 public:
  explicit FakeSource(int seconds) {
    for (int i = 0; i < seconds * 30; ++i)
      frames_.push_back(make_frame("skel", Timestamp::from_ns(i * 1'000'000'000LL / 30),
                                   static_cast<uint64_t>(i), Skeleton{}));
    std::stable_sort(frames_.begin(), frames_.end(),
                     [](const FramePtr& a, const FramePtr& b) { return a->stamp < b->stamp; });
  }
  Result<FramePtr> next() override {
    if (pos_ >= frames_.size()) return make_error(ErrorCode::kEndOfStream, "end");
    return frames_[pos_++];
  }
  SourceInfo info() const override {
    SourceInfo i;
    i.sensors.push_back(SensorDescription{"skel", SensorKind::kSkeleton, 30});
    return i;
  }

 private:
  std::vector<FramePtr> frames_;
  size_t pos_ = 0;
};

class CountingAnalyzer : public Analyzer {
 public:
  std::string_view name() const override { return "counter"; }
  AnalyzerContract contract() const override { return {{"skel"}, {}, {}, {kSeen.name}}; }
  Status process(const MultiFrame& in, const BlackboardView&, BlackboardWriter& out) override {
    if (in.frame("skel"))
      out.set(kSeen, ++count_, in.stamp, 1.f);
    else
      out.set_absent(kSeen, in.stamp);
    return ok_status();
  }
  int count_ = 0;
};

class DoublingAnalyzer : public Analyzer {
 public:
  std::string_view name() const override { return "doubler"; }
  AnalyzerContract contract() const override { return {{}, {}, {kSeen.name}, {kDoubled.name}}; }
  Status process(const MultiFrame& in, const BlackboardView& prior,
                 BlackboardWriter& out) override {
    auto seen = prior.get(kSeen);
    if (!seen || !seen->present() || seen->stamp != in.stamp)
      return make_error(ErrorCode::kInternal, "counter's result of this tick is not visible");
    out.set(kDoubled, *seen->value * 2, in.stamp, 1.f);
    return ok_status();
  }
};

class ThrowingAnalyzer : public Analyzer {
 public:
  std::string_view name() const override { return "thrower"; }
  AnalyzerContract contract() const override { return {}; }
  Status process(const MultiFrame&, const BlackboardView&, BlackboardWriter&) override {
    DS_CHECK_EQ(1, 2);
    return ok_status();
  }
  void reset() override { resets++; }
  int resets = 0;
};

// The counter, then the doubler that reads its count in the same tick.
Result<std::unique_ptr<Pipeline>> counter_then_doubler(const FakeSource& src) {
  std::vector<std::unique_ptr<Analyzer>> a;
  a.push_back(std::make_unique<CountingAnalyzer>());
  a.push_back(std::make_unique<DoublingAnalyzer>());
  PipelineOptions o;
  o.sync.start = Timestamp::from_ns(0);
  return Pipeline::build(o, src.info(), std::move(a));
}

TEST(Pipeline, LaterAnalysersSeeEarlierResultsOfTheSameTick) {
  FakeSource src(2);
  auto p = counter_then_doubler(src);
  ASSERT_TRUE(p) << p.error().message;
  int ticks = 0;
  auto st = (*p)->run(src, [&](const MultiFrame& mf, const BlackboardView& v) -> Status {
    ++ticks;
    auto d = v.get(kDoubled);
    EXPECT_TRUE(d && d->stamp == mf.stamp);
    return ok_status();
  });
  ASSERT_TRUE(st) << st.error().message;
  EXPECT_EQ(ticks, 50);
  EXPECT_EQ((*p)->stats().analyzers[1].errors, 0u);
  EXPECT_EQ((*p)->stats().analyzers[0].latency_ms.size(), 50u);
}

// A doubler that claims the counter's name: another contract under a known name.
class CounterNamedDoubler : public DoublingAnalyzer {
 public:
  std::string_view name() const override { return "counter"; }
};

TEST(Pipeline, AnalysersReplacedBetweenTicksRunFromTheNextTickOn) {
  FakeSource src(2);
  auto p = counter_then_doubler(src);
  ASSERT_TRUE(p) << p.error().message;
  std::vector<int> seen;
  auto st = (*p)->run(src, [&](const MultiFrame&, const BlackboardView& v) -> Status {
    auto s = v.get(kSeen);
    seen.push_back(s && s->present() ? *s->value : -1);
    if (seen.size() == 10) {
      // Refused, nothing replaced: another contract, an unknown name, a null analyser.
      std::vector<std::unique_ptr<Analyzer>> wrong;
      wrong.push_back(std::make_unique<CounterNamedDoubler>());
      EXPECT_FALSE((*p)->replace_analyzers(std::move(wrong)));
      std::vector<std::unique_ptr<Analyzer>> unknown;
      unknown.push_back(std::make_unique<ThrowingAnalyzer>());
      EXPECT_FALSE((*p)->replace_analyzers(std::move(unknown)));
      std::vector<std::unique_ptr<Analyzer>> null;
      null.emplace_back();
      EXPECT_FALSE((*p)->replace_analyzers(std::move(null)));
      // A fresh counter: its count starts again at the next tick.
      std::vector<std::unique_ptr<Analyzer>> fresh;
      fresh.push_back(std::make_unique<CountingAnalyzer>());
      return (*p)->replace_analyzers(std::move(fresh));
    }
    return ok_status();
  });
  ASSERT_TRUE(st) << st.error().message;
  ASSERT_EQ(seen.size(), 50u);
  EXPECT_EQ(seen[9], 10);  // the first counter's tenth tick
  EXPECT_EQ(seen[10], 1);  // the replacement's first
  EXPECT_EQ(seen[49], 40);
  EXPECT_EQ((*p)->analyzers().size(), 2u);
  EXPECT_EQ((*p)->stats().analyzers[1].errors, 0u);  // the doubler saw every tick's count
}

TEST(Pipeline, BuildRejectsBadWiring) {
  FakeSource src(1);
  {
    std::vector<std::unique_ptr<Analyzer>> a;
    a.push_back(std::make_unique<DoublingAnalyzer>());  // reads what nobody wrote before it
    a.push_back(std::make_unique<CountingAnalyzer>());
    auto p = Pipeline::build({}, src.info(), std::move(a));
    ASSERT_FALSE(p);
    EXPECT_NE(p.error().message.find("test.seen"), std::string::npos);
  }
  {
    std::vector<std::unique_ptr<Analyzer>> a;
    a.push_back(std::make_unique<CountingAnalyzer>());
    SourceInfo no_skeleton;
    auto p = Pipeline::build({}, no_skeleton, std::move(a));
    ASSERT_FALSE(p);
    EXPECT_NE(p.error().message.find("'skel'"), std::string::npos);
  }
  {
    std::vector<std::unique_ptr<Analyzer>> a;
    a.push_back(std::make_unique<CountingAnalyzer>());
    a.push_back(std::make_unique<CountingAnalyzer>());
    EXPECT_FALSE(Pipeline::build({}, src.info(), std::move(a)));
  }
}

TEST(Pipeline, BrokenCheckInAnAnalyserResetsItAndTheRunGoesOn) {
  FakeSource src(1);
  std::vector<std::unique_ptr<Analyzer>> a;
  a.push_back(std::make_unique<CountingAnalyzer>());
  auto thrower = std::make_unique<ThrowingAnalyzer>();
  ThrowingAnalyzer* t = thrower.get();
  a.push_back(std::move(thrower));
  auto p = Pipeline::build({}, src.info(), std::move(a));
  ASSERT_TRUE(p);
  ASSERT_TRUE((*p)->run(src, nullptr));
  EXPECT_EQ((*p)->stats().analyzers[1].errors, (*p)->stats().ticks);
  EXPECT_EQ(t->resets, static_cast<int>((*p)->stats().ticks));
}

TEST(Pipeline, LivePolicyPacedByStampsKeepsUpWithAFastAnalyser) {
  FakeSource src(1);  // plays for one second of wall time
  std::vector<std::unique_ptr<Analyzer>> a;
  a.push_back(std::make_unique<CountingAnalyzer>());
  PipelineOptions o;
  o.sync.policy = SyncPolicy::kLatestWithinTolerance;
  auto p = Pipeline::build(o, src.info(), std::move(a));
  ASSERT_TRUE(p);
  ASSERT_TRUE((*p)->run(src, nullptr));
  EXPECT_EQ((*p)->stats().frames, 30u);
  // 25 slots of 40 ms; a tick is missed only when the main thread sleeps through a whole slot,
  // which a loaded 2-core machine does now and then.
  EXPECT_GE((*p)->stats().ticks, 18u);
  EXPECT_LE((*p)->stats().ticks, 26u);
}

// A fake source that says when it has handed out its last frame.
class DrainSignallingSource : public FakeSource {
 public:
  using FakeSource::FakeSource;
  Result<FramePtr> next() override {
    auto r = FakeSource::next();
    if (!r) drained = true;
    return r;
  }
  std::atomic<bool> drained{false};
};

// Its first tick lasts until the source is drained, so every later frame is already queued
// when the pipeline looks again; without that the test would depend on thread timing.
class WaitForDrainAnalyzer : public CountingAnalyzer {
 public:
  explicit WaitForDrainAnalyzer(const std::atomic<bool>& drained) : drained_(drained) {}
  Status process(const MultiFrame& in, const BlackboardView& prior,
                 BlackboardWriter& out) override {
    const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(10);
    while (!drained_ && std::chrono::steady_clock::now() < give_up)
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    return CountingAnalyzer::process(in, prior, out);
  }

 private:
  const std::atomic<bool>& drained_;
};

TEST(Pipeline, LivePolicyUnpacedTakesOnlyTheNewestFrames) {
  // All frames arrive at once: live keeps the newest, counts the rest.
  DrainSignallingSource src(1);
  std::vector<std::unique_ptr<Analyzer>> a;
  a.push_back(std::make_unique<WaitForDrainAnalyzer>(src.drained));
  PipelineOptions o;
  o.sync.policy = SyncPolicy::kLatestWithinTolerance;
  o.pace_source = false;
  auto p = Pipeline::build(o, src.info(), std::move(a));
  ASSERT_TRUE(p);
  ASSERT_TRUE((*p)->run(src, nullptr));
  const auto& st = (*p)->stats();
  EXPECT_EQ(st.frames, 30u);
  EXPECT_GE(st.ticks, 1u);
  EXPECT_LE(st.ticks, 3u);
  const auto& skel = st.sync.streams.at("skel");
  EXPECT_EQ(skel.delivered + skel.dropped + skel.unmatched, 30u - 0u) << "every frame accounted";
}

// Two skeleton streams at 30 Hz: "short" ends after 1 s, "long" goes on for 10 s.
class EarlyEndSource : public Source {
 public:
  explicit EarlyEndSource(bool reports_ends) : reports_ends_(reports_ends) {
    for (int i = 0; i < 300; ++i) {
      const auto t = Timestamp::from_ns(i * 1'000'000'000LL / 30);
      if (i < 30) frames_.push_back(make_frame("short", t, static_cast<uint64_t>(i), Skeleton{}));
      frames_.push_back(make_frame("long", t, static_cast<uint64_t>(i), Skeleton{}));
    }
  }
  Result<FramePtr> next() override {
    if (pos_ >= frames_.size()) return make_error(ErrorCode::kEndOfStream, "end");
    return frames_[pos_++];
  }
  SourceInfo info() const override {
    SourceInfo i;
    i.sensors.push_back(SensorDescription{"short", SensorKind::kSkeleton, 30});
    i.sensors.push_back(SensorDescription{"long", SensorKind::kSkeleton, 30});
    return i;
  }
  bool stream_ended(const SensorId& id) const override {
    if (!reports_ends_) return false;
    for (size_t k = pos_; k < frames_.size(); ++k)
      if (frames_[k]->sensor == id) return false;
    return true;
  }
  size_t position() const { return pos_; }
  size_t size() const { return frames_.size(); }

 private:
  bool reports_ends_;
  std::vector<FramePtr> frames_;
  size_t pos_ = 0;
};

class BothStreamsAnalyzer : public Analyzer {
 public:
  std::string_view name() const override { return "both"; }
  AnalyzerContract contract() const override { return {{"short", "long"}, {}, {}, {}}; }
  Status process(const MultiFrame&, const BlackboardView&, BlackboardWriter&) override {
    return ok_status();
  }
};

// Issue 18 (soak): a stream that ends early must not make settled replay hold every later frame
// of the other streams until the source ends. With Source::stream_ended the tick at 5 s is
// processed while the source is half read; without it (the default), only at the very end.
TEST(Pipeline, SettledReplayDoesNotWaitForAStreamThatEnded) {
  for (const bool reports_ends : {true, false}) {
    EarlyEndSource src(reports_ends);
    std::vector<std::unique_ptr<Analyzer>> a;
    a.push_back(std::make_unique<BothStreamsAnalyzer>());
    auto p = Pipeline::build({}, src.info(), std::move(a));
    ASSERT_TRUE(p);
    size_t read_at_5s = 0;
    const auto on_tick = [&](const MultiFrame& tick, const BlackboardView&) {
      if (tick.stamp == Timestamp::from_ns(5'000'000'000LL)) read_at_5s = src.position();
      return ok_status();
    };
    ASSERT_TRUE((*p)->run(src, on_tick));
    EXPECT_EQ((*p)->stats().ticks, 250u) << reports_ends;
    if (reports_ends)
      EXPECT_LT(read_at_5s, src.size() * 2 / 3) << "frames kept until the end";
    else
      EXPECT_EQ(read_at_5s, src.size());
  }
}

// An analyser of a dependency graph: writes a number mixing its call count with every value it
// read (this tick's `reads`, and `previous` as feedback from earlier ticks); sleeps a varying
// 0-0.4 ms so that the threads interleave differently from tick to tick. A feedback read that
// sees this tick's value is an error.
inline constexpr Key<int64_t> kA{"test.a"}, kB{"test.b"}, kC{"test.c"}, kD{"test.d"}, kE{"test.e"},
    kX{"test.x"}, kY{"test.y"};

class MixingAnalyzer : public Analyzer {
 public:
  MixingAnalyzer(std::string name, std::vector<Key<int64_t>> reads, Key<int64_t> writes,
                 std::vector<Key<int64_t>> previous = {}, bool needs_skeleton = false,
                 int extra_sleep_us = 0)
      : name_(std::move(name)),
        reads_(std::move(reads)),
        previous_(std::move(previous)),
        writes_(writes),
        needs_skeleton_(needs_skeleton),
        extra_sleep_us_(extra_sleep_us) {}
  std::string_view name() const override { return name_; }
  AnalyzerContract contract() const override {
    AnalyzerContract c;
    if (needs_skeleton_) c.required_inputs = {"skel"};
    for (const auto& k : reads_) c.reads.push_back(k.name);
    for (const auto& k : previous_) c.reads_previous.push_back(k.name);
    c.writes = {writes_.name};
    return c;
  }
  Status process(const MultiFrame& in, const BlackboardView& prior,
                 BlackboardWriter& out) override {
    ++calls_;
    int64_t v = calls_ * 1000 + static_cast<int64_t>(name_.size());
    for (const auto& k : reads_) {
      const auto e = prior.get(k);
      if (!e || e->stamp != in.stamp)
        return make_error(ErrorCode::kInternal, "{}: {} of this tick not visible", name_, k.name);
      v = v * 31 + *e->value;
    }
    for (const auto& k : previous_) {
      const auto e = prior.get(k);
      if (e && e->stamp >= in.stamp)
        return make_error(ErrorCode::kInternal, "{}: saw this tick's {}", name_, k.name);
      v = v * 17 + (e ? *e->value : -1);
    }
    std::this_thread::sleep_for(
        std::chrono::microseconds(200 * ((calls_ * 7 + v) % 3) + extra_sleep_us_));
    out.set(writes_, v, in.stamp, 1.f);
    return ok_status();
  }

 private:
  std::string name_;
  std::vector<Key<int64_t>> reads_, previous_;
  Key<int64_t> writes_;
  bool needs_skeleton_;
  int extra_sleep_us_;
  int64_t calls_ = 0;
};

// Every key's value after every tick, and the errors, with `threads` threads.
std::tuple<std::vector<std::vector<int64_t>>, uint64_t, int> run_graph(int threads) {
  FakeSource src(2);
  std::vector<std::unique_ptr<Analyzer>> a;
  a.push_back(std::make_unique<MixingAnalyzer>("source", std::vector<Key<int64_t>>{}, kA,
                                               std::vector<Key<int64_t>>{}, true));
  // Slow: "feedback" starts late, after d's writer could have finished.
  a.push_back(std::make_unique<MixingAnalyzer>("alone", std::vector<Key<int64_t>>{}, kX,
                                               std::vector<Key<int64_t>>{}, false, 1500));
  // Reads d of the previous tick: must run before d's writer in every tick.
  a.push_back(
      std::make_unique<MixingAnalyzer>("feedback", std::vector{kA, kX}, kE, std::vector{kD}));
  a.push_back(std::make_unique<MixingAnalyzer>("left", std::vector{kA}, kB));
  a.push_back(std::make_unique<MixingAnalyzer>("right", std::vector{kA}, kC));
  a.push_back(std::make_unique<MixingAnalyzer>("join", std::vector{kB, kC}, kD));
  a.push_back(std::make_unique<MixingAnalyzer>("after_alone", std::vector{kX, kE}, kY));
  PipelineOptions o;
  o.sync.start = Timestamp::from_ns(0);
  o.threads = threads;
  auto p = Pipeline::build(o, src.info(), std::move(a));
  EXPECT_TRUE(p) << p.error().message;
  if (!p) return {};
  std::vector<std::vector<int64_t>> seen;
  auto st = (*p)->run(src, [&](const MultiFrame&, const BlackboardView& v) -> Status {
    std::vector<int64_t> row;
    for (const auto& k : {kA, kB, kC, kD, kE, kX, kY})
      row.push_back(v.get(k) ? *v.get(k)->value : 0);
    seen.push_back(row);
    return ok_status();
  });
  EXPECT_TRUE(st);
  uint64_t errors = 0;
  for (const auto& s : (*p)->stats().analyzers) errors += s.errors;
  EXPECT_EQ((*p)->stats().threads, threads);  // what bench pipeline reports
  return {seen, errors, (*p)->threads()};
}

TEST(Pipeline, ParallelTicksGiveTheResultsOfTheSequentialOrder) {
  const auto [sequential, sequential_errors, one] = run_graph(1);
  EXPECT_EQ(one, 1);
  ASSERT_EQ(sequential.size(), 50u);
  EXPECT_EQ(sequential_errors, 0u);
  for (const int threads : {2, 3, 8}) {
    const auto [parallel, errors, used] = run_graph(threads);
    EXPECT_EQ(used, threads);
    EXPECT_EQ(errors, 0u) << threads << " threads";
    EXPECT_EQ(parallel, sequential) << threads << " threads";
  }
}

// Each of two independent analysers waits (up to 2 s) for the other to have started the same
// tick: they meet only if they run at the same time.
class MeetingAnalyzer : public Analyzer {
 public:
  MeetingAnalyzer(std::string name, Key<int64_t> writes, std::atomic<int>* arrivals)
      : name_(std::move(name)), writes_(writes), arrivals_(arrivals) {}
  std::string_view name() const override { return name_; }
  AnalyzerContract contract() const override { return {{}, {}, {}, {writes_.name}}; }
  Status process(const MultiFrame& in, const BlackboardView&, BlackboardWriter& out) override {
    ++calls_;
    arrivals_->fetch_add(1);
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(2);
    while (arrivals_->load() < 2 * calls_ && std::chrono::steady_clock::now() < deadline)
      std::this_thread::sleep_for(std::chrono::microseconds(50));
    met += arrivals_->load() >= 2 * calls_;
    out.set(writes_, int64_t{calls_}, in.stamp, 1.f);
    return ok_status();
  }
  int met = 0;

 private:
  std::string name_;
  Key<int64_t> writes_;
  std::atomic<int>* arrivals_;
  int calls_ = 0;
};

TEST(Pipeline, IndependentAnalysersOfATickRunAtTheSameTime) {
  FakeSource src(1);
  std::atomic<int> arrivals{0};
  auto first = std::make_unique<MeetingAnalyzer>("first", kX, &arrivals);
  auto second = std::make_unique<MeetingAnalyzer>("second", kY, &arrivals);
  MeetingAnalyzer* f = first.get();
  MeetingAnalyzer* s = second.get();
  std::vector<std::unique_ptr<Analyzer>> a;
  a.push_back(std::move(first));
  a.push_back(std::move(second));
  PipelineOptions o;
  o.sync.start = Timestamp::from_ns(0);
  o.threads = 2;
  auto p = Pipeline::build(o, src.info(), std::move(a));
  ASSERT_TRUE(p);
  ASSERT_TRUE((*p)->run(src, nullptr));
  const int ticks = static_cast<int>((*p)->stats().ticks);
  EXPECT_GT(ticks, 0);
  EXPECT_EQ(f->met, ticks);
  EXPECT_EQ(s->met, ticks);
}

class ExceptionAnalyzer : public Analyzer {
 public:
  std::string_view name() const override { return "exception"; }
  AnalyzerContract contract() const override { return {}; }
  Status process(const MultiFrame&, const BlackboardView&, BlackboardWriter&) override {
    throw std::runtime_error("broken analyser");
  }
};

TEST(Pipeline, AnExceptionInAnAnalyserLeavesTheRunWithAnyNumberOfThreads) {
  for (const int threads : {1, 2}) {
    FakeSource src(1);
    std::vector<std::unique_ptr<Analyzer>> a;
    a.push_back(std::make_unique<CountingAnalyzer>());
    a.push_back(std::make_unique<ExceptionAnalyzer>());
    PipelineOptions o;
    o.threads = threads;
    auto p = Pipeline::build(o, src.info(), std::move(a));
    ASSERT_TRUE(p);
    EXPECT_THROW((void)(*p)->run(src, nullptr), std::runtime_error) << threads;
  }
}

TEST(Pipeline, ThreadsOutsideTheRangeAreRejected) {
  PipelineOptions o;
  o.threads = -1;
  EXPECT_FALSE(o.check());
  o.threads = PipelineOptions::kMaxThreads + 1;
  EXPECT_FALSE(o.check());
  o.threads = 0;
  EXPECT_TRUE(o.check());
  EXPECT_EQ(PipelineOptions::auto_threads(0), 1);  // unknown
  EXPECT_EQ(PipelineOptions::auto_threads(2), 1);
  EXPECT_EQ(PipelineOptions::auto_threads(4), 3);
  EXPECT_EQ(PipelineOptions::auto_threads(64), PipelineOptions::kMaxAutoThreads);
}

}  // namespace
}  // namespace dreamsense
