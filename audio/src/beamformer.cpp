#include "dreamsense/audio/beamformer.hpp"

#include "dreamsense/audio/fft.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <string>

namespace dreamsense::audio {

using cd = std::complex<double>;

namespace {

int auto_frame_length(int rate) {
  const double target = 0.032 * rate;
  int n = 2;
  while (n * 2 <= target * std::numbers::sqrt2) n *= 2;  // power of two nearest (geometric)
  return std::max(n, 16);
}

double max_spacing(const std::vector<cv::Vec3d>& mics) {
  double d = 0;
  for (size_t i = 0; i < mics.size(); ++i)
    for (size_t j = i + 1; j < mics.size(); ++j) d = std::max(d, cv::norm(mics[i] - mics[j]));
  return d;
}

// Solves A x = b (n x n, row-major, partial pivoting); A and b are destroyed.
std::vector<cd> solve(std::vector<cd> a, std::vector<cd> b, size_t n) {
  for (size_t c = 0; c < n; ++c) {
    size_t p = c;
    for (size_t r = c + 1; r < n; ++r)
      if (std::abs(a[r * n + c]) > std::abs(a[p * n + c])) p = r;
    if (p != c) {
      for (size_t k = 0; k < n; ++k) std::swap(a[c * n + k], a[p * n + k]);
      std::swap(b[c], b[p]);
    }
    const cd piv = a[c * n + c];
    for (size_t r = c + 1; r < n; ++r) {
      const cd f = a[r * n + c] / piv;
      for (size_t k = c; k < n; ++k) a[r * n + k] -= f * a[c * n + k];
      b[r] -= f * b[c];
    }
  }
  std::vector<cd> x(n);
  for (size_t r = n; r-- > 0;) {
    cd s = b[r];
    for (size_t k = r + 1; k < n; ++k) s -= a[r * n + k] * x[k];
    x[r] = s / a[r * n + r];
  }
  return x;
}

}  // namespace

Status BeamformerOptions::check() const {
  std::string bad;
  auto add = [&](const std::string& s) { bad += (bad.empty() ? "" : "; ") + s; };
  if (sample_rate < 1000 || sample_rate > 192000)
    add(fmt::format("sample_rate must be in [1000, 192000] (is {})", sample_rate));
  if (mic_positions_m.empty() || mic_positions_m.size() > 64)
    add(fmt::format("need 1 to 64 mic positions (have {})", mic_positions_m.size()));
  for (size_t i = 0; i < mic_positions_m.size(); ++i)
    for (int k = 0; k < 3; ++k)
      if (!std::isfinite(mic_positions_m[i][k])) add(fmt::format("mic {} is not finite", i));
  if (!(speed_of_sound_m_s > 100 && speed_of_sound_m_s < 2000))
    add(fmt::format("speed_of_sound_m_s must be in (100, 2000) (is {})", speed_of_sound_m_s));
  if (!(diagonal_loading > 0)) add("diagonal_loading must be > 0");
  if (frame_length != 0 && (frame_length < 16 || frame_length % 2 != 0))
    add(fmt::format("frame_length must be 0 (auto) or even and >= 16 (is {})", frame_length));
  if (bad.empty() && sample_rate > 0) {
    const int n = frame_length != 0 ? frame_length : auto_frame_length(sample_rate);
    const double max_delay = max_spacing(mic_positions_m) / speed_of_sound_m_s * sample_rate;
    if (4 * max_delay > n)
      add(
          fmt::format("frame_length {} is too short for the array ({:.1f} samples across it); "
                      "use >= {}",
                      n, max_delay, static_cast<int>(std::ceil(4 * max_delay))));
  }
  if (!bad.empty()) return make_error(ErrorCode::kInvalidArgument, "BeamformerOptions: {}", bad);
  return ok_status();
}

struct Beamformer::Impl {
  explicit Impl(int n) : fft(n) {}
  RealFft fft;
  std::vector<double> window;           // sqrt periodic Hann
  std::vector<std::vector<double>> in;  // per channel, internal samples from the next frame on
  std::vector<double> ola;              // overlap-add accumulator, n samples
  std::vector<cd> weights;              // bins x M, conj(w): Y = sum_m weights * X_m
  std::vector<cd> acc;                  // bins
  int64_t input_frames = 0;             // real input samples pushed in this stream
  int64_t emitted = 0;                  // outputs emitted in this stream (incl. skipped)
  cv::Vec3d centroid{0, 0, 0};
};

Beamformer::Beamformer(BeamformerOptions options, std::unique_ptr<Impl> impl, int n)
    : options_(std::move(options)), impl_(std::move(impl)), n_(n) {}
Beamformer::~Beamformer() = default;

Result<std::unique_ptr<Beamformer>> Beamformer::create(const BeamformerOptions& options) {
  if (auto s = options.check(); !s) return tl::unexpected(s.error());
  const int n =
      options.frame_length != 0 ? options.frame_length : auto_frame_length(options.sample_rate);
  auto impl = std::make_unique<Impl>(n);
  impl->window.resize(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i)
    impl->window[static_cast<size_t>(i)] =
        std::sqrt(0.5 - 0.5 * std::cos(2 * std::numbers::pi * i / n));
  for (const auto& p : options.mic_positions_m) impl->centroid += p;
  impl->centroid *= 1.0 / static_cast<double>(options.mic_positions_m.size());
  auto b = std::unique_ptr<Beamformer>(new Beamformer(options, std::move(impl), n));
  b->reset();
  b->steer({0, 0, 1});
  return b;
}

std::vector<double> Beamformer::arrival_delays_s() const {
  std::vector<double> t;
  for (const auto& p : options_.mic_positions_m)
    t.push_back(-(p - impl_->centroid).dot(direction_) / options_.speed_of_sound_m_s);
  return t;
}

void Beamformer::steer(const cv::Vec3d& direction) {
  const double len = cv::norm(direction);
  DS_CHECK(std::isfinite(len) && len > 0);
  direction_ = direction / len;
  update_weights();
}

void Beamformer::update_weights() {
  const size_t m = options_.mic_positions_m.size();
  const int bins = n_ / 2 + 1;
  const std::vector<double> tau = arrival_delays_s();
  impl_->weights.assign(static_cast<size_t>(bins) * m, cd(0, 0));
  for (int k = 0; k < bins; ++k) {
    const double w = 2 * std::numbers::pi * k * options_.sample_rate / n_;
    cd* c = &impl_->weights[static_cast<size_t>(k) * m];
    if (options_.method == BeamformerMethod::kDelayAndSum || m == 1) {
      for (size_t i = 0; i < m; ++i) c[i] = std::polar(1.0 / static_cast<double>(m), w * tau[i]);
      continue;
    }
    // Superdirective MVDR: (Γ + μI) z = d, w = z / (dᴴ z), weights = conj(w).
    std::vector<cd> a(m * m), d(m);
    for (size_t i = 0; i < m; ++i) {
      d[i] = std::polar(1.0, -w * tau[i]);
      for (size_t j = 0; j < m; ++j) {
        const double x = w * cv::norm(options_.mic_positions_m[i] - options_.mic_positions_m[j]) /
                         options_.speed_of_sound_m_s;
        a[i * m + j] =
            (x < 1e-9 ? 1.0 : std::sin(x) / x) + (i == j ? options_.diagonal_loading : 0);
      }
    }
    const std::vector<cd> z = solve(a, d, m);
    cd dz(0, 0);
    for (size_t i = 0; i < m; ++i) dz += std::conj(d[i]) * z[i];
    for (size_t i = 0; i < m; ++i) c[i] = std::conj(z[i] / dz);
  }
}

void Beamformer::reset() {
  const size_t m = options_.mic_positions_m.size();
  const size_t hop = static_cast<size_t>(n_ / 2);
  impl_->in.assign(m, std::vector<double>(hop, 0.0));  // primed: the first frame starts -hop
  impl_->ola.assign(static_cast<size_t>(n_), 0.0);
  impl_->acc.assign(static_cast<size_t>(n_ / 2 + 1), cd(0, 0));
  impl_->input_frames = 0;
  impl_->emitted = 0;
}

void Beamformer::run_frame() {
  Impl& s = *impl_;
  const size_t m = options_.mic_positions_m.size();
  const size_t n = static_cast<size_t>(n_), hop = n / 2, bins = n / 2 + 1;
  std::fill(s.acc.begin(), s.acc.end(), cd(0, 0));
  double* x = s.fft.real();
  const cd* spec = s.fft.spectrum();
  for (size_t c = 0; c < m; ++c) {
    const double* src = s.in[c].data();
    for (size_t i = 0; i < n; ++i) x[i] = src[i] * s.window[i];
    s.fft.forward();
    const cd* wc = s.weights.data() + c;
    for (size_t k = 0; k < bins; ++k) s.acc[k] += wc[k * m] * spec[k];
  }
  std::copy(s.acc.begin(), s.acc.end(), s.fft.spectrum());
  s.fft.inverse();
  const double scale = 1.0 / static_cast<double>(n);
  for (size_t i = 0; i < n; ++i) s.ola[i] += x[i] * scale * s.window[i];
  for (auto& ch : s.in) ch.erase(ch.begin(), ch.begin() + static_cast<std::ptrdiff_t>(hop));
}

Status Beamformer::process(std::span<const float> interleaved, std::vector<float>& out) {
  const size_t m = options_.mic_positions_m.size();
  if (interleaved.size() % m != 0)
    return make_error(ErrorCode::kInvalidArgument,
                      "beamformer: {} values is not a whole number of {}-channel frames",
                      interleaved.size(), m);
  Impl& s = *impl_;
  const size_t frames = interleaved.size() / m;
  const size_t n = static_cast<size_t>(n_), hop = n / 2;
  size_t pos = 0;
  while (pos < frames) {
    // Fill the channel buffers up to one frame, then run it.
    const size_t need = n - s.in[0].size();
    const size_t take = std::min(need, frames - pos);
    for (size_t c = 0; c < m; ++c)
      for (size_t i = 0; i < take; ++i) s.in[c].push_back(interleaved[(pos + i) * m + c]);
    pos += take;
    s.input_frames += static_cast<int64_t>(take);
    if (s.in[0].size() < n) break;
    run_frame();
    // The first hop of the accumulator is final. The stream's first hop is the priming.
    for (size_t i = 0; i < hop; ++i, ++s.emitted)
      if (s.emitted >= static_cast<int64_t>(hop)) out.push_back(static_cast<float>(s.ola[i]));
    std::copy(s.ola.begin() + static_cast<std::ptrdiff_t>(hop), s.ola.end(), s.ola.begin());
    std::fill(s.ola.begin() + static_cast<std::ptrdiff_t>(n - hop), s.ola.end(), 0.0);
  }
  return ok_status();
}

void Beamformer::flush(std::vector<float>& out) {
  Impl& s = *impl_;
  const int64_t hop = n_ / 2;
  const int64_t owed = s.input_frames;  // one output per real input sample
  auto emitted_real = [&] { return std::max<int64_t>(0, s.emitted - hop); };
  const std::vector<float> zeros(static_cast<size_t>(hop) * options_.mic_positions_m.size(), 0.f);
  while (emitted_real() < owed) {
    const size_t before = out.size();
    const int64_t real_before = emitted_real();
    (void)process(zeros, out);  // whole frames: cannot fail
    const int64_t keep = std::min(emitted_real(), owed) - real_before;
    out.resize(before + static_cast<size_t>(keep));
  }
  reset();
}

Result<std::vector<float>> Beamformer::apply(std::span<const float> interleaved) {
  reset();
  std::vector<float> out;
  out.reserve(interleaved.size() / options_.mic_positions_m.size());
  if (auto s = process(interleaved, out); !s) return tl::unexpected(s.error());
  flush(out);
  return out;
}

}  // namespace dreamsense::audio
