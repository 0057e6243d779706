// speech_synth: writes a synthetic spoken-word set with espeak-ng (Debian package espeak-ng) in
// the `speech-commands` or `fsdd` layout of `dreamsense eval speech`, for tests and for tuning.
// Synthetic speech is NOT the real test: it is far more regular than people talking into
// phones; it checks the plumbing, the rejection of other words and the silence check.
//
//   speech_synth OUT [--layout speech-commands|fsdd] [--per-class N] [--voices tune|test|all]
//                [--seed S] [--rate HZ (fsdd only, default 8000)] [--require] [--fresh]
//   --voices also takes a comma-separated list of espeak-ng voices (e.g. one talker).
//
// Voices are espeak-ng accents x variants, split into two disjoint halves (accents and
// variants both differ) so that thresholds tuned on `tune` can be reported on `test`.
// speech-commands: OUT/<class>/<voice>_<i>.wav, 1 s, 16 kHz, the word at a random offset,
//   speed 120-200 wpm, pitch 30-70, white/pink/brown noise at 10-35 dB SNR, peak -30..-3 dBFS;
//   _unknown_ = bed bird cat dog happy house marvin sheila tree wow (one per clip, cycled);
//   _silence_ = noise only (white, pink, brown, hum, modulated pink, near-silence),
//   -75..-25 dBFS RMS.
// fsdd: OUT/recordings/<digit>_<voice>_<i>.wav, 8 kHz, trimmed like FSDD, light noise.
// Exit 0 with a message and nothing written when espeak-ng is not installed (exit code 77
// with --require).

#include "dreamsense/speech/recognizer.hpp"

#include <sndfile.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <random>
#include <sstream>
#include <string>
#include <unistd.h>
#include <vector>

