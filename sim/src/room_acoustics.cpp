#include "dreamsense/sim/room_acoustics.hpp"

#include "dreamsense/audio/fft.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <map>
#include <mutex>
#include <numeric>
#include <random>

namespace dreamsense::sim {
namespace {

// Smallest 2^a 3^b 5^c >= n (FFTW is fast on these sizes).
size_t good_fft_size(size_t n) {
  size_t best = 1;
  while (best < n) best *= 2;
  for (size_t p3 = 1; p3 < best; p3 *= 3)
    for (size_t p35 = p3; p35 < best; p35 *= 5) {
      size_t v = p35;
      while (v < n) v *= 2;
      best = std::min(best, v);
    }
  return best;
}

// Box-Muller on mt19937_64 output: identical on every platform (std distributions are not).
class GaussianSource {
 public:
  explicit GaussianSource(uint64_t seed) : rng_(seed) {}
  double next() {
    if (has_spare_) {
      has_spare_ = false;
      return spare_;
    }
    double u1 = 0;
    do {
      u1 = static_cast<double>(rng_() >> 11) * 0x1.0p-53;
    } while (u1 <= 0);
    const double u2 = static_cast<double>(rng_() >> 11) * 0x1.0p-53;
    const double r = std::sqrt(-2.0 * std::log(u1));
    spare_ = r * std::sin(2 * CV_PI * u2);
    has_spare_ = true;
    return r * std::cos(2 * CV_PI * u2);
  }

