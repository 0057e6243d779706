#include "dreamsense/sound_direction/srp_phat.hpp"

#include "dreamsense/audio/fft.hpp"

#include <algorithm>
#include <cmath>
#include <complex>

namespace dreamsense::sound_direction {
namespace {

using cd = std::complex<double>;

// Shared machinery: windowed forward FFT of frames, PHAT cross-spectrum, upsampled inverse FFT.
struct PhatCore {
  int n = 0, k = 0, u = 0, l = 0, kl = 0;
  int band_lo = 1, band_hi = 0;  // PHAT band bins, inclusive
  int vad_lo = 1, vad_hi = 0;
  double norm = 1;  // 2 * band bins: a coherent pair correlates to 1
  std::vector<double> window;
  double window_power = 1;                  // sum of w^2
  std::unique_ptr<audio::RealFft> forward;  // n: frames -> spectra
  std::unique_ptr<audio::RealFft> inverse;  // l: cross-spectrum -> upsampled correlation
  double* in = nullptr;                     // forward's input (n)
  cd* cross = nullptr;                      // inverse's input (kl bins)
  double* out = nullptr;                    // inverse's output (l lags)

  PhatCore(const PhatOptions& o, int fs) {
    n = o.frame_length;
    k = n / 2 + 1;
    u = o.upsample;
    l = n * u;
    kl = l / 2 + 1;
    const double bin_hz = static_cast<double>(fs) / n;
    band_lo = std::max(1, static_cast<int>(std::ceil(o.min_freq_hz / bin_hz)));
    band_hi = std::min(k - 2, static_cast<int>(std::floor(o.max_freq_hz / bin_hz)));
    vad_lo = std::max(1, static_cast<int>(std::ceil(300.0 / bin_hz)));
    vad_hi = std::min(k - 2, static_cast<int>(std::floor(4000.0 / bin_hz)));
    norm = 2.0 * std::max(1, band_hi - band_lo + 1);
    window.resize(static_cast<size_t>(n));
    window_power = 0;
    for (int i = 0; i < n; ++i) {
      window[static_cast<size_t>(i)] = 0.5 - 0.5 * std::cos(2 * M_PI * i / n);  // periodic Hann
      window_power += window[static_cast<size_t>(i)] * window[static_cast<size_t>(i)];
    }
    forward = std::make_unique<audio::RealFft>(n);
    inverse = std::make_unique<audio::RealFft>(l);
    in = forward->real();
    cross = inverse->spectrum();
    out = inverse->real();
  }
  PhatCore(const PhatCore&) = delete;
  PhatCore& operator=(const PhatCore&) = delete;

  // Windowed FFT of samples x[i * stride] into `dst` (k bins); returns the in-band mean power.
  double transform(const float* x, int stride, cd* dst) {
    for (int i = 0; i < n; ++i)
      in[static_cast<size_t>(i)] =
          window[static_cast<size_t>(i)] * x[static_cast<size_t>(i) * stride];
    forward->forward(in, dst);
    double p = 0;
    for (int b = vad_lo; b <= vad_hi; ++b)
      p += dst[b].real() * dst[b].real() + dst[b].imag() * dst[b].imag();
    return 2.0 * p / (n * window_power);
  }

