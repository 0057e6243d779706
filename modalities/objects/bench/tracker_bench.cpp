// Tracker speed (frames per second = items_per_second) on a synthetic 640x480 colour sequence with
// a 60x80 target, every tracker of make_tracker. The frames are made before timing; each
// iteration is one update().
//   build/modalities/objects/objects_bench --benchmark_filter=Tracker

#include "dreamsense/objects/tracker.hpp"

#include <benchmark/benchmark.h>

#include "../test/synthetic_sequence.hpp"

namespace {

using namespace dreamsense::objects;

const testing::SyntheticSequence& sequence(bool large) {
  static const auto small_seq = [] {
    testing::SyntheticOptions o;
    o.frames = 120;
    return testing::make_synthetic_sequence(o);
  }();
  static const auto large_seq = [] {
    testing::SyntheticOptions o;
    o.frames = 120;
    o.target_size = {160, 200};
    return testing::make_synthetic_sequence(o);
  }();
  return large ? large_seq : small_seq;
}

void BM_TrackerUpdate(benchmark::State& state, const std::string& name, bool large) {
  const auto& seq = sequence(large);
  auto t = make_tracker(name);
  if (!t || !(*t)->init(seq.frames[0], seq.boxes[0])) {
    state.SkipWithError("init failed");
    return;
  }
  size_t i = 1;
  for (auto _ : state) {
    auto u = (*t)->update(seq.frames[i]);
    benchmark::DoNotOptimize(u);
    if (++i == seq.frames.size()) {
      state.PauseTiming();
      (void)(*t)->init(seq.frames[0], seq.boxes[0]);
      i = 1;
      state.ResumeTiming();
    }
  }
  state.SetItemsProcessed(state.iterations());
}

void register_all() {
  for (const auto& n : tracker_names()) {
    benchmark::RegisterBenchmark(("TrackerUpdate640x480/" + n + "/target60x80").c_str(),
                                 BM_TrackerUpdate, n, false)
        ->Unit(benchmark::kMillisecond);
    benchmark::RegisterBenchmark(("TrackerUpdate640x480/" + n + "/target160x200").c_str(),
                                 BM_TrackerUpdate, n, true)
        ->Unit(benchmark::kMillisecond);
  }
}

// Registered before main (BENCHMARK_MAIN in table_top_bench.cpp).
const bool registered = (register_all(), true);

}  // namespace

BENCHMARK_MAIN();