 private:
  std::mt19937_64 rng_;
  double spare_ = 0;
  bool has_spare_ = false;
};

bool inside(const cv::Vec3d& p, const cv::Vec3d& size) {
  for (int i = 0; i < 3; ++i)
    if (!(p[i] > 0 && p[i] < size[i])) return false;
  return true;
}

}  // namespace

Status RoomOptions::check() const {
  std::string bad;
  for (int i = 0; i < 3; ++i)
    if (!(size_m[i] > 0)) bad += fmt::format(" size_m[{}] must be > 0;", i);
  if (!(rt60_s >= 0) || rt60_s > 10) bad += " rt60_s must be in [0, 10];";
  if (max_order < -1) bad += " max_order must be >= -1;";
  if (!(max_image_distance_m >= 0)) bad += " max_image_distance_m must be >= 0;";
  if (!(sample_rate_hz > 0)) bad += " sample_rate_hz must be > 0;";
  if (!(speed_of_sound_m_s > 0)) bad += " speed_of_sound_m_s must be > 0;";
  if (sinc_half_width < 2 || sinc_half_width > 128) bad += " sinc_half_width must be in [2, 128];";
  if (bad.empty() && rt60_s > 0) {
    const double V = size_m[0] * size_m[1] * size_m[2];
    const double S = 2 * (size_m[0] * size_m[1] + size_m[0] * size_m[2] + size_m[1] * size_m[2]);
    if (0.161 * V / (S * rt60_s) > 1)
      bad += fmt::format(" rt60_s {} is shorter than Sabine allows for this room (min {:.3f});",
                         rt60_s, 0.161 * V / S);
  }
  if (!bad.empty()) return make_error(ErrorCode::kInvalidArgument, "RoomOptions:{}", bad);
  return ok_status();
}

double sabine_reflection_coefficient(const cv::Vec3d& size_m, double rt60_s) {
  DS_CHECK(size_m[0] > 0 && size_m[1] > 0 && size_m[2] > 0);
  if (rt60_s <= 0) return 0.0;
  const double V = size_m[0] * size_m[1] * size_m[2];
  const double S = 2 * (size_m[0] * size_m[1] + size_m[0] * size_m[2] + size_m[1] * size_m[2]);
  const double alpha = std::clamp(0.161 * V / (S * rt60_s), 0.0, 1.0);
  return std::sqrt(1.0 - alpha);
}

namespace {

Channels image_source_rirs(const RoomOptions& options, const AcousticPlacement& placement,
                           double beta) {
  const cv::Vec3d& L = options.size_m;
  const double fs = options.sample_rate_hz, c = options.speed_of_sound_m_s;
  const double diagonal = cv::norm(L);
  double max_dist = options.max_image_distance_m > 0 ? options.max_image_distance_m
                                                     : std::max(c * options.rt60_s, 1.5 * diagonal);
  const bool anechoic = beta <= 0 || options.max_order == 0;
  const int hw = options.sinc_half_width;
  const size_t length = static_cast<size_t>(std::ceil(max_dist / c * fs)) + 2 * hw + 2;

  // Precompute the Hann-windowed sinc on a fine grid (linear interpolation): fast and exact
  // enough (error < 1e-6 relative with 1024 steps per sample).
  constexpr int kSteps = 1024;
  std::vector<double> table(static_cast<size_t>(2 * hw * kSteps + 2));
  for (size_t i = 0; i < table.size(); ++i) {
    const double x = static_cast<double>(i) / kSteps - hw;
    const double w = std::abs(x) < hw ? 0.5 * (1 + std::cos(CV_PI * x / hw)) : 0.0;
    const double s = std::abs(x) < 1e-12 ? 1.0 : std::sin(CV_PI * x) / (CV_PI * x);
    table[i] = w * s;
  }
  auto kernel = [&](double x) {  // x in (-hw, hw)
    const double pos = (x + hw) * kSteps;
    const size_t i = static_cast<size_t>(pos);
    const double f = pos - static_cast<double>(i);
    return table[i] * (1 - f) + table[i + 1] * f;
  };

  Channels rirs(placement.mics_m.size(), std::vector<double>(length, 0.0));
  std::array<int, 3> N{};
  for (int d = 0; d < 3; ++d)
    N[d] = anechoic ? 0 : static_cast<int>(std::ceil(max_dist / (2 * L[d]))) + 1;
  const cv::Vec3d& s = placement.source_m;

  for (size_t m = 0; m < placement.mics_m.size(); ++m) {
    const cv::Vec3d& r = placement.mics_m[m];
    std::vector<double>& h = rirs[m];
    for (int nx = -N[0]; nx <= N[0]; ++nx)
      for (int px = 0; px <= 1; ++px) {
        const double dx = (1 - 2 * px) * s[0] + 2 * nx * L[0] - r[0];
        const int ox = std::abs(nx - px) + std::abs(nx);
        if (anechoic && (nx != 0 || px != 0)) continue;
        for (int ny = -N[1]; ny <= N[1]; ++ny)
          for (int py = 0; py <= 1; ++py) {
            const double dy = (1 - 2 * py) * s[1] + 2 * ny * L[1] - r[1];
            const int oy = std::abs(ny - py) + std::abs(ny);
            if (anechoic && (ny != 0 || py != 0)) continue;
            const double dxy2 = dx * dx + dy * dy;
            if (dxy2 > max_dist * max_dist) continue;
            for (int nz = -N[2]; nz <= N[2]; ++nz)
              for (int pz = 0; pz <= 1; ++pz) {
                if (anechoic && (nz != 0 || pz != 0)) continue;
                const double dz = (1 - 2 * pz) * s[2] + 2 * nz * L[2] - r[2];
                const int order = ox + oy + std::abs(nz - pz) + std::abs(nz);
                if (options.max_order >= 0 && order > options.max_order) continue;
                const double dist = std::sqrt(dxy2 + dz * dz);
                if (dist > max_dist) continue;
                const double gain = std::pow(beta, order) / std::max(dist, 1e-3);
                const double delay = dist / c * fs;
                const long k0 = static_cast<long>(std::floor(delay));
                for (long k = k0 - hw + 1; k <= k0 + hw; ++k) {
                  if (k < 0 || static_cast<size_t>(k) >= length) continue;
                  h[static_cast<size_t>(k)] += gain * kernel(static_cast<double>(k) - delay);
                }
              }
          }
      }
  }
  return rirs;
}

}  // namespace

double matched_reflection_coefficient(const RoomOptions& options) {
  const cv::Vec3d& L = options.size_m;
  if (options.rt60_s <= 0) return 0.0;
  using Key = std::array<double, 6>;
  static std::mutex cache_mutex;
  static std::map<Key, double> cache;
  const Key key{
      L[0], L[1], L[2], options.rt60_s, options.sample_rate_hz, options.speed_of_sound_m_s};
  {
    std::lock_guard lock(cache_mutex);
    if (auto it = cache.find(key); it != cache.end()) return it->second;
  }
  // Canonical placement away from walls and symmetry planes.
  const AcousticPlacement pl{cv::Vec3d(0.31 * L[0], 0.37 * L[1], 0.41 * L[2]),
                             {cv::Vec3d(0.67 * L[0], 0.61 * L[1], 0.56 * L[2])}};
  RoomOptions o = options;
  o.max_order = -1;
  o.max_image_distance_m = 1.3 * options.speed_of_sound_m_s * options.rt60_s;
  o.sinc_half_width = 4;
  const double V = L[0] * L[1] * L[2];
  const double S = 2 * (L[0] * L[1] + L[0] * L[2] + L[1] * L[2]);
  double alpha = std::clamp(0.161 * V / (S * options.rt60_s), 1e-4, 0.99);  // Sabine start
  for (int it = 0; it < 8; ++it) {
    const Channels h = image_source_rirs(o, pl, std::sqrt(1 - alpha));
    const auto t30 = schroeder_rt60(h.front(), o.sample_rate_hz, -5.0, -35.0);
    if (!t30) break;
    const double ratio = *t30 / options.rt60_s;
    if (std::abs(ratio - 1) < 0.01) break;
    alpha = std::clamp(alpha * ratio, 1e-4, 0.99);  // T60 ~ 1/alpha
  }
  const double beta = std::sqrt(1 - alpha);
  std::lock_guard lock(cache_mutex);
  cache[key] = beta;
  return beta;
}

Result<Channels> room_impulse_responses(const RoomOptions& options,
                                        const AcousticPlacement& placement) {
  if (auto st = options.check(); !st) return tl::unexpected(st.error());
  const cv::Vec3d& L = options.size_m;
  if (!inside(placement.source_m, L))
    return make_error(ErrorCode::kInvalidArgument, "source ({}, {}, {}) m is outside the room",
                      placement.source_m[0], placement.source_m[1], placement.source_m[2]);
  if (placement.mics_m.empty())
    return make_error(ErrorCode::kInvalidArgument, "no microphones in the placement");
  for (const auto& m : placement.mics_m)
    if (!inside(m, L))
      return make_error(ErrorCode::kInvalidArgument,
                        "microphone ({}, {}, {}) m is outside the room", m[0], m[1], m[2]);
  const double beta = options.match_rt60 ? matched_reflection_coefficient(options)
                                         : sabine_reflection_coefficient(L, options.rt60_s);
  return image_source_rirs(options, placement, beta);
}

std::vector<double> fft_convolve(std::span<const double> a, std::span<const double> b) {
  if (a.empty() || b.empty()) return {};
  const size_t out_len = a.size() + b.size() - 1;
  if (std::min(a.size(), b.size()) <= 32) {  // direct form is faster for tiny kernels
    std::vector<double> out(out_len, 0.0);
    for (size_t i = 0; i < a.size(); ++i)
      for (size_t j = 0; j < b.size(); ++j) out[i + j] += a[i] * b[j];
    return out;
  }
  const size_t n = good_fft_size(out_len);
  audio::RealFft fa(static_cast<int>(n));
  double* real = fa.real();
  std::complex<double>* spec = fa.spectrum();
  std::vector<std::complex<double>> A(n / 2 + 1);
  std::fill(real, real + n, 0.0);
  std::copy(a.begin(), a.end(), real);
  fa.forward();
  std::copy(spec, spec + A.size(), A.begin());
  std::fill(real, real + n, 0.0);
  std::copy(b.begin(), b.end(), real);
  fa.forward();
  for (size_t i = 0; i < A.size(); ++i) spec[i] = A[i] * spec[i];
  fa.inverse();
  std::vector<double> out(real, real + out_len);
  const double scale = 1.0 / static_cast<double>(n);
  for (double& v : out) v *= scale;
  return out;
}

Result<Channels> simulate(std::span<const double> mono, const RoomOptions& options,
                          const AcousticPlacement& placement) {
  auto rirs = room_impulse_responses(options, placement);
  if (!rirs) return tl::unexpected(rirs.error());
  Channels out;
  out.reserve(rirs->size());
  for (const auto& h : *rirs) out.push_back(fft_convolve(mono, h));
  return out;
}

Channels make_noise(int channels, size_t frames, NoiseColor color, uint64_t seed) {
  DS_CHECK_GE(channels, 0);
  Channels out(static_cast<size_t>(channels));
  GaussianSource gauss(seed);
  for (auto& ch : out) {
    ch.resize(frames);
    for (double& v : ch) v = gauss.next();
  }
  if (color == NoiseColor::kPink && frames > 1) {
    const size_t n = good_fft_size(frames);
    audio::RealFft f(static_cast<int>(n));
    double* real = f.real();
    std::complex<double>* spec = f.spectrum();
    for (auto& ch : out) {
      std::fill(real, real + n, 0.0);
      std::copy(ch.begin(), ch.end(), real);
      f.forward();
      spec[0] = 0;
      for (size_t k = 1; k <= n / 2; ++k) {
        const double g = 1.0 / std::sqrt(static_cast<double>(k));  // power ~ 1/f
        spec[k] *= g;  // real and imaginary parts scaled alike
      }
      f.inverse();
      std::copy(real, real + frames, ch.begin());
    }
  }
  for (auto& ch : out) {  // exact unit power per channel
    double p = 0;
    for (double v : ch) p += v * v;
    p /= static_cast<double>(std::max<size_t>(ch.size(), 1));
    if (p > 0)
      for (double& v : ch) v /= std::sqrt(p);
  }
  return out;
}

double mean_power(const Channels& signal, size_t begin, size_t end) {
  double sum = 0;
  size_t count = 0;
  for (const auto& ch : signal) {
    const size_t e = std::min(end, ch.size());
    for (size_t i = begin; i < e; ++i) sum += ch[i] * ch[i];
    if (e > begin) count += e - begin;
  }
  return count ? sum / static_cast<double>(count) : 0.0;
}

double add_noise(Channels& signal, double snr_db, NoiseColor color, uint64_t seed,
                 std::optional<double> reference_power) {
  if (signal.empty()) return 0.0;
  const double ref = reference_power ? *reference_power : mean_power(signal);
  const double noise_power = ref / std::pow(10.0, snr_db / 10.0);
  size_t frames = 0;
  for (const auto& ch : signal) frames = std::max(frames, ch.size());
  const Channels noise = make_noise(static_cast<int>(signal.size()), frames, color, seed);
  const double g = std::sqrt(noise_power);
  for (size_t c = 0; c < signal.size(); ++c)
    for (size_t i = 0; i < signal[c].size(); ++i) signal[c][i] += g * noise[c][i];
  return noise_power;
}

std::optional<double> schroeder_rt60(std::span<const double> rir, double sample_rate_hz,
                                     double from_db, double to_db) {
  if (rir.empty() || !(from_db > to_db)) return std::nullopt;
  std::vector<double> edc(rir.size());
  double acc = 0;
  for (size_t i = rir.size(); i-- > 0;) {
    acc += rir[i] * rir[i];
    edc[i] = acc;
  }
  if (acc <= 0) return std::nullopt;
  // Fit from the first sample below from_db to the first below to_db (least squares).
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  size_t n = 0;
  bool reached = false;
  for (size_t i = 0; i < edc.size(); ++i) {
    const double db = 10 * std::log10(std::max(edc[i] / acc, 1e-300));
    if (db > from_db) continue;
    if (db < to_db) {
      reached = true;
      break;
    }
    const double t = static_cast<double>(i) / sample_rate_hz;
    sx += t;
    sy += db;
    sxx += t * t;
    sxy += t * db;
    ++n;
  }
  if (!reached || n < 2) return std::nullopt;
  const double slope = (static_cast<double>(n) * sxy - sx * sy) /
                       (static_cast<double>(n) * sxx - sx * sx);  // dB per second
  if (slope >= 0) return std::nullopt;
  return -60.0 / slope;
}

}  // namespace dreamsense::sim
