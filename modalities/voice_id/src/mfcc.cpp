#include "dreamsense/voice_id/mfcc.hpp"

#include "dreamsense/audio/fft.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <memory>
#include <vector>

namespace dreamsense::voice_id {

Status MfccOptions::check() const {
  std::string bad;
  if (!(frame_s > 0 && frame_s <= 0.1)) bad += " frame_s must be in (0, 0.1];";
  if (!(hop_s > 0 && hop_s <= frame_s)) bad += " hop_s must be in (0, frame_s];";
  if (!(preemphasis >= 0 && preemphasis < 1)) bad += " preemphasis must be in [0, 1);";
  if (filters < 4 || filters > 128) bad += " filters must be in [4, 128];";
  if (cepstra < 2 || cepstra > filters) bad += " cepstra must be in [2, filters];";
  if (!(low_hz >= 0 && high_hz > low_hz)) bad += " need 0 <= low_hz < high_hz;";
  if (delta_window < 0 || delta_window > 10) bad += " delta_window must be in [0, 10];";
  if (delta_deltas && delta_window == 0) bad += " delta_deltas needs delta_window > 0;";
  if (!(drop_below_peak_db > 0)) bad += " drop_below_peak_db must be > 0;";
  if (!(above_floor_db >= 0)) bad += " above_floor_db must be >= 0;";
  if (!(min_level_db < 0)) bad += " min_level_db must be < 0;";
  if (!(cmn_prior_frames >= 0)) bad += " cmn_prior_frames must be >= 0;";
  if (!bad.empty()) return make_error(ErrorCode::kInvalidArgument, "MfccOptions:" + bad);
  return ok_status();
}

int MfccOptions::dimension() const {
  const int blocks = 1 + (delta_window > 0 ? 1 : 0) + (delta_window > 0 && delta_deltas ? 1 : 0);
  return cepstra * blocks - (static_energy ? 0 : 1);
}

double hz_to_mel(double hz) { return 2595.0 * std::log10(1.0 + hz / 700.0); }
double mel_to_hz(double mel) { return 700.0 * (std::pow(10.0, mel / 2595.0) - 1.0); }

namespace {

// Triangular mel filters over FFT bins 0..nfft/2: weights[f][bin].
std::vector<std::vector<double>> mel_filters(const MfccOptions& o, int rate, int nfft) {
  const int bins = nfft / 2 + 1;
  const double lo = hz_to_mel(o.low_hz), hi = hz_to_mel(o.high_hz);
  std::vector<double> edges(static_cast<size_t>(o.filters) + 2);
  for (size_t i = 0; i < edges.size(); ++i)
    edges[i] = mel_to_hz(lo + (hi - lo) * static_cast<double>(i) / (o.filters + 1));
  std::vector<std::vector<double>> w(static_cast<size_t>(o.filters),
                                     std::vector<double>(static_cast<size_t>(bins), 0.0));
  for (int f = 0; f < o.filters; ++f) {
    const double a = edges[f], b = edges[f + 1], c = edges[f + 2];
    for (int k = 0; k < bins; ++k) {
      const double hz = static_cast<double>(k) * rate / nfft;
      double v = 0;
      if (hz > a && hz <= b)
        v = (hz - a) / (b - a);
      else if (hz > b && hz < c)
        v = (c - hz) / (c - b);
      w[f][k] = v;
    }
  }
  return w;
}

// Regression deltas over +-n frames, edges replicated.
cv::Mat deltas(const cv::Mat& c, int n) {
  cv::Mat d(c.rows, c.cols, CV_64F, cv::Scalar(0));
  double norm = 0;
  for (int k = 1; k <= n; ++k) norm += 2.0 * k * k;
  for (int t = 0; t < c.rows; ++t)
    for (int k = 1; k <= n; ++k) {
      const double* plus = c.ptr<double>(std::min(c.rows - 1, t + k));
      const double* minus = c.ptr<double>(std::max(0, t - k));
      double* out = d.ptr<double>(t);
      for (int j = 0; j < c.cols; ++j) out[j] += k * (plus[j] - minus[j]) / norm;
    }
  return d;
}

}  // namespace

namespace {

// Log mel energies (frames x filters) and log frame energies (frames x 1).
Status analyse_frames(std::span<const float> samples, int sample_rate, const MfccOptions& o,
                      cv::Mat& logmel_out, cv::Mat& log_energy_out) {
  if (auto s = o.check(); !s) return tl::unexpected(s.error());
  if (sample_rate <= 0)
    return make_error(ErrorCode::kInvalidArgument, "mfcc: sample rate {} is not positive",
                      sample_rate);
  if (sample_rate / 2.0 + 1e-9 < o.high_hz)
    return make_error(ErrorCode::kUnsupported,
                      "mfcc: audio at {} Hz cannot give features up to {} Hz (the model's band); "
                      "use audio of at least {} Hz",
                      sample_rate, o.high_hz, static_cast<int>(std::ceil(2 * o.high_hz)));
  const int len = std::max(2, static_cast<int>(std::lround(o.frame_s * sample_rate)));
  const int hop = std::max(1, static_cast<int>(std::lround(o.hop_s * sample_rate)));
  const int n = static_cast<int>(samples.size());
  if (n < len) {
    logmel_out = cv::Mat(0, o.filters, CV_64F);
    log_energy_out = cv::Mat(0, 1, CV_64F);
    return ok_status();
  }
  const int frames = 1 + (n - len) / hop;
  int nfft = 1;
  while (nfft < len) nfft *= 2;
  const int bins = nfft / 2 + 1;

  audio::RealFft fft(nfft);
  double* in = fft.real();
  const std::complex<double>* spec = fft.spectrum();
  const auto filters = mel_filters(o, sample_rate, nfft);
  std::vector<double> window(static_cast<size_t>(len));
  for (int i = 0; i < len; ++i) window[i] = 0.54 - 0.46 * std::cos(2 * CV_PI * i / (len - 1));
  const int M = o.filters;
  logmel_out = cv::Mat(frames, M, CV_64F);
  log_energy_out = cv::Mat(frames, 1, CV_64F);
  std::vector<double> power(static_cast<size_t>(bins));
  for (int t = 0; t < frames; ++t) {
    const int s0 = t * hop;
    double energy = 0;
    for (int i = 0; i < nfft; ++i) {
      double v = 0;
      if (i < len) {
        const double x = samples[static_cast<size_t>(s0 + i)];
        const double prev = s0 + i > 0 ? samples[static_cast<size_t>(s0 + i - 1)] : 0.0;
        v = (x - o.preemphasis * prev) * window[static_cast<size_t>(i)];
        energy += v * v;
      }
      in[i] = v;
    }
    fft.forward();
    for (int k = 0; k < bins; ++k)
      power[k] = spec[k].real() * spec[k].real() + spec[k].imag() * spec[k].imag();
    double* logmel = logmel_out.ptr<double>(t);
    for (int m = 0; m < M; ++m) {
      double e = 0;
      const auto& w = filters[static_cast<size_t>(m)];
      for (int k = 0; k < bins; ++k) e += w[k] * power[k];
      logmel[m] = std::log(std::max(e, 1e-10));
    }
    log_energy_out.at<double>(t, 0) = std::log(std::max(energy, 1e-10));
  }
  return ok_status();
}

}  // namespace

Result<cv::Mat> log_mel_spectrum(std::span<const float> samples, int sample_rate,
                                 const MfccOptions& o) {
  cv::Mat logmel, energy;
  if (auto s = analyse_frames(samples, sample_rate, o, logmel, energy); !s)
    return tl::unexpected(s.error());
  return logmel;
}

Result<cv::Mat> static_cepstra(std::span<const float> samples, int sample_rate,
                               const MfccOptions& o) {
  cv::Mat logmel, energy;
  if (auto s = analyse_frames(samples, sample_rate, o, logmel, energy); !s)
    return tl::unexpected(s.error());
  // DCT-II (orthonormal rows) of the log filter energies; c0 -> log frame energy.
  const int M = o.filters;
  cv::Mat dct(o.cepstra, M, CV_64F);
  for (int k = 0; k < o.cepstra; ++k)
    for (int m = 0; m < M; ++m)
      dct.at<double>(k, m) = std::sqrt(2.0 / M) * std::cos(CV_PI * k * (m + 0.5) / M);
  cv::Mat out(logmel.rows, o.cepstra, CV_64F);
  for (int t = 0; t < logmel.rows; ++t) {
    const double* lm = logmel.ptr<double>(t);
    double* row = out.ptr<double>(t);
    for (int k = 1; k < o.cepstra; ++k) {
      double c = 0;
      const double* d = dct.ptr<double>(k);
      for (int m = 0; m < M; ++m) c += d[m] * lm[m];
      row[k] = c;
    }
    row[0] = energy.at<double>(t, 0);
  }
  return out;
}

Result<MfccFeatures> unnormalised_mfcc(std::span<const float> samples, int sample_rate,
                                       const MfccOptions& o) {
  auto c = static_cepstra(samples, sample_rate, o);
  if (!c) return tl::unexpected(c.error());
  MfccFeatures f;
  f.frames_total = c->rows;
  if (c->rows == 0) {
    f.frames = cv::Mat(0, o.dimension(), CV_64F);
    return f;
  }
  // Static + delta + delta-delta, computed on the contiguous frames before dropping.
  std::vector<cv::Mat> blocks{*c};
  if (o.delta_window > 0) {
    blocks.push_back(deltas(*c, o.delta_window));
    if (o.delta_deltas) blocks.push_back(deltas(blocks.back(), o.delta_window));
  }
  if (!o.static_energy) blocks[0] = blocks[0].colRange(1, blocks[0].cols).clone();
  cv::Mat all;
  cv::hconcat(blocks, all);

  // Silence dropping on the log energy (column 0), in dB.
  const double to_db = 10.0 / std::log(10.0);
  std::vector<double> db(static_cast<size_t>(c->rows));
  for (int t = 0; t < c->rows; ++t) db[t] = c->at<double>(t, 0) * to_db;
  std::vector<double> sorted = db;
  std::sort(sorted.begin(), sorted.end());
  const double peak = sorted.back();
  const double floor = sorted[sorted.size() / 10];
  const int len = std::max(2, static_cast<int>(std::lround(o.frame_s * sample_rate)));
  const double silence = o.min_level_db + 10 * std::log10(static_cast<double>(len));
  const double thr = std::max({peak - o.drop_below_peak_db, floor + o.above_floor_db, silence});
  std::vector<int> keep;
  for (int t = 0; t < c->rows; ++t)
    if (db[t] >= thr) keep.push_back(t);
  f.frames = cv::Mat(static_cast<int>(keep.size()), all.cols, CV_64F);
  for (size_t i = 0; i < keep.size(); ++i)
    all.row(keep[i]).copyTo(f.frames.row(static_cast<int>(i)));
  return f;
}

void normalise_features(cv::Mat& frames, const MfccOptions& o, const cv::Mat& prior_mean) {
  if (frames.rows == 0 || !(o.mean_normalise || o.variance_normalise)) return;
  const bool prior = !prior_mean.empty() && o.cmn_prior_frames > 0;
  if (prior) {
    DS_CHECK_EQ(prior_mean.cols, frames.cols);
    DS_CHECK_EQ(prior_mean.type(), CV_64F);
  }
  const double n = frames.rows, tau = prior ? o.cmn_prior_frames : 0.0;
  for (int j = 0; j < frames.cols; ++j) {
    cv::Mat col = frames.col(j);
    cv::Scalar m, s;
    cv::meanStdDev(col, m, s);
    if (o.variance_normalise && s[0] > 1e-8) col /= s[0];
    if (o.mean_normalise) {
      const double mean =
          (n * m[0] + tau * (prior ? prior_mean.at<double>(0, j) : 0.0)) / (n + tau);
      col -= o.variance_normalise && s[0] > 1e-8 ? mean / s[0] : mean;
    }
  }
}

Result<MfccFeatures> compute_mfcc(std::span<const float> samples, int sample_rate,
                                  const MfccOptions& o, const cv::Mat& prior_mean) {
  auto f = unnormalised_mfcc(samples, sample_rate, o);
  if (!f) return f;
  normalise_features(f->frames, o, prior_mean);
  return f;
}

}  // namespace dreamsense::voice_id
