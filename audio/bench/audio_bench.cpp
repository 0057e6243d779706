// Cost per second of 4-channel 16 kHz audio: resampling (48 kHz -> 16 kHz, 16 kHz -> 16 kHz is
// a copy and not measured), voice activity + segmentation, beamforming. Inputs are generated
// before the timed loops; each iteration processes one second in 40 ms chunks (the pipeline's
// 25 Hz ticks). items/s = audio seconds per wall second (the real-time factor's inverse).

#include "dreamsense/audio/beamformer.hpp"
#include "dreamsense/audio/noise_suppressor.hpp"
#include "dreamsense/audio/reference_gate.hpp"
#include "dreamsense/audio/resampler.hpp"
#include "dreamsense/audio/utterance_segmenter.hpp"

#include <benchmark/benchmark.h>

#include <cmath>
#include <random>
#include <vector>

namespace {

using namespace dreamsense;
using namespace dreamsense::audio;

std::vector<float> noise(size_t n, uint32_t seed = 1) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> d(0.f, 0.1f);
  std::vector<float> x(n);
  for (auto& v : x) v = d(rng);
  return x;
}

void BM_Resample4ch(benchmark::State& state) {
  const int from = static_cast<int>(state.range(0)), to = 16000, ch = 4;
  ResamplerOptions o;
  o.input_rate = from;
  o.output_rate = to;
  o.channels = ch;
  o.quality = static_cast<ResamplerQuality>(state.range(1));
  auto r = Resampler::create(o);
  const auto x = noise(static_cast<size_t>(from * ch));
  const size_t chunk = static_cast<size_t>(from / 25 * ch);
  std::vector<StampedAudio> out;
  int64_t k = 0;
  for (auto _ : state) {
    for (size_t i = 0; i < x.size(); i += chunk) {
      out.clear();
      (void)(*r)->process(std::span<const float>(x).subspan(i, chunk),
                          Timestamp::from_ns(0) + frames_to_duration(k, from), out);
      k += from / 25;
      benchmark::DoNotOptimize(out.data());
    }
  }
  state.SetItemsProcessed(state.iterations());
  state.SetLabel(fmt::format("{} Hz -> 16 kHz, 4 ch, quality {}", from, state.range(1)));
}
BENCHMARK(BM_Resample4ch)
    ->Args({48000, static_cast<int>(ResamplerQuality::kHigh)})
    ->Args({48000, static_cast<int>(ResamplerQuality::kMedium)})
    ->Args({44100, static_cast<int>(ResamplerQuality::kHigh)})
    ->Unit(benchmark::kMillisecond);

void BM_Beamform4ch16k(benchmark::State& state) {
  BeamformerOptions o;
  o.mic_positions_m = {{0.113, 0, 0}, {-0.036, 0, 0}, {-0.076, 0, 0}, {-0.113, 0, 0}};
  o.method = static_cast<BeamformerMethod>(state.range(0));
  auto b = Beamformer::create(o);
  (*b)->steer({0.5, 0, 0.866});
  const auto x = noise(16000 * 4);
  std::vector<float> out;
  for (auto _ : state) {
    for (size_t i = 0; i < x.size(); i += 640 * 4) {
      out.clear();
      (void)(*b)->process(std::span<const float>(x).subspan(i, 640 * 4), out);
      benchmark::DoNotOptimize(out.data());
    }
  }
  state.SetItemsProcessed(state.iterations());
  state.SetLabel(state.range(0) == 0 ? "delay-and-sum" : "superdirective");
}
BENCHMARK(BM_Beamform4ch16k)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

void BM_Steer(benchmark::State& state) {
  BeamformerOptions o;
  o.mic_positions_m = {{0.113, 0, 0}, {-0.036, 0, 0}, {-0.076, 0, 0}, {-0.113, 0, 0}};
  o.method = static_cast<BeamformerMethod>(state.range(0));
  auto b = Beamformer::create(o);
  double a = 0;
  for (auto _ : state) {
    a += 0.01;
    (*b)->steer({std::sin(a), 0, std::cos(a)});
  }
  state.SetLabel(state.range(0) == 0 ? "delay-and-sum" : "superdirective");
}
BENCHMARK(BM_Steer)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

void BM_Segment4ch16k(benchmark::State& state) {
  UtteranceSegmenterOptions o;
  o.channels = 4;
  auto s = UtteranceSegmenter::create(o);
  const auto x = noise(16000 * 4);
  std::vector<Utterance> out;
  int64_t k = 0;
  for (auto _ : state) {
    for (size_t i = 0; i < x.size(); i += 640 * 4) {
      out.clear();
      (void)(*s)->push(std::span<const float>(x).subspan(i, 640 * 4),
                       Timestamp::from_ns(0) + frames_to_duration(k, 16000), out);
      k += 640;
    }
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_Segment4ch16k)->Unit(benchmark::kMillisecond);

// Issue 16: the robot-voice gate and the noise suppressor, per second of 4-channel 16 kHz audio
// with a mono 16 kHz reference, in 40 ms chunks. The gate runs in each of the three audio
// analysers (sound_direction, speech, voice_id): 3 gates; the suppressor on all 4 channels
// (the worst case: voice_id filters one channel, speech one beamformed utterance).
// Budget: 5 % of one core = 50 ms per audio second.
void BM_RobotGateAndNoiseSuppressor4ch16k(benchmark::State& state) {
  const int rate = 16000, ch = 4;
  const bool gate = state.range(0) != 0, suppress = state.range(1) != 0;
  const auto mic = noise(static_cast<size_t>(rate * ch));
  auto ref = noise(static_cast<size_t>(rate), 2);
  for (size_t i = ref.size() / 2; i < ref.size(); ++i) ref[i] = 0;  // robot speaks half the time
  std::vector<ReferenceGate> gates(3);
  NoiseSuppressorOptions no;
  no.channels = ch;
  auto ns = NoiseSuppressor::create(no);
  const size_t chunk = static_cast<size_t>(rate / 25);
  std::vector<float> out;
  int64_t k = 0;
  for (auto _ : state) {
    for (size_t i = 0; i < static_cast<size_t>(rate); i += chunk) {
      const Timestamp t = Timestamp::from_ns(0) + frames_to_duration(k, rate);
      if (gate)
        for (auto& g : gates) {
          (void)g.push_reference(std::span<const float>(ref).subspan(i, chunk), 1, rate, t);
          g.push_microphone(std::span<const float>(mic).subspan(i * ch, chunk * ch), ch, rate, t);
          benchmark::DoNotOptimize(g.active(t));
          g.forget_before(t - Duration::from_seconds(30));
        }
      if (suppress) {
        out.clear();
        (*ns)->process(std::span<const float>(mic).subspan(i * ch, chunk * ch), out);
        benchmark::DoNotOptimize(out.data());
      }
      k += static_cast<int64_t>(chunk);
    }
  }
  state.SetItemsProcessed(state.iterations());
  state.SetLabel(fmt::format("per audio second: gate x3 {}, noise suppressor 4 ch {}",
                             gate ? "on" : "off", suppress ? "on" : "off"));
}
BENCHMARK(BM_RobotGateAndNoiseSuppressor4ch16k)
    ->Args({1, 1})
    ->Args({1, 0})
    ->Args({0, 1})
    ->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
