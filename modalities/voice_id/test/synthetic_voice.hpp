#pragma once
// Synthetic "speakers" for tests: a glottal pulse train (f0 with vibrato and jitter, plus a
// little aspiration noise) through three formant resonators, moving through a random sequence
// of vowels. Speakers differ in f0 and in vocal-tract length (all formants scaled), which is
// what MFCC-based speaker models pick up. Deterministic for a given seed.

#include <opencv2/core.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

namespace dreamsense::voice_id::testing {

struct SyntheticSpeaker {
  double f0_hz = 120;
  double formant_scale = 1.0;  // 1 = adult male-like; > 1 = shorter vocal tract
};

// `seconds` of voiced speech between lead/trail seconds of faint noise, at `rate` Hz.
inline std::vector<float> synth_utterance(const SyntheticSpeaker& sp, double seconds, int rate,
                                          uint32_t seed, double lead_s = 0.2,
                                          double trail_s = 0.2) {
  static const double kVowels[][3] = {{730, 1090, 2440}, {270, 2290, 3010}, {300, 870, 2240},
                                      {530, 1840, 2480}, {570, 840, 2410},  {660, 1720, 2410}};
  static const double kBandwidth[3] = {90, 110, 160};
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> vowel(0, 5);
  std::uniform_real_distribution<double> seg(0.12, 0.3);
  std::normal_distribution<double> n01(0.0, 1.0);
  const size_t lead = static_cast<size_t>(lead_s * rate),
               body = static_cast<size_t>(seconds * rate),
               trail = static_cast<size_t>(trail_s * rate);
  std::vector<float> out(lead + body + trail);
  for (auto& v : out) v = static_cast<float>(1e-4 * n01(rng));
  double phase = 0, y[3][2] = {{0, 0}, {0, 0}, {0, 0}};
  size_t next_change = 0;
  double a1[3] = {0, 0, 0}, a2[3] = {0, 0, 0}, g[3] = {1, 1, 1};
  for (size_t i = 0; i < body; ++i) {
    if (i >= next_change) {
      const auto& f = kVowels[vowel(rng)];
      for (int k = 0; k < 3; ++k) {
        const double fk = f[k] * sp.formant_scale * (1 + 0.03 * n01(rng));
        const double r = std::exp(-CV_PI * kBandwidth[k] / rate);
        a1[k] = 2 * r * std::cos(2 * CV_PI * fk / rate);
        a2[k] = -r * r;
        g[k] = 1 - r;
      }
      next_change = i + static_cast<size_t>(seg(rng) * rate);
    }
    const double t = static_cast<double>(i) / rate;
    const double f0 = sp.f0_hz * (1 + 0.04 * std::sin(2 * CV_PI * 4.5 * t)) * (1 + 0.01 * n01(rng));
    phase += f0 / rate;
    double x = 0.02 * n01(rng);
    if (phase >= 1) {
      phase -= 1;
      x += 1.0;
    }
    // Cascade of the three resonators.
    for (int k = 0; k < 3; ++k) {
      const double v = g[k] * x + a1[k] * y[k][0] + a2[k] * y[k][1];
      y[k][1] = y[k][0];
      y[k][0] = v;
      x = v;
    }
    // Syllable-like amplitude envelope (4 Hz).
    const double env = 0.6 + 0.4 * std::sin(2 * CV_PI * 4 * t);
    out[lead + i] += static_cast<float>(x * env);
  }
  // Normalise the voiced part to a peak of 0.5.
  double peak = 1e-9;
  for (size_t i = lead; i < lead + body; ++i) peak = std::max(peak, std::abs(double(out[i])));
  for (size_t i = lead; i < lead + body; ++i) out[i] = static_cast<float>(out[i] * 0.5 / peak);
  return out;
}

}  // namespace dreamsense::voice_id::testing
