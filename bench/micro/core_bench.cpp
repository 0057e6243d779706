// Synchroniser and blackboard costs per tick. Frames are built before the timed region.

#include "dreamsense/core/blackboard.hpp"
#include "dreamsense/core/synchronizer.hpp"

#include <benchmark/benchmark.h>

namespace dreamsense {
namespace {

// One second of a DREAM-like rig: 3 cameras at 25 Hz, 3 Kinect streams at 30 Hz, audio at 50 Hz.
std::vector<FramePtr> one_second_of_frames() {
  std::vector<FramePtr> frames;
  const cv::Mat tiny(1, 1, CV_8UC3);
  for (const char* cam : {"camera_left", "camera_middle", "camera_right"})
    for (int i = 0; i < 25; ++i)
      frames.push_back(make_frame(cam, Timestamp::from_ns(i * 40'000'000LL), i, ColorImage{tiny}));
  for (const char* k : {"front.color", "front.depth", "front.skeleton"})
    for (int i = 0; i < 30; ++i)
      frames.push_back(make_frame(k, Timestamp::from_ns(i * 1'000'000'000LL / 30), i, Skeleton{}));
  for (int i = 0; i < 50; ++i)
    frames.push_back(make_frame("mic", Timestamp::from_ns(i * 20'000'000LL), i, AudioChunk{}));
  std::stable_sort(frames.begin(), frames.end(),
                   [](const FramePtr& a, const FramePtr& b) { return a->stamp < b->stamp; });
  return frames;
}

std::vector<StreamSpec> specs() {
  return {{"camera_left"},
          {"camera_middle"},
          {"camera_right"},
          {"front.color"},
          {"front.depth"},
          {"front.skeleton"},
          {"mic", StreamMode::kContinuous}};
}

void BM_SynchronizerSettledOneSecond(benchmark::State& state) {
  const auto frames = one_second_of_frames();
  SynchronizerOptions o;
  o.start = Timestamp::from_ns(0);
  size_t ticks = 0;
  for (auto _ : state) {
    Synchronizer sync(o, specs());
    for (const auto& f : frames) {
      (void)sync.push(f);
      ticks += sync.poll().size();
    }
    sync.end_all();
    ticks += sync.poll().size();
  }
  state.counters["ticks_per_s"] =
      benchmark::Counter(static_cast<double>(ticks), benchmark::Counter::kIsRate);
  state.counters["frames_per_s"] = benchmark::Counter(
      static_cast<double>(frames.size() * state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_SynchronizerSettledOneSecond);

void BM_SynchronizerLiveOneSecond(benchmark::State& state) {
  const auto frames = one_second_of_frames();
  SynchronizerOptions o;
  o.policy = SyncPolicy::kLatestWithinTolerance;
  o.start = Timestamp::from_ns(0);
  for (auto _ : state) {
    Synchronizer sync(o, specs());
    for (const auto& f : frames) {
      (void)sync.push(f);
      for (auto& mf : sync.poll(f->stamp)) {
        benchmark::DoNotOptimize(mf);
        sync.done();
      }
    }
  }
  state.counters["frames_per_s"] = benchmark::Counter(
      static_cast<double>(frames.size() * state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_SynchronizerLiveOneSecond);

struct FaceLike {
  double box[4];
  double landmarks[136];
};
inline constexpr Key<FaceLike> kFace{"face.bench"};

// A tick's worth of writes: `keys` entries committed at once, then a snapshot read.
void BM_BlackboardCommitAndRead(benchmark::State& state) {
  const int nkeys = static_cast<int>(state.range(0));
  std::vector<std::string> names;
  for (int i = 0; i < nkeys; ++i) names.push_back("key." + std::to_string(i));
  Blackboard bb;
  int64_t t = 0;
  for (auto _ : state) {
    BlackboardWriter w("bench");
    for (int i = 0; i < nkeys; ++i)
      w.set(Key<FaceLike>{names[i].c_str()}, FaceLike{}, Timestamp::from_ns(t), 1.f);
    bb.commit(w, Timestamp::from_ns(t));
    auto e = bb.snapshot().get(Key<FaceLike>{names[0].c_str()});
    benchmark::DoNotOptimize(e);
    t += 40'000'000;
  }
  state.SetItemsProcessed(state.iterations() * nkeys);
}
BENCHMARK(BM_BlackboardCommitAndRead)->Arg(1)->Arg(30)->Arg(100);

void BM_BlackboardHistory64(benchmark::State& state) {
  Blackboard bb;
  for (int64_t t = 0; t < 100; ++t) {
    BlackboardWriter w("bench");
    w.set(kFace, FaceLike{}, Timestamp::from_ns(t), 1.f);
    bb.commit(w, Timestamp::from_ns(t));
  }
  const BlackboardView v = bb.snapshot();
  for (auto _ : state) {
    auto h = v.history(kFace, 64);
    benchmark::DoNotOptimize(h);
  }
}
BENCHMARK(BM_BlackboardHistory64);

}  // namespace
}  // namespace dreamsense

BENCHMARK_MAIN();
