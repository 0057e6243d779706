// CPU cost of direction finding per second of 4-channel 16 kHz audio (Kinect v1 geometry).
// Run: build/bench/sound_direction_bench. The input (reverberant, noisy speech-like noise) is
// simulated before the timed region; items_per_second = seconds of audio per CPU second.

#include "dreamsense/sim/room_acoustics.hpp"
#include "dreamsense/sound_direction/direction_finder.hpp"

#include <benchmark/benchmark.h>

#include <random>

namespace {
using namespace dreamsense;
using namespace dreamsense::sound_direction;

std::vector<float> make_audio(double seconds) {
  const auto g = MicArrayGeometry::kinect_v1();
  std::mt19937_64 rng(1);
  std::normal_distribution<double> d(0, 0.1);
  std::vector<double> mono(static_cast<size_t>(seconds * 16000));
  for (auto& v : mono) v = d(rng);
  sim::RoomOptions ro;
  ro.size_m = {5, 3, 4};
  ro.rt60_s = 0.3;
  sim::AcousticPlacement pl;
  const cv::Vec3d array(2.5, 1.2, 1.0);
  pl.source_m = array + cv::Vec3d(0.8, 0, 1.2);
  for (const auto& m : g.mics_m) pl.mics_m.push_back(array + m);
  auto mix = sim::simulate(mono, ro, pl);
  sim::add_noise(*mix, 10, sim::NoiseColor::kPink, 2);
  std::vector<float> out(mono.size() * 4);
  for (size_t n = 0; n < mono.size(); ++n)
    for (size_t c = 0; c < 4; ++c) out[n * 4 + c] = static_cast<float>((*mix)[c][n]);
  return out;
}

// One iteration = one second of audio pushed in 100 ms chunks (every frame voiced).
void BM_DirectionFinderPerSecond(benchmark::State& state) {
  const auto audio = make_audio(1.0);
  DirectionFinderOptions o;
  o.vad.threshold_db = 0;  // every frame through SRP-PHAT: the worst case
  o.vad.min_level_dbfs = -200;
  auto f = DirectionFinder::create(MicArrayGeometry::kinect_v1(), o);
  std::vector<FrameEstimate> est;
  for (auto _ : state) {
    est.clear();
    for (size_t n = 0; n < audio.size(); n += 1600 * 4)
      (void)(*f)->push(
          std::span<const float>(audio.data() + n, std::min<size_t>(1600 * 4, audio.size() - n)),
          est);
    benchmark::DoNotOptimize(est.data());
  }
  state.SetItemsProcessed(state.iterations());  // seconds of audio
  state.counters["cpu_s_per_audio_s"] =
      benchmark::Counter(static_cast<double>(state.iterations()),
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}
BENCHMARK(BM_DirectionFinderPerSecond)->Unit(benchmark::kMillisecond);

// The demo's room simulation: one 3 s utterance at 0.4 s RT60 to the 4 microphones (image
// sources); five of them make the 20 s of 4-channel audio a demo session holds.
void BM_RoomSimulationOfAThreeSecondUtterance(benchmark::State& state) {
  sim::RoomOptions room;
  room.rt60_s = 0.4;
  const cv::Vec3d centre(2.5, 2.05, 1.5);
  sim::AcousticPlacement pl;
  pl.source_m = {1.0, 1.8, 2.8};
  for (double x : {0.113, -0.036, -0.076, -0.113}) pl.mics_m.push_back(centre + cv::Vec3d(x, 0, 0));
  const auto clip = sim::make_noise(1, 3 * 16000, sim::NoiseColor::kWhite, 1)[0];
  for (auto _ : state) {
    auto wet = sim::simulate(clip, room, pl);
    benchmark::DoNotOptimize(wet);
  }
}
BENCHMARK(BM_RoomSimulationOfAThreeSecondUtterance)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