namespace {

namespace fs = std::filesystem;
using dreamsense::speech::resample;

const std::vector<std::string> kCommands = {"yes",   "no", "up",  "down", "left",
                                            "right", "on", "off", "stop", "go"};
const std::vector<std::string> kUnknown = {"bed",   "bird",   "cat",    "dog",  "happy",
                                           "house", "marvin", "sheila", "tree", "wow"};
const std::vector<std::string> kDigits = {"zero", "one", "two",   "three", "four",
                                          "five", "six", "seven", "eight", "nine"};

std::vector<std::string> voices(const std::string& set) {
  const std::vector<std::string> tune_accents = {"en-us", "en-gb-x-rp", "en-029", "en-gb-x-gbclan"};
  const std::vector<std::string> test_accents = {"en-gb", "en-us-nyc", "en-gb-scotland",
                                                 "en-gb-x-gbcwmd"};
  const std::vector<std::string> tune_variants = {"m1", "m3", "m5", "f2", "f4", "klatt"};
  const std::vector<std::string> test_variants = {"m2", "m4", "m6", "f1", "f3", "klatt3"};
  std::vector<std::string> out;
  auto add = [&](const auto& accents, const auto& variants) {
    for (const auto& a : accents)
      for (const auto& v : variants) out.push_back(a + "+" + v);
  };
  if (set == "tune" || set == "all") add(tune_accents, tune_variants);
  if (set == "test" || set == "all") add(test_accents, test_variants);
  if (out.empty()) {  // an explicit list of espeak-ng voices, e.g. "en-gb-scotland+m2" (one talker)
    std::stringstream ss(set);
    std::string v;
    while (std::getline(ss, v, ','))
      if (!v.empty()) out.push_back(v);
  }
  return out;
}

bool have_espeak() { return std::system("espeak-ng --version >/dev/null 2>&1") == 0; }

// Synthesises one word; returns mono samples at `rate` (empty on failure).
std::vector<double> speak(const std::string& word, const std::string& voice, int speed, int pitch,
                          int rate, const fs::path& tmp) {
  const std::string cmd = "espeak-ng -v '" + voice + "' -s " + std::to_string(speed) + " -p " +
                          std::to_string(pitch) + " -w '" + tmp.string() + "' '" + word +
                          "' >/dev/null 2>&1";
  if (std::system(cmd.c_str()) != 0) return {};
  SF_INFO info{};
  SNDFILE* sf = sf_open(tmp.string().c_str(), SFM_READ, &info);
  if (!sf) return {};
  std::vector<int16_t> s(static_cast<size_t>(info.frames) * info.channels);
  sf_read_short(sf, s.data(), static_cast<sf_count_t>(s.size()));
  sf_close(sf);
  std::vector<int16_t> mono(static_cast<size_t>(info.frames));
  for (size_t i = 0; i < mono.size(); ++i) mono[i] = s[i * info.channels];
  const auto r = resample(mono, info.samplerate, rate);
  // Trim to the first/last sample within 45 dB of the peak (FSDD is trimmed similarly).
  int16_t peak = 1;
  for (int16_t v : r) peak = std::max<int16_t>(peak, static_cast<int16_t>(std::abs(v)));
  const double thr = peak * std::pow(10.0, -45.0 / 20);
  size_t b = 0, e = r.size();
  while (b < e && std::abs(r[b]) < thr) ++b;
  while (e > b && std::abs(r[e - 1]) < thr) --e;
  std::vector<double> out(r.begin() + static_cast<std::ptrdiff_t>(b),
                          r.begin() + static_cast<std::ptrdiff_t>(e));
  for (auto& v : out) v /= peak;  // peak 1
  return out;
}

enum class Noise { kWhite, kPink, kBrown, kHum, kModulated, kNearSilence };

// Unit-RMS noise of the given colour.
std::vector<double> noise(Noise type, size_t n, int rate, std::mt19937& g) {
  std::normal_distribution<double> nd(0, 1);
  std::vector<double> x(n);
  double b0 = 0, b1 = 0, b2 = 0, brown = 0;
  std::uniform_real_distribution<double> u(0, 1);
  const double f_hum = u(g) < 0.5 ? 50 : 60, f_mod = 0.5 + 3 * u(g);
  for (size_t i = 0; i < n; ++i) {
    const double w = nd(g);
    switch (type) {
      case Noise::kWhite:
      case Noise::kNearSilence:
        x[i] = w;
        break;
      case Noise::kPink:
      case Noise::kModulated:  // Paul Kellet's economy pink filter
        b0 = 0.99765 * b0 + w * 0.0990460;
        b1 = 0.96300 * b1 + w * 0.2965164;
        b2 = 0.57000 * b2 + w * 1.0526913;
        x[i] = b0 + b1 + b2 + w * 0.1848;
        if (type == Noise::kModulated)
          x[i] *= 0.3 + 0.7 * std::abs(std::sin(2 * M_PI * f_mod * i / rate));
        break;
      case Noise::kBrown:
        brown = 0.995 * brown + w;
        x[i] = brown;
        break;
      case Noise::kHum: {
        double h = 0;
        for (int k = 1; k <= 5; ++k) h += std::sin(2 * M_PI * f_hum * k * i / rate) / k;
        x[i] = h + 0.05 * w;
        break;
      }
    }
  }
  double e = 0;
  for (double v : x) e += v * v;
  const double rms = std::sqrt(e / std::max<size_t>(1, n));
  for (auto& v : x) v /= rms > 0 ? rms : 1;
  return x;
}

bool write_wav(const fs::path& p, const std::vector<double>& x, int rate) {
  SF_INFO info{};
  info.samplerate = rate;
  info.channels = 1;
  info.format = SF_FORMAT_WAV | SF_FORMAT_PCM_16;
  SNDFILE* sf = sf_open(p.string().c_str(), SFM_WRITE, &info);
  if (!sf) return false;
  std::vector<int16_t> s(x.size());
  for (size_t i = 0; i < x.size(); ++i)
    s[i] = static_cast<int16_t>(std::clamp(std::lround(x[i] * 32767.0), -32768L, 32767L));
  sf_write_short(sf, s.data(), static_cast<sf_count_t>(s.size()));
  sf_close(sf);
  return true;
}

double db_to_amp(double db) { return std::pow(10.0, db / 20); }

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2 || std::string(argv[1]) == "--help") {
    std::fprintf(stderr,
                 "usage: speech_synth OUT [--layout speech-commands|fsdd] [--per-class N] "
                 "[--voices tune|test|all|V1,V2] [--seed S] [--rate HZ] [--require] [--fresh]\n");
    return argc < 2 ? 2 : 0;
  }
  const fs::path out = argv[1];
  std::string layout = "speech-commands", voice_set = "test";
  int per_class = 10, fsdd_rate = 8000;
  unsigned seed = 1;
  bool require = false, fresh = false;
  for (int i = 2; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "speech_synth: %s needs a value\n", a.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--layout")
      layout = next();
    else if (a == "--per-class")
      per_class = std::stoi(next());
    else if (a == "--voices")
      voice_set = next();
    else if (a == "--seed")
      seed = static_cast<unsigned>(std::stoul(next()));
    else if (a == "--rate")  // fsdd layout only: 16000 gives a wide-band control set
      fsdd_rate = std::stoi(next());
    else if (a == "--require")
      require = true;
    else if (a == "--fresh")  // delete the layout's folders in OUT first
      fresh = true;
    else {
      std::fprintf(stderr, "speech_synth: unknown argument %s\n", a.c_str());
      return 2;
    }
  }
  if (layout != "speech-commands" && layout != "fsdd") {
    std::fprintf(stderr, "speech_synth: --layout must be speech-commands or fsdd\n");
    return 2;
  }
  const auto vs = voices(voice_set);
  if (vs.empty() || per_class <= 0) {
    std::fprintf(stderr, "speech_synth: --voices tune|test|all|V1,V2 and --per-class > 0\n");
    return 2;
  }
  if (!have_espeak()) {
    std::fprintf(stderr,
                 "speech_synth: espeak-ng is not installed (Debian package espeak-ng); "
                 "nothing written\n");
    return require ? 77 : 0;
  }
  std::mt19937 g(seed);
  std::uniform_real_distribution<double> u(0, 1);
  auto uni = [&](double a, double b) { return a + (b - a) * u(g); };
  if (fresh) {
    std::error_code ec;
    for (const auto& w : kCommands) fs::remove_all(out / w, ec);
    for (const char* d : {"_unknown_", "_silence_", "recordings"}) fs::remove_all(out / d, ec);
  }
  fs::create_directories(out);
  const fs::path tmp = out / (".espeak_" + std::to_string(getpid()) + ".wav");
  int written = 0;

  auto voice_name = [](std::string v) {
    std::replace(v.begin(), v.end(), '+', '-');
    return v;
  };

  if (layout == "fsdd") {
    const int rate = fsdd_rate;
    fs::create_directories(out / "recordings");
    for (size_t d = 0; d < kDigits.size(); ++d)
      for (int i = 0; i < per_class; ++i) {
        const std::string& voice = vs[static_cast<size_t>(i) % vs.size()];
        auto x = speak(kDigits[d], voice, static_cast<int>(uni(130, 190)),
                       static_cast<int>(uni(25, 75)), rate, tmp);
        if (x.empty()) continue;
        const double gain = db_to_amp(uni(-12, -3));
        const auto n = noise(Noise::kWhite, x.size(), rate, g);
        for (size_t k = 0; k < x.size(); ++k) x[k] = gain * (x[k] + db_to_amp(-45) * n[k]);
        const fs::path p = out / "recordings" /
                           (std::to_string(d) + "_" + voice_name(voice) + "_" +
                            std::to_string(i / static_cast<int>(vs.size())) + ".wav");
        written += write_wav(p, x, rate);
      }
  } else {
    const int rate = 16000;
    const size_t clip = rate;
    auto make_word_clip = [&](const std::string& word, const std::string& voice) {
      std::vector<double> w;
      for (int speed = static_cast<int>(uni(120, 200)); speed <= 400; speed += 40) {
        w = speak(word, voice, speed, static_cast<int>(uni(30, 70)), rate, tmp);
        if (w.size() <= clip * 9 / 10) break;  // fits into 0.9 s
      }
      std::vector<double> x(clip, 0.0);
      if (w.empty()) return std::vector<double>{};
      w.resize(std::min(w.size(), clip));
      const size_t off = static_cast<size_t>(uni(0, 1) * static_cast<double>(clip - w.size()));
      for (size_t k = 0; k < w.size(); ++k) x[off + k] = w[k];
      double e = 0;
      for (double v : w) e += v * v;
      const double speech_rms = std::sqrt(e / static_cast<double>(w.size()));
      const Noise type = static_cast<Noise>(static_cast<int>(uni(0, 3)));  // white/pink/brown
      const auto n = noise(type, clip, rate, g);
      const double noise_amp = speech_rms * db_to_amp(-uni(10, 35));
      double peak = 1e-9;
      for (size_t k = 0; k < clip; ++k) {
        x[k] += noise_amp * n[k];
        peak = std::max(peak, std::abs(x[k]));
      }
      const double gain = db_to_amp(uni(-30, -3)) / peak;
      for (auto& v : x) v *= gain;
      return x;
    };
    for (const auto& word : kCommands) {
      fs::create_directories(out / word);
      for (int i = 0; i < per_class; ++i) {
        const std::string& voice = vs[(static_cast<size_t>(i) * 7 + word.size()) % vs.size()];
        const auto x = make_word_clip(word, voice);
        if (!x.empty())
          written += write_wav(out / word / (voice_name(voice) + "_" + std::to_string(i) + ".wav"),
                               x, rate);
      }
    }
    fs::create_directories(out / "_unknown_");
    for (int i = 0; i < per_class; ++i) {
      const std::string& word = kUnknown[static_cast<size_t>(i) % kUnknown.size()];
      const std::string& voice = vs[(static_cast<size_t>(i) * 5 + 3) % vs.size()];
      const auto x = make_word_clip(word, voice);
      if (!x.empty())
        written += write_wav(
            out / "_unknown_" / (word + "_" + voice_name(voice) + "_" + std::to_string(i) + ".wav"),
            x, rate);
    }
    fs::create_directories(out / "_silence_");
    const char* names[] = {"white", "pink", "brown", "hum", "modulated", "near_silence"};
    for (int i = 0; i < per_class; ++i) {
      const Noise type = static_cast<Noise>(i % 6);
      auto x = noise(type, clip, rate, g);
      const double rms = type == Noise::kNearSilence ? db_to_amp(-85) : db_to_amp(uni(-75, -25));
      for (auto& v : x) v *= rms;
      written += write_wav(
          out / "_silence_" /
              (std::string(names[static_cast<int>(type)]) + "_" + std::to_string(i) + ".wav"),
          x, rate);
    }
  }
  std::error_code ec;
  fs::remove(tmp, ec);
  std::fprintf(stderr, "speech_synth: wrote %d clips (%s layout, %s voices) to %s\n", written,
               layout.c_str(), voice_set.c_str(), out.string().c_str());
  return written > 0 ? 0 : 1;
}
