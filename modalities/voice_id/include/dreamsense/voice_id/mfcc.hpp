#pragma once
// MFCC front end for speaker identification (Reynolds, Quatieri & Dunn 2000, section 3.2):
// pre-emphasis, 25 ms Hamming frames every 10 ms, FFT power spectrum, triangular mel filters
// between low_hz and high_hz, log, DCT-II; c1..c(N-1) plus the frame's log energy, then delta and
// delta-delta features (regression over +-delta_window frames), energy-based dropping of silent
// frames and cepstral mean normalisation over the kept frames.
//
// The filter bank is defined in Hz, so any sample rate with rate / 2 >= high_hz gives comparable
// features: the default band (100-3800 Hz) lets one model serve 8 kHz (FSDD) and 16 kHz audio.

#include "dreamsense/core/status.hpp"

#include <opencv2/core.hpp>

#include <span>

namespace dreamsense::voice_id {

struct MfccOptions {
  double frame_s = 0.025;     // analysis window
  double hop_s = 0.010;       // frame step
  double preemphasis = 0.97;  // y[n] = x[n] - a x[n-1]; 0 = off
  int filters = 24;           // mel filters
  int cepstra = 13;           // c0..c12 computed; c0 is replaced by the log energy
  double low_hz = 100;        // filter-bank band
  double high_hz = 3800;      // must be <= sample_rate / 2 of every input
  // Static log energy in the features (its deltas always are): off by default, as a speaker's
  // loudness says little about who they are and varies with distance.
  bool static_energy = false;
  int delta_window = 2;      // +-frames of the delta regression; 0 = no deltas
  bool delta_deltas = true;  // also the deltas of the deltas (needs delta_window > 0)
  // Silence dropping on the frame log energy: keep frames within drop_below_peak_db of the
  // loudest frame and at least above_floor_db above the 10th-percentile frame (so the quietest
  // tenth always goes). A larger above_floor_db cleans noisy recordings but also drops the quiet
  // speech of tightly trimmed clips (FSDD: 0.96 -> 0.89 accuracy at 6 dB), so it is 0.
  double drop_below_peak_db = 30;
  double above_floor_db = 0;
  // Frames quieter than this (mean square of the pre-emphasised, windowed frame, dB re full
  // scale 1.0) are silence whatever the rest of the recording is (digital silence).
  double min_level_db = -80;
  // Cepstral mean normalisation over the kept frames of each recording. With a prior mean
  // (normalise_features), the recording's mean is shrunk towards it with the weight of
  // cmn_prior_frames frames, as Kaldi's online CMN backs off to global statistics
  // (global_frames = 200): a 0.4 s word then keeps most of its long-term spectrum, which a plain
  // per-word mean would remove along with the channel. 0 = plain per-recording CMN.
  bool mean_normalise = true;
  double cmn_prior_frames = 200;
  bool variance_normalise = false;  // also divide by the recording's standard deviation
  // Issue 16: every recording (enrolment, background) and the analysed stream pass the noise
  // suppressor (audio/noise_suppressor.hpp) before the features (train_voice_model, identify,
  // the analyser). Stored in the model, so scoring always matches enrolment.
  bool noise_suppression = false;
  Status check() const;
  // Feature dimension: cepstra * (1 + deltas + delta-deltas), minus 1 without static energy.
  int dimension() const;
};

// Features of one recording: one row per kept frame, dimension() columns, CV_64F.
// `frames_total` counts the frames before silence dropping.
struct MfccFeatures {
  cv::Mat frames;
  int frames_total = 0;
  int frames_kept() const { return frames.rows; }
};

// Log mel filter-bank energies of every frame (pre-emphasised, windowed): frames x filters,
// natural log. Empty when the recording is shorter than one frame. Error: rate too low for
// high_hz.
Result<cv::Mat> log_mel_spectrum(std::span<const float> samples, int sample_rate,
                                 const MfccOptions& options);

// Static cepstra of every frame (no deltas, no dropping, no normalisation): frames x cepstra,
// column 0 = log energy (natural log of the windowed frame energy), columns 1.. = c1, c2, ...
// Empty when the recording is shorter than one frame. Error: rate too low for high_hz.
Result<cv::Mat> static_cepstra(std::span<const float> samples, int sample_rate,
                               const MfccOptions& options);

// Full feature pipeline: static cepstra, deltas, silence dropping, then normalise_features with
// `prior_mean` (empty: plain per-recording CMN). A recording without any speech-like frame gives
// zero rows (not an error).
Result<MfccFeatures> compute_mfcc(std::span<const float> samples, int sample_rate,
                                  const MfccOptions& options, const cv::Mat& prior_mean = {});

// The same without normalisation (what the prior mean is estimated from).
Result<MfccFeatures> unnormalised_mfcc(std::span<const float> samples, int sample_rate,
                                       const MfccOptions& options);

// In-place mean (and optionally variance) normalisation of one recording's frames:
// x -= (sum_t x_t + tau * prior) / (T + tau), tau = cmn_prior_frames (0 or empty prior: the
// recording's own mean). Precondition: prior_mean is empty or 1 x frames.cols.
void normalise_features(cv::Mat& frames, const MfccOptions& options, const cv::Mat& prior_mean);

// Mel scale (O'Shaughnessy): 2595 log10(1 + f / 700).
double hz_to_mel(double hz);
double mel_to_hz(double mel);

}  // namespace dreamsense::voice_id
