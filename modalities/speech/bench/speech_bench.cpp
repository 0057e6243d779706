// Speech micro-benchmarks (Google Benchmark). Audio is loaded and the grammar compiled before
// the timed loop; the counter `rtf` is decode time per second of audio (real-time factor,
// one thread). Run: build/bench/speech_bench
//   BM_DecodeGoForward      goforward.raw (2.8 s, 16 kHz) under goforward.gram, with the
//                           phone-loop rejection and its confidence pass (pocketsphinx layout)
//   BM_DecodeGoForward8k    the same clip at 8 kHz, resampled inside (soxr | sinc)
//   BM_DecodeCommand        a 1 s clip under the 10-word Speech Commands grammar
//   BM_DecodeDigitTidigits  a 1 s clip under the digit grammar, TIDIGITS model at 8 kHz (fsdd)
//   BM_Resample8to16        3 s of audio, soxr | sinc
//   BM_DetectSpeech         the silence check on 1 s
#include "dreamsense/audio/speech_presence.hpp"
#include "dreamsense/speech/recognizer.hpp"

#include <benchmark/benchmark.h>

#include <filesystem>
#include <fstream>
#include <memory>

namespace {

namespace fs = std::filesystem;
using namespace dreamsense::speech;

const fs::path kData = "/usr/share/pocketsphinx/test/data";  // pocketsphinx-testdata
const fs::path kTidigits = kData / "tidigits/hmm";

std::vector<int16_t> read_raw(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::vector<char> b((std::istreambuf_iterator<char>(in)), {});
  std::vector<int16_t> s(b.size() / 2);
  std::memcpy(s.data(), b.data(), s.size() * 2);
  return s;
}

void set_rtf(benchmark::State& state, double audio_seconds) {
  state.counters["rtf"] =
      benchmark::Counter(static_cast<double>(state.iterations()) * audio_seconds,
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

void decode_loop(benchmark::State& state, const RecognizerOptions& o, const Grammar& g,
                 const std::vector<int16_t>& audio, int rate) {
  auto rec = Recognizer::create(o, g);
  if (!rec) {
    state.SkipWithError(rec.error().message.c_str());
    return;
  }
  for (auto _ : state) {
    auto d = (*rec)->decode(audio, rate);
    benchmark::DoNotOptimize(d);
  }
  set_rtf(state, static_cast<double>(audio.size()) / rate);
}

bool have(benchmark::State& state, const fs::path& p) {
  if (fs::exists(p)) return true;
  state.SkipWithError(("missing " + p.string()).c_str());
  return false;
}

void BM_DecodeGoForward(benchmark::State& state) {
  if (!have(state, RecognizerOptions{}.model_dir / "mdef") || !have(state, kData / "goforward.raw"))
    return;
  auto g = Grammar::from_file(kData / "goforward.gram");
  decode_loop(state, {}, *g, read_raw(kData / "goforward.raw"), 16000);
}
BENCHMARK(BM_DecodeGoForward)->Unit(benchmark::kMillisecond);

void BM_DecodeGoForward8k(benchmark::State& state) {
  if (!have(state, RecognizerOptions{}.model_dir / "mdef") || !have(state, kData / "goforward.raw"))
    return;
  auto g = Grammar::from_file(kData / "goforward.gram");
  const auto audio8 = resample(read_raw(kData / "goforward.raw"), 16000, 8000);
  RecognizerOptions o;
  o.resampler = state.range(0) ? Resampler::kSoxr : Resampler::kSinc;
  state.SetLabel(std::string(to_string(o.resampler)));
  decode_loop(state, o, *g, audio8, 8000);
}
BENCHMARK(BM_DecodeGoForward8k)->Arg(1)->Arg(0)->Unit(benchmark::kMillisecond);

// 1 s: the first second of goforward.raw ("go forward").
void BM_DecodeCommand(benchmark::State& state) {
  if (!have(state, RecognizerOptions{}.model_dir / "mdef") || !have(state, kData / "goforward.raw"))
    return;
  auto g = Grammar::from_jsgf(
      "#JSGF V1.0;\ngrammar c;\npublic <c> = yes | no | up | down | left | right | on | off | "
      "stop | go;\n");
  RecognizerOptions o;
  o.garbage_phone_weight = 0.01;
  auto audio = read_raw(kData / "goforward.raw");
  audio.resize(16000);
  decode_loop(state, o, *g, audio, 16000);
}
BENCHMARK(BM_DecodeCommand)->Unit(benchmark::kMillisecond);

void BM_DecodeDigitTidigits(benchmark::State& state) {
  if (!have(state, kTidigits / "mdef") || !have(state, kData / "tidigits/dhd.2934z.raw")) return;
  auto g = Grammar::from_jsgf(
      "#JSGF V1.0;\ngrammar d;\npublic <d> = zero | oh | one | two | three | four | five | six "
      "| seven | eight | nine;\n");
  RecognizerOptions o;
  o.model_dir = kTidigits;
  o.dictionary = kData / "tidigits/lm/tidigits.dic";
  o.model_rate_hz = 8000;
  o.reject_out_of_grammar = false;
  o.frequency_warp = 1.6;
  auto audio = resample(read_raw(kData / "tidigits/dhd.2934z.raw"), 16000, 8000);
  audio.resize(8000);
  decode_loop(state, o, *g, audio, 8000);
}
BENCHMARK(BM_DecodeDigitTidigits)->Unit(benchmark::kMillisecond);

void BM_Resample8to16(benchmark::State& state) {
  std::vector<int16_t> in(24000);
  for (size_t i = 0; i < in.size(); ++i)
    in[i] = static_cast<int16_t>(8000 * std::sin(0.3 * static_cast<double>(i)));
  const Resampler m = state.range(0) ? Resampler::kSoxr : Resampler::kSinc;
  state.SetLabel(std::string(to_string(m)));
  for (auto _ : state) benchmark::DoNotOptimize(resample(in, 8000, 16000, m));
  set_rtf(state, 3.0);
}
BENCHMARK(BM_Resample8to16)->Arg(1)->Arg(0)->Unit(benchmark::kMicrosecond);

void BM_DetectSpeech(benchmark::State& state) {
  if (!have(state, kData / "goforward.raw")) return;
  auto audio = read_raw(kData / "goforward.raw");
  audio.resize(16000);
  for (auto _ : state) benchmark::DoNotOptimize(dreamsense::audio::detect_speech(audio, 16000));
  set_rtf(state, 1.0);
}
BENCHMARK(BM_DetectSpeech)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