  // PHAT-weighted cross-correlation of spectra a and b into `out` (l lags, lag t at index
  // t * u mod l), normalised so that a coherent pair peaks at 1.
  void correlate(const cd* a, const cd* b) {
    std::fill(cross, cross + kl, cd(0, 0));
    for (int i = band_lo; i <= band_hi; ++i) {
      const double re = a[i].real() * b[i].real() + a[i].imag() * b[i].imag();  // a * conj(b)
      const double im = a[i].imag() * b[i].real() - a[i].real() * b[i].imag();
      const double mag = std::sqrt(re * re + im * im);
      if (mag > 1e-20) cross[i] = cd(re / (mag * norm), im / (mag * norm));
    }
    inverse->inverse();
  }
  // Correlation at a fractional lag (samples), linear interpolation on the upsampled grid.
  double at(double lag_samples) const {
    const double pos = lag_samples * u;
    const double f = std::floor(pos);
    const double frac = pos - f;
    auto idx = [&](long long i) { return static_cast<size_t>(((i % l) + l) % l); };
    const long long i0 = static_cast<long long>(f);
    return (1 - frac) * out[idx(i0)] + frac * out[idx(i0 + 1)];
  }
};

double parabola_offset(double ym, double y0, double yp) {
  const double d = ym - 2 * y0 + yp;
  if (std::abs(d) < 1e-15) return 0;
  return std::clamp(0.5 * (ym - yp) / d, -0.5, 0.5);
}

}  // namespace

// ------------------------------------------------------------------ options

Status PhatOptions::check(int sample_rate) const {
  std::string bad;
  if (frame_length < 64 || frame_length > 16384 || (frame_length & (frame_length - 1)) != 0)
    bad += fmt::format(" frame_length {} must be a power of 2 in [64, 16384];", frame_length);
  if (upsample < 1 || upsample > 16) bad += fmt::format(" upsample {} outside [1, 16];", upsample);
  if (!(min_freq_hz >= 0 && max_freq_hz > min_freq_hz))
    bad += " need 0 <= min_freq_hz < max_freq_hz;";
  if (sample_rate > 0 && min_freq_hz >= 0.5 * sample_rate)
    bad += " min_freq_hz must be below Nyquist;";
  if (!bad.empty()) return make_error(ErrorCode::kInvalidArgument, "PhatOptions:" + bad);
  return ok_status();
}

Status SrpGridOptions::check() const {
  std::string bad;
  if (!(azimuth_step_deg >= 0.1 && azimuth_step_deg <= 30))
    bad += " azimuth_step_deg in [0.1, 30];";
  if (!(elevation_step_deg >= 0.5 && elevation_step_deg <= 45))
    bad += " elevation_step_deg in [0.5, 45];";
  if (!(speed_of_sound_m_s > 100 && speed_of_sound_m_s < 2000)) bad += " speed_of_sound_m_s;";
  if (!bad.empty()) return make_error(ErrorCode::kInvalidArgument, "SrpGridOptions:" + bad);
  return ok_status();
}

// ------------------------------------------------------------------ GccPhat

struct GccPhat::Impl {
  Impl(const PhatOptions& o, int fs)
      : core(o, fs),
        sa(audio::aligned_complex(static_cast<size_t>(core.k))),
        sb(audio::aligned_complex(static_cast<size_t>(core.k))) {}
  PhatCore core;
  audio::AlignedComplex sa, sb;
};

Result<std::unique_ptr<GccPhat>> GccPhat::create(const PhatOptions& options, int sample_rate) {
  if (auto s = options.check(sample_rate); !s) return tl::unexpected(s.error());
  std::unique_ptr<GccPhat> g(new GccPhat());
  g->impl_ = std::make_unique<Impl>(options, sample_rate);
  return g;
}
GccPhat::~GccPhat() = default;

GccPhat::Delay GccPhat::delay(std::span<const float> a, std::span<const float> b,
                              double max_lag) const {
  PhatCore& c = impl_->core;
  DS_CHECK_EQ(a.size(), static_cast<size_t>(c.n));
  DS_CHECK_EQ(b.size(), static_cast<size_t>(c.n));
  c.transform(a.data(), 1, impl_->sa.get());
  c.transform(b.data(), 1, impl_->sb.get());
  c.correlate(impl_->sa.get(), impl_->sb.get());
  const int m = std::min(static_cast<int>(std::ceil(max_lag * c.u)), c.l / 2 - 1);
  auto val = [&](int i) { return c.out[static_cast<size_t>(((i % c.l) + c.l) % c.l)]; };
  int best = 0;
  for (int i = -m; i <= m; ++i)
    if (val(i) > val(best)) best = i;
  const double off = parabola_offset(val(best - 1), val(best), val(best + 1));
  // The peak lag is t_a - t_b; b lagging a by D samples peaks at -D.
  return Delay{-(best + off) / c.u, val(best)};
}

// ------------------------------------------------------------------ grid

std::vector<GridDirection> make_grid(const MicArrayGeometry& g, const SrpGridOptions& o) {
  std::vector<GridDirection> out;
  auto dir = [](double az_deg, double el_deg) {
    const double az = az_deg * M_PI / 180, el = el_deg * M_PI / 180;
    return cv::Vec3d(std::sin(az) * std::cos(el), -std::sin(el), std::cos(az) * std::cos(el));
  };
  const int rank = g.rank();
  if (rank <= 1) {
    const int n = static_cast<int>(std::floor(90.0 / o.azimuth_step_deg + 1e-9));
    for (int i = -n; i <= n; ++i) {
      const double az = i * o.azimuth_step_deg;
      out.push_back({az, 0, dir(az, 0)});
    }
    return out;
  }
  cv::Vec3d normal(0, 0, 0);
  if (rank == 2) {
    cv::Vec3d mean(0, 0, 0);
    for (const auto& m : g.mics_m) mean += m;
    mean *= 1.0 / static_cast<double>(g.mics_m.size());
    cv::Mat a(static_cast<int>(g.mics_m.size()), 3, CV_64F);
    for (int i = 0; i < a.rows; ++i)
      for (int k = 0; k < 3; ++k)
        a.at<double>(i, k) = g.mics_m[static_cast<size_t>(i)][k] - mean[k];
    cv::Mat w, u, vt;
    cv::SVD::compute(a, w, u, vt);
    normal = cv::Vec3d(vt.at<double>(2, 0), vt.at<double>(2, 1), vt.at<double>(2, 2));
    // Horizontal array: keep the half above it (-y); otherwise the half in front (+z).
    if (std::abs(normal[1]) > 0.7 ? normal[1] > 0 : normal[2] < 0) normal = -normal;
  }
  const int ne = static_cast<int>(std::floor(90.0 / o.elevation_step_deg + 1e-9));
  const int na = static_cast<int>(std::floor(360.0 / o.azimuth_step_deg + 1e-9));
  for (int e = -ne; e <= ne; ++e) {
    const double el = e * o.elevation_step_deg;
    const bool pole = std::abs(std::abs(el) - 90) < 1e-9;
    for (int a = 0; a < (pole ? 1 : na); ++a) {
      const double az = -180 + a * o.azimuth_step_deg;
      const cv::Vec3d d = dir(az, el);
      if (rank == 2 && d.dot(normal) < -1e-9) continue;
      out.push_back({az, el, d});
    }
  }
  return out;
}

// ------------------------------------------------------------------ SrpPhat

struct SrpPhat::Impl {
  Impl(const PhatOptions& o, int fs) : core(o, fs) {}
  PhatCore core;
  MicArrayGeometry geometry;
  std::vector<GridDirection> grid;
  bool linear = false;
  double az_step = 1;
  int channels = 0;
  std::vector<audio::AlignedComplex> spectra;
  std::vector<std::pair<int, int>> pairs;
  // Per pair, per grid direction: upsampled lag index (mod l) and interpolation fraction.
  std::vector<std::vector<std::pair<size_t, float>>> taps;
  std::vector<float> scratch;
};

Result<std::unique_ptr<SrpPhat>> SrpPhat::create(const MicArrayGeometry& geometry,
                                                 const PhatOptions& phat,
                                                 const SrpGridOptions& grid) {
  if (auto s = geometry.check(); !s) return tl::unexpected(s.error());
  if (auto s = phat.check(geometry.sample_rate); !s) return tl::unexpected(s.error());
  if (auto s = grid.check(); !s) return tl::unexpected(s.error());
  std::unique_ptr<SrpPhat> p(new SrpPhat());
  p->impl_ = std::make_unique<Impl>(phat, geometry.sample_rate);
  Impl& m = *p->impl_;
  m.geometry = geometry;
  m.grid = make_grid(geometry, grid);
  m.linear = geometry.rank() <= 1;
  m.az_step = grid.azimuth_step_deg;
  m.channels = static_cast<int>(geometry.mics_m.size());
  for (int c = 0; c < m.channels; ++c)
    m.spectra.push_back(audio::aligned_complex(static_cast<size_t>(m.core.k)));
  for (int i = 0; i < m.channels; ++i)
    for (int j = i + 1; j < m.channels; ++j) m.pairs.emplace_back(i, j);
  const double fs = geometry.sample_rate;
  for (const auto& [i, j] : m.pairs) {
    std::vector<std::pair<size_t, float>> t;
    t.reserve(m.grid.size());
    const cv::Vec3d baseline =
        geometry.mics_m[static_cast<size_t>(j)] - geometry.mics_m[static_cast<size_t>(i)];
    for (const auto& d : m.grid) {
      // Far field: t_m = -(m . d) / c, so the peak of corr(x_i, x_j) is at t_i - t_j.
      const double lag = baseline.dot(d.unit) / grid.speed_of_sound_m_s * fs;
      const double pos = lag * m.core.u;
      const double f = std::floor(pos);
      const long long i0 = static_cast<long long>(f);
      const size_t idx = static_cast<size_t>(((i0 % m.core.l) + m.core.l) % m.core.l);
      t.emplace_back(idx, static_cast<float>(pos - f));
    }
    m.taps.push_back(std::move(t));
  }
  return p;
}

SrpPhat::~SrpPhat() = default;
const std::vector<GridDirection>& SrpPhat::grid() const { return impl_->grid; }
int SrpPhat::channels() const { return impl_->channels; }
int SrpPhat::frame_length() const { return impl_->core.n; }
bool SrpPhat::linear() const { return impl_->linear; }

double SrpPhat::analyse(std::span<const float> interleaved) {
  Impl& m = *impl_;
  DS_CHECK_EQ(interleaved.size(), static_cast<size_t>(m.core.n) * static_cast<size_t>(m.channels));
  double p = 0;
  for (int c = 0; c < m.channels; ++c)
    p += m.core.transform(interleaved.data() + c, m.channels,
                          m.spectra[static_cast<size_t>(c)].get());
  return p / m.channels;
}

void SrpPhat::power_map(std::vector<float>& map) {
  Impl& m = *impl_;
  map.assign(m.grid.size(), 0.f);
  const size_t l = static_cast<size_t>(m.core.l);
  for (size_t p = 0; p < m.pairs.size(); ++p) {
    const auto [i, j] = m.pairs[p];
    m.core.correlate(m.spectra[static_cast<size_t>(i)].get(),
                     m.spectra[static_cast<size_t>(j)].get());
    const double* r = m.core.out;
    const auto& taps = m.taps[p];
    for (size_t g = 0; g < taps.size(); ++g) {
      const size_t i0 = taps[g].first;
      const size_t i1 = i0 + 1 == l ? 0 : i0 + 1;
      const double f = taps[g].second;
      map[g] += static_cast<float>((1 - f) * r[i0] + f * r[i1]);
    }
  }
  const float inv = 1.f / static_cast<float>(m.pairs.size());
  for (float& v : map) v *= inv;
}

SrpPeak SrpPhat::peak(std::span<const float> map, double min_separation_deg) const {
  const Impl& m = *impl_;
  DS_CHECK_EQ(map.size(), m.grid.size());
  SrpPeak out;
  const size_t best = static_cast<size_t>(std::max_element(map.begin(), map.end()) - map.begin());
  out.index = best;
  out.power = map[best];
  out.second_power = -1;
  const GridDirection& g = m.grid[best];
  if (m.linear) {
    double az = g.azimuth_deg;
    if (best > 0 && best + 1 < map.size())
      az += m.az_step * parabola_offset(map[best - 1], map[best], map[best + 1]);
    out.azimuth_deg = az;
    const double a = az * M_PI / 180;
    out.unit = cv::Vec3d(std::sin(a), 0, std::cos(a));
    for (size_t i = 0; i < map.size(); ++i) {
      const bool local =
          (i == 0 || map[i] >= map[i - 1]) && (i + 1 == map.size() || map[i] >= map[i + 1]);
      if (local && std::abs(m.grid[i].azimuth_deg - g.azimuth_deg) >= min_separation_deg)
        out.second_power = std::max(out.second_power, static_cast<double>(map[i]));
    }
  } else {
    out.azimuth_deg = g.azimuth_deg;
    out.elevation_deg = g.elevation_deg;
    out.unit = g.unit;
    const double cos_sep = std::cos(min_separation_deg * M_PI / 180);
    for (size_t i = 0; i < map.size(); ++i)
      if (m.grid[i].unit.dot(g.unit) <= cos_sep)
        out.second_power = std::max(out.second_power, static_cast<double>(map[i]));
  }
  return out;
}

}  // namespace dreamsense::sound_direction
