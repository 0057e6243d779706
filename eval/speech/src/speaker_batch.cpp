#include "dreamsense/eval/speaker_batch.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <numbers>
#include <numeric>

namespace dreamsense::speech {
namespace {

void fft(std::vector<std::complex<double>>& a) {  // in place, size a power of two
  const size_t n = a.size();
  for (size_t i = 1, j = 0; i < n; ++i) {
    size_t bit = n >> 1;
    for (; j & bit; bit >>= 1) j ^= bit;
    j ^= bit;
    if (i < j) std::swap(a[i], a[j]);
  }
  for (size_t len = 2; len <= n; len <<= 1) {
    const double ang = -2 * std::numbers::pi / static_cast<double>(len);
    const std::complex<double> wl(std::cos(ang), std::sin(ang));
    for (size_t i = 0; i < n; i += len) {
      std::complex<double> w(1);
      for (size_t j = 0; j < len / 2; ++j) {
        const auto u = a[i + j], v = a[i + j + len / 2] * w;
        a[i + j] = u + v;
        a[i + j + len / 2] = u - v;
        w *= wl;
      }
    }
  }
}

double mel(double hz) { return 2595 * std::log10(1 + hz / 700); }
double mel_inverse(double m) { return 700 * (std::pow(10, m / 2595) - 1); }

}  // namespace

DtwFeatures dtw_features(std::span<const int16_t> s, int rate) {
  constexpr int kFilters = 24, kCepstra = 13, kDelta = 2;
  constexpr double kLowHz = 100, kHighHz = 3800;
  if (rate < 2 * kHighHz) return {};
  const size_t win = static_cast<size_t>(rate / 40), hop = static_cast<size_t>(rate / 100);
  size_t nfft = 1;
  while (nfft < win) nfft <<= 1;
  std::vector<double> edges(kFilters + 2);
  for (int i = 0; i < kFilters + 2; ++i)
    edges[i] = mel_inverse(mel(kLowHz) + (mel(kHighHz) - mel(kLowHz)) * i / (kFilters + 1));
  std::vector<double> x(s.size()), window(win);
  for (size_t i = 0; i < s.size(); ++i) x[i] = s[i] - (i ? 0.97 * s[i - 1] : 0.0);
  for (size_t i = 0; i < win; ++i)
    window[i] = 0.54 - 0.46 * std::cos(2 * std::numbers::pi * i / static_cast<double>(win - 1));
  DtwFeatures st;
  for (size_t b = 0; b + win <= x.size(); b += hop) {
    std::vector<std::complex<double>> a(nfft);
    double energy = 0;
    for (size_t i = 0; i < win; ++i) {
      a[i] = x[b + i] * window[i];
      energy += std::norm(a[i]);
    }
    fft(a);
    std::vector<double> fb(kFilters, 1e-3);
    for (size_t k = 0; k <= nfft / 2; ++k) {
      const double f = static_cast<double>(k) * rate / static_cast<double>(nfft),
                   p = std::norm(a[k]);
      for (int m = 0; m < kFilters; ++m) {
        const double l = edges[m], c = edges[m + 1], r = edges[m + 2];
        if (f > l && f < r) fb[m] += p * (f < c ? (f - l) / (c - l) : (r - f) / (r - c));
      }
    }
    std::vector<float> c(kCepstra);
    for (int i = 1; i < kCepstra; ++i) {
      double acc = 0;
      for (int m = 0; m < kFilters; ++m)
        acc += std::log(fb[m]) * std::cos(std::numbers::pi * i * (m + 0.5) / kFilters);
      c[i] = static_cast<float>(acc);
    }
    c[0] = static_cast<float>(std::log(energy + 1e-3));
    st.push_back(std::move(c));
  }
  if (st.empty()) return st;
  std::vector<double> mean(kCepstra, 0);
  float peak = -std::numeric_limits<float>::infinity();
  for (const auto& f : st) {
    for (int i = 0; i < kCepstra; ++i) mean[i] += f[i];
    peak = std::max(peak, f[0]);
  }
  for (auto& f : st) {
    for (int i = 1; i < kCepstra; ++i) f[i] -= static_cast<float>(mean[i] / st.size());
    f[0] -= peak;
  }
  const int n = static_cast<int>(st.size());
  DtwFeatures out(st.size());
  for (int t = 0; t < n; ++t) {
    out[t] = st[t];
    for (int i = 0; i < kCepstra; ++i) {
      double d = 0;
      for (int k = 1; k <= kDelta; ++k)
        d += k * (st[std::min(n - 1, t + k)][i] - st[std::max(0, t - k)][i]);
      out[t].push_back(static_cast<float>(d / 10));  // 2 * sum k^2 = 10
    }
  }
  return out;
}

double dtw_distance(const DtwFeatures& a, const DtwFeatures& b) {
  if (a.empty() || b.empty()) return std::numeric_limits<double>::infinity();
  const size_t n = a.size(), m = b.size();
  constexpr double kInf = std::numeric_limits<double>::infinity();
  std::vector<double> prev(m + 1, kInf), cur(m + 1);
  prev[0] = 0;
  for (size_t i = 1; i <= n; ++i) {
    cur[0] = kInf;
    for (size_t j = 1; j <= m; ++j) {
      const auto& x = a[i - 1];
      const auto& y = b[j - 1];
      double d = 0;
      for (size_t k = 0; k < std::min(x.size(), y.size()); ++k) {
        const double t = x[k] - y[k];
        d += t * t;
      }
      cur[j] = std::sqrt(d) + std::min({prev[j], cur[j - 1], prev[j - 1]});
    }
    std::swap(prev, cur);
  }
  return prev[m] / static_cast<double>(n + m);
}

std::vector<int> neighbour_vote(const std::vector<std::vector<double>>& scores,
                                const std::vector<std::vector<double>>& distances,
                                const NeighbourVoteOptions& o) {
  // Posteriors; log floors as in the tuning runs: 1e-12 for the clip itself, 1e-6 for a
  // neighbour (one confidently contrary neighbour cannot veto a word).
  const size_t n = scores.size();
  std::vector<std::vector<double>> p(n);
  for (size_t i = 0; i < n; ++i) {
    const auto& s = scores[i];
    double best = -std::numeric_limits<double>::infinity();
    for (double v : s)
      if (std::isfinite(v)) best = std::max(best, v);
    double z = 0;
    for (double v : s) {
      p[i].push_back(std::isfinite(v) ? std::exp((v - best) / o.temperature) : 0.0);
      z += p[i].back();
    }
    for (double& v : p[i]) v = z > 0 ? v / z : 1.0 / static_cast<double>(s.size());
  }
  std::vector<int> out(n, -1);
  for (size_t i = 0; i < n; ++i) {
    std::vector<double> acc(p[i].size());
    for (size_t w = 0; w < acc.size(); ++w) acc[w] = std::log(p[i][w] + 1e-12);
    std::vector<size_t> others;
    for (size_t j = 0; j < n; ++j)
      if (j != i) others.push_back(j);
    const size_t k =
        std::min<size_t>(others.size(), static_cast<size_t>(std::max(0, o.neighbours)));
    size_t kept = 0;
    if (k > 0 && o.weight > 0) {
      std::partial_sort(others.begin(), others.begin() + static_cast<std::ptrdiff_t>(k),
                        others.end(),
                        [&](size_t a, size_t b) { return distances[i][a] < distances[i][b]; });
      const double limit = distances[i][others[0]] * o.max_distance_ratio;
      while (kept < k && std::isfinite(distances[i][others[kept]]) &&
             distances[i][others[kept]] <= limit)
        ++kept;
      for (size_t q = 0; q < kept; ++q)
        for (size_t w = 0; w < acc.size() && w < p[others[q]].size(); ++w)
          acc[w] += o.weight / static_cast<double>(kept) * std::log(p[others[q]][w] + 1e-6);
    }
    // A clip without any word path and without neighbours has no answer.
    const bool own =
        std::any_of(scores[i].begin(), scores[i].end(), [](double v) { return std::isfinite(v); });
    if (!acc.empty() && (own || kept > 0))
      out[i] = static_cast<int>(std::max_element(acc.begin(), acc.end()) - acc.begin());
  }
  return out;
}

}  // namespace dreamsense::speech
