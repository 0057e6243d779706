// Beamformer on the Kinect v1 array with plane waves synthesised by windowed-sinc fractional
// delays (independent of the beamformer's own FFT delays).

#include "dreamsense/audio/beamformer.hpp"

#include "dreamsense/audio/mic_array.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <random>
#include <vector>

namespace dreamsense::audio {
namespace {

constexpr int kRate = 16000;
constexpr double kC = 343.0;

std::vector<cv::Vec3d> kinect() {
  return {{0.113, 0, 0}, {-0.036, 0, 0}, {-0.076, 0, 0}, {-0.113, 0, 0}};
}
cv::Vec3d azimuth(double deg) {
  const double a = deg * std::numbers::pi / 180;
  return {std::sin(a), 0, std::cos(a)};
}

std::vector<double> white(size_t n, uint32_t seed, double rms = 0.1) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> d(0, rms);
  std::vector<double> x(n);
  for (auto& v : x) v = d(rng);
  return x;
}

// x delayed by d samples (fractional), Blackman-windowed sinc with 64 taps per side.
std::vector<double> delayed(const std::vector<double>& x, double d) {
  const int half = 64;
  const int whole = static_cast<int>(std::floor(d));
  const double frac = d - whole;
  std::vector<double> taps;  // y[i] = sum_j taps[j] * x[i - whole - j + half - 1]
  for (int j = 0; j < 2 * half; ++j) {
    const double u = j - half + 1 - frac;  // distance from the tap to the delayed instant
    const double sinc =
        std::abs(u) < 1e-12 ? 1.0 : std::sin(std::numbers::pi * u) / (std::numbers::pi * u);
    const double w = 0.42 + 0.5 * std::cos(std::numbers::pi * u / half) +
                     0.08 * std::cos(2 * std::numbers::pi * u / half);
    taps.push_back(sinc * w);
  }
  std::vector<double> y(x.size(), 0.0);
  const int n = static_cast<int>(x.size());
  for (int i = 0; i < n; ++i) {
    double acc = 0;
    for (int j = 0; j < 2 * half; ++j) {
      const int k = i - whole - j + half - 1;
      if (k >= 0 && k < n) acc += taps[static_cast<size_t>(j)] * x[static_cast<size_t>(k)];
    }
    y[static_cast<size_t>(i)] = acc;
  }
  return y;
}

// Interleaved array signal of a far-field source from `dir` (delays relative to the centroid).
std::vector<float> plane_wave(const std::vector<double>& s, const cv::Vec3d& dir) {
  const auto mics = kinect();
  cv::Vec3d centroid(0, 0, 0);
  for (const auto& p : mics) centroid += p;
  centroid *= 1.0 / static_cast<double>(mics.size());
  std::vector<float> x(s.size() * mics.size());
  for (size_t m = 0; m < mics.size(); ++m) {
    const double tau = -(mics[m] - centroid).dot(dir) / kC * kRate;
    const auto y = delayed(s, tau);
    for (size_t i = 0; i < s.size(); ++i) x[i * mics.size() + m] = static_cast<float>(y[i]);
  }
  return x;
}

double power(const std::vector<float>& x, size_t from, size_t to) {
  double p = 0;
  for (size_t i = from; i < to; ++i) p += static_cast<double>(x[i]) * x[i];
  return p / static_cast<double>(to - from);
}

std::unique_ptr<Beamformer> make(BeamformerMethod method = BeamformerMethod::kDelayAndSum) {
  BeamformerOptions o;
  o.sample_rate = kRate;
  o.mic_positions_m = kinect();
  o.method = method;
  auto b = Beamformer::create(o);
  EXPECT_TRUE(b) << (b ? "" : b.error().message);
  return std::move(*b);
}

TEST(Beamformer, PassesTheSteeredDirectionUnchanged) {
  for (auto method : {BeamformerMethod::kDelayAndSum, BeamformerMethod::kSuperdirective}) {
    const auto s = white(kRate, 1);
    const auto x = plane_wave(s, azimuth(35));
    auto b = make(method);
    b->steer(azimuth(35));
    auto y = b->apply(x);
    ASSERT_TRUE(y);
    ASSERT_EQ(y->size(), s.size());
    double err = 0, ref = 0;
    for (size_t i = 1000; i + 1000 < s.size(); ++i) {
      err += std::pow((*y)[i] - s[i], 2);
      ref += s[i] * s[i];
    }
    EXPECT_LT(10 * std::log10(err / ref), -25.0) << "distortionless toward the beam";
  }
}

TEST(Beamformer, UncorrelatedNoiseGainIsTenLogM) {
  const size_t n = static_cast<size_t>(kRate) * 2;
  std::vector<float> x(n * 4);
  for (size_t m = 0; m < 4; ++m) {
    const auto w = white(n, 10 + static_cast<uint32_t>(m));
    for (size_t i = 0; i < n; ++i) x[i * 4 + m] = static_cast<float>(w[i]);
  }
  auto b = make();
  b->steer(azimuth(20));
  auto y = b->apply(x);
  ASSERT_TRUE(y);
  const double in = 0.01, out = power(*y, 1000, n - 1000);
  const double gain_db = 10 * std::log10(in / out);
  EXPECT_NEAR(gain_db, 10 * std::log10(4.0), 0.5);
}

// Target at +40 deg, interferer of the same power at -50 deg, sensor noise 10 dB down. Steering
// at the target gives a better target-to-rest ratio than one mic, and a much better one than
// steering at the interferer (the "off-axis" beam).
TEST(Beamformer, SteeringTowardTheSourceImprovesSnrOverOffAxis) {
  const size_t n = static_cast<size_t>(kRate) * 2;
  const auto target = plane_wave(white(n, 21), azimuth(40));
  const auto interferer = plane_wave(white(n, 22), azimuth(-50));
  std::vector<float> rest(interferer);
  for (size_t m = 0; m < 4; ++m) {
    const auto w = white(n, 30 + static_cast<uint32_t>(m), 0.1 / std::sqrt(10.0));
    for (size_t i = 0; i < n; ++i) rest[i * 4 + m] += static_cast<float>(w[i]);
  }
  auto snr_db = [&](const cv::Vec3d& steer) {
    auto b = make();
    b->steer(steer);
    const auto yt = *b->apply(target);  // linear: each part through the same beam
    const auto yr = *b->apply(rest);
    return 10 * std::log10(power(yt, 1000, n - 1000) / power(yr, 1000, n - 1000));
  };
  std::vector<float> mic0_t(n), mic0_r(n);
  for (size_t i = 0; i < n; ++i) mic0_t[i] = target[i * 4], mic0_r[i] = rest[i * 4];
  const double single =
      10 * std::log10(power(mic0_t, 1000, n - 1000) / power(mic0_r, 1000, n - 1000));
  const double on = snr_db(azimuth(40)), off = snr_db(azimuth(-50));
  RecordProperty("snr_single_mic_db", std::to_string(single));
  RecordProperty("snr_steered_db", std::to_string(on));
  RecordProperty("snr_off_axis_db", std::to_string(off));
  std::printf("SNR: one mic %.1f dB, steered at the target %.1f dB, off-axis %.1f dB\n", single, on,
              off);
  EXPECT_GT(on - single, 3.0);
  EXPECT_GT(on - off, 6.0);
}

TEST(Beamformer, StreamingMatchesOneShotWhateverTheChunking) {
  const size_t n = 12345;
  const auto x = plane_wave(white(n, 5), azimuth(-20));
  auto b = make();
  b->steer(azimuth(-20));
  const auto ref = *b->apply(x);
  for (size_t chunk : {1u, 100u, 256u, 640u, 5000u}) {
    std::vector<float> y;
    for (size_t i = 0; i < n; i += chunk) {
      const size_t len = std::min(chunk, n - i);
      ASSERT_TRUE(b->process(std::span<const float>(x).subspan(i * 4, len * 4), y));
    }
    b->flush(y);
    ASSERT_EQ(y.size(), n) << "chunk " << chunk;
    for (size_t i = 0; i < n; ++i)
      ASSERT_NEAR(y[i], ref[i], 1e-6) << "chunk " << chunk << " @" << i;
  }
}

TEST(Beamformer, DelaysAndOptions) {
  auto b = make();
  b->steer({1, 0, 0});  // endfire toward +x: mic 0 (+113 mm) hears it first
  const auto d = b->arrival_delays_s();
  ASSERT_EQ(d.size(), 4u);
  EXPECT_LT(d[0], 0);
  EXPECT_GT(d[3], 0);
  EXPECT_NEAR(d[3] - d[0], 0.226 / kC, 1e-9);

  BeamformerOptions o;
  o.mic_positions_m = {{0, 0, 0}, {1.0, 0, 0}};  // 1 m apart: 47 samples across
  o.frame_length = 64;
  auto bad = Beamformer::create(o);
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().message.find("frame_length"), std::string::npos);
  o.mic_positions_m.clear();
  EXPECT_FALSE(Beamformer::create(o));
}

// Found by fuzzing (issue 18, fuzz/README.md): on this 12-byte file OpenCV's YAML parser throws
// std::length_error, which used to escape the reader and end the program; it must be an error.
TEST(FuzzRegression, MicArrayOpenCvCannotParseIsAnError) {
  const std::filesystem::path p =
      std::filesystem::path(::testing::TempDir()) / "ds_fuzz_mic_array.yaml";
  std::ofstream(p) << "%YAML:1.\n{ :";
  EXPECT_FALSE(read_mic_array(p));
  // fuzz/findings/opencv_xml_segv.calibration without its selector byte (finding 4): OpenCV's XML
  // reader dereferenced null on it; open_file_storage makes it an error.
  constexpr char kXmlSegv[] = "<?xml?>\n<open-----------------------ml ve=\0%";
  std::ofstream(p, std::ios::binary).write(kXmlSegv, sizeof kXmlSegv - 1);
  EXPECT_FALSE(read_mic_array(p));
  std::filesystem::remove(p);
}

}  // namespace
}  // namespace dreamsense::audio
