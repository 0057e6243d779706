#include "dreamsense/perception/sound_direction.hpp"

#include "dreamsense/core/blackboard.hpp"
#include "dreamsense/core/camera_model.hpp"
#include "dreamsense/sim/room_acoustics.hpp"
#include "dreamsense/sound_direction/direction_finder.hpp"
#include "dreamsense/sound_direction/sound_direction_analyzer.hpp"
#include "dreamsense/sound_direction/srp_phat.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <random>

#include "doa_eval.hpp"

namespace dreamsense::sound_direction {
namespace {

constexpr int kFs = 16000;

std::vector<float> white_noise(size_t n, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<float> d(0.f, 0.1f);
  std::vector<float> x(n);
  for (auto& v : x) v = d(rng);
  return x;
}

// A band-limited signal (sum of sinusoids below 6 kHz) evaluated at t - delay: exact fractional
// delays without interpolation error.
std::vector<float> tones(size_t n, double delay_samples) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> f(200, 6000), ph(0, 2 * M_PI);
  std::vector<std::pair<double, double>> comps;
  for (int i = 0; i < 60; ++i) comps.emplace_back(f(rng), ph(rng));
  std::vector<float> x(n);
  for (size_t i = 0; i < n; ++i) {
    double s = 0;
    const double t = (static_cast<double>(i) - delay_samples) / kFs;
    for (const auto& [fr, p] : comps) s += std::sin(2 * M_PI * fr * t + p);
    x[i] = static_cast<float>(0.01 * s);
  }
  return x;
}

// Source `azimuth_deg` (elevation 0) at 1.5 m from the Kinect array in a 5x3x4 m room; returns
// interleaved 4-channel float samples.
std::vector<float> simulated(double azimuth_deg, double rt60_s, double seconds, double snr_db = 30,
                             uint64_t seed = 1) {
  const auto g = MicArrayGeometry::kinect_v1();
  sim::RoomOptions ro;
  ro.size_m = {5.0, 3.0, 4.0};
  ro.rt60_s = rt60_s;
  const cv::Vec3d array(2.5, 1.2, 1.0);
  const double a = azimuth_deg * M_PI / 180;
  sim::AcousticPlacement pl;
  pl.source_m = array + cv::Vec3d(1.5 * std::sin(a), 0, 1.5 * std::cos(a));
  for (const auto& m : g.mics_m) pl.mics_m.push_back(array + m);
  const auto src = white_noise(static_cast<size_t>(seconds * kFs), seed);
  std::vector<double> mono(src.begin(), src.end());
  auto mix = sim::simulate(mono, ro, pl);
  EXPECT_TRUE(mix.has_value());
  sim::add_noise(*mix, snr_db, sim::NoiseColor::kPink, seed + 1);
  std::vector<float> out(mono.size() * 4);
  for (size_t n = 0; n < mono.size(); ++n)
    for (size_t c = 0; c < 4; ++c) out[n * 4 + c] = static_cast<float>((*mix)[c][n]);
  return out;
}

TEST(GccPhat, RecoversIntegerDelay) {
  auto gcc = GccPhat::create(PhatOptions{}, kFs);
  ASSERT_TRUE(gcc.has_value());
  const auto x = white_noise(1024 + 16, 3);
  std::vector<float> a(x.begin() + 8, x.begin() + 8 + 1024);
  std::vector<float> b(x.begin() + 3, x.begin() + 3 + 1024);  // b lags a by 5 samples
  const auto d = (*gcc)->delay(a, b, 12);
  EXPECT_NEAR(d.samples, 5.0, 0.05);
  EXPECT_GT(d.peak, 0.8);
  const auto back = (*gcc)->delay(b, a, 12);
  EXPECT_NEAR(back.samples, -5.0, 0.05);
}

TEST(GccPhat, RecoversFractionalDelay) {
  auto gcc = GccPhat::create(PhatOptions{}, kFs);
  ASSERT_TRUE(gcc.has_value());
  for (double delay : {2.4, -3.7, 0.3}) {
    const auto a = tones(1024, 0.0);
    const auto b = tones(1024, delay);
    EXPECT_NEAR((*gcc)->delay(a, b, 12).samples, delay, 0.15) << delay;
  }
}

TEST(SrpPhat, LinearGridIsFrontHalfPlaneWithoutElevation) {
  auto srp = SrpPhat::create(MicArrayGeometry::kinect_v1(), PhatOptions{});
  ASSERT_TRUE(srp.has_value());
  EXPECT_TRUE((*srp)->linear());
  EXPECT_EQ((*srp)->grid().size(), 181u);
  EXPECT_DOUBLE_EQ((*srp)->grid().front().azimuth_deg, -90);
  EXPECT_DOUBLE_EQ((*srp)->grid().back().azimuth_deg, 90);
}

std::optional<SrpPeak> utterance_estimate(const std::vector<float>& audio,
                                          std::vector<FrameEstimate>* frames = nullptr) {
  auto f = DirectionFinder::create(MicArrayGeometry::kinect_v1(), DirectionFinderOptions{});
  EXPECT_TRUE(f.has_value());
  std::vector<FrameEstimate> est;
  // Lead-in of quiet noise so the VAD learns the floor.
  std::vector<float> lead = white_noise(kFs / 2 * 4, 99);
  for (auto& v : lead) v *= 0.001f;
  EXPECT_TRUE((*f)->push(lead, est).has_value());
  EXPECT_TRUE((*f)->push(audio, est).has_value());
  if (frames) *frames = est;
  return (*f)->utterance_peak();
}

TEST(SrpPhat, AnechoicSourceWithinTwoDegrees) {
  for (double az : {-60.0, -20.0, 0.0, 35.0, 70.0}) {
    const auto p = utterance_estimate(simulated(az, 0.0, 1.0));
    ASSERT_TRUE(p.has_value()) << az;
    EXPECT_NEAR(p->azimuth_deg, az, 2.0) << az;
    EXPECT_FALSE(p->elevation_deg.has_value());
  }
}

TEST(SrpPhat, ReverberantSourceWithinFiveDegrees) {
  for (double az : {-45.0, 10.0, 50.0}) {
    std::vector<FrameEstimate> frames;
    const auto p = utterance_estimate(simulated(az, 0.4, 1.5, 10), &frames);
    ASSERT_TRUE(p.has_value()) << az;
    EXPECT_NEAR(p->azimuth_deg, az, 5.0) << az;
    ASSERT_FALSE(frames.empty());
    ASSERT_TRUE(frames.back().smoothed_peak.has_value());
    EXPECT_NEAR(frames.back().smoothed_peak->azimuth_deg, az, 8.0) << az;
  }
}

TEST(SrpPhat, PlanarArrayGivesAzimuthAndElevation) {
  // A horizontal 4-mic square (ReSpeaker-like, 6 cm side) hears a source above its plane.
  MicArrayGeometry g;
  g.mics_m = {{0.03, 0, 0.03}, {-0.03, 0, 0.03}, {-0.03, 0, -0.03}, {0.03, 0, -0.03}};
  EXPECT_EQ(g.rank(), 2);
  auto f = DirectionFinder::create(g, DirectionFinderOptions{});
  ASSERT_TRUE(f.has_value());
  sim::RoomOptions ro;
  ro.size_m = {5.0, 3.0, 4.0};
  ro.rt60_s = 0;
  const cv::Vec3d array(2.5, 2.0, 2.0);  // room y down: the source at y 1.0 is above the array
  sim::AcousticPlacement pl;
  const double az = 120 * M_PI / 180, el = 30 * M_PI / 180;
  pl.source_m = array + 1.5 * cv::Vec3d(std::sin(az) * std::cos(el), -std::sin(el),
                                        std::cos(az) * std::cos(el));
  for (const auto& m : g.mics_m) pl.mics_m.push_back(array + m);
  const auto src = white_noise(kFs, 5);
  auto mix = sim::simulate(std::vector<double>(src.begin(), src.end()), ro, pl);
  ASSERT_TRUE(mix.has_value());
  std::vector<float> audio(src.size() * 4);
  for (size_t n = 0; n < src.size(); ++n)
    for (size_t c = 0; c < 4; ++c) audio[n * 4 + c] = static_cast<float>((*mix)[c][n]);
  std::vector<FrameEstimate> est;
  std::vector<float> lead(kFs / 2 * 4, 0.f);
  lead[0] = 1e-3f;
  ASSERT_TRUE((*f)->push(white_noise(kFs / 2 * 4, 1), est).has_value());
  (*f)->reset_utterance();
  for (auto& v : audio) v *= 30.f;  // well above the lead-in noise
  ASSERT_TRUE((*f)->push(audio, est).has_value());
  const auto p = (*f)->utterance_peak();
  ASSERT_TRUE(p.has_value());
  ASSERT_TRUE(p->elevation_deg.has_value());
  EXPECT_NEAR(p->azimuth_deg, 120, 6);
  EXPECT_NEAR(*p->elevation_deg, 30, 10);
}

TEST(DirectionFinder, SilenceGivesNoDirection) {
  auto f = DirectionFinder::create(MicArrayGeometry::kinect_v1(), DirectionFinderOptions{});
  ASSERT_TRUE(f.has_value());
  std::vector<FrameEstimate> est;
  ASSERT_TRUE((*f)->push(std::vector<float>(kFs * 4, 0.f), est).has_value());
  ASSERT_FALSE(est.empty());
  for (const auto& e : est) EXPECT_FALSE(e.voiced);
  EXPECT_FALSE((*f)->utterance_peak().has_value());
}

TEST(DirectionFinder, BadInputIsAClearError) {
  auto f = DirectionFinder::create(MicArrayGeometry::kinect_v1(), DirectionFinderOptions{});
  ASSERT_TRUE(f.has_value());
  std::vector<FrameEstimate> est;
  auto r = (*f)->push(std::vector<float>(7, 0.f), est);
  ASSERT_FALSE(r.has_value());
  EXPECT_NE(r.error().message.find("4-channel"), std::string::npos) << r.error().message;
  std::vector<float> nan(8, 0.f);
  nan[3] = std::nanf("");
  EXPECT_FALSE((*f)->push(nan, est).has_value());

  MicArrayGeometry one;
  one.mics_m = {{0, 0, 0}};
  EXPECT_FALSE(DirectionFinder::create(one, {}).has_value());
  MicArrayGeometry tilted;
  tilted.mics_m = {{0, 0, 0}, {0, 0, 0.1}};
  auto t = DirectionFinder::create(tilted, {});
  ASSERT_FALSE(t.has_value());
  EXPECT_NE(t.error().message.find("x axis"), std::string::npos);
  DirectionFinderOptions o;
  o.phat.frame_length = 1000;
  EXPECT_FALSE(DirectionFinder::create(MicArrayGeometry::kinect_v1(), o).has_value());
}

TEST(MicArray, ReadsDemoCalibration) {
  const auto dir = std::filesystem::temp_directory_path() / "ds_sound_direction_test";
  std::filesystem::create_directories(dir);
  const auto path = dir / "mic_array.yaml";
  {
    cv::FileStorage f(path.string(), cv::FileStorage::WRITE);
    f << "sample_rate" << 16000;
    cv::Mat m = (cv::Mat_<double>(4, 3) << 0.113, 0, 0, -0.036, 0, 0, -0.076, 0, 0, -0.113, 0, 0);
    f << "mic_positions_m" << m;
    f << "array_from_world_R" << cv::Mat(cv::Matx33d::eye());
    f << "array_from_world_t" << cv::Mat(cv::Vec3d(0, -0.05, 0));
  }
  auto g = read_mic_array(path);
  ASSERT_TRUE(g.has_value()) << g.error().message;
  EXPECT_EQ(g->mics_m.size(), 4u);
  EXPECT_EQ(g->rank(), 1);
  EXPECT_NEAR(g->array_from_world_t[1], -0.05, 1e-12);
  EXPECT_FALSE(read_mic_array(dir / "missing.yaml").has_value());
  std::filesystem::remove_all(dir);
}

// ---- analyser harness: timestamped MultiFrames with 40 ms audio chunks at 25 Hz ticks.

struct HarnessResult {
  std::vector<Entry<SoundDirection>> entries;  // one per write, in order
  int errors = 0;
  std::string last_error;
};

HarnessResult run_analyzer(Analyzer& a, const std::vector<float>& audio, int channels,
                           int sample_rate) {
  HarnessResult r;
  Blackboard bb;
  const size_t chunk = static_cast<size_t>(sample_rate / 25);
  const size_t frames = audio.size() / static_cast<size_t>(channels);
  uint64_t tick = 0;
  for (size_t n = 0; n < frames; n += chunk, ++tick) {
    AudioChunk c;
    c.sample_rate = sample_rate;
    c.channels = channels;
    const size_t len = std::min(chunk, frames - n);
    c.samples.assign(audio.begin() + static_cast<std::ptrdiff_t>(n * channels),
                     audio.begin() + static_cast<std::ptrdiff_t>((n + len) * channels));
    MultiFrame mf;
    mf.tick = tick;
    mf.stamp = Timestamp::from_ns(static_cast<int64_t>(tick) * 40000000);
    mf.chunks["mic_array"].push_back(make_frame("mic_array", mf.stamp, tick, std::move(c)));
    BlackboardWriter w{std::string(a.name())};
    auto s = a.process(mf, bb.snapshot(), w);
    if (!s) {
      ++r.errors;
      r.last_error = s.error().message;
      continue;
    }
    const size_t before = w.size();
    bb.commit(w, mf.stamp);
    if (before > 0) {
      auto e = bb.snapshot().get(keys::kSoundDirection);
      EXPECT_TRUE(e.has_value());
      EXPECT_LE(e->stamp, mf.stamp) << "observations are never stamped after their tick";
      r.entries.push_back(*e);
    }
  }
  return r;
}

TEST(SoundDirectionAnalyzer, FindsTheSourceAndWritesWorldDirection) {
  SoundDirectionAnalyzerOptions o;
  o.geometry.array_from_world_R = rotation_from_ypr_deg(90, 0, 0);
  auto a = make_sound_direction_analyzer(o);
  ASSERT_TRUE(a.has_value());
  EXPECT_EQ((*a)->contract().writes.front(), keys::kSoundDirection.name);
  std::vector<float> audio(static_cast<size_t>(kFs / 2) * 4);  // 0.5 s quiet lead-in
  const auto noise = white_noise(audio.size(), 11);
  for (size_t i = 0; i < audio.size(); ++i) audio[i] = 0.001f * noise[i];
  const auto src = simulated(25, 0.3, 2.0, 25);
  audio.insert(audio.end(), src.begin(), src.end());
  const auto r = run_analyzer(**a, audio, 4, kFs);
  EXPECT_EQ(r.errors, 0) << r.last_error;
  ASSERT_GT(r.entries.size(), 40u);
  EXPECT_FALSE(r.entries.front().present()) << "lead-in is not speech";
  const auto& last = r.entries.back();
  ASSERT_TRUE(last.present());
  EXPECT_NEAR(last.value->azimuth_deg, 25, 5);
  EXPECT_FALSE(last.value->elevation_deg.has_value());
  EXPECT_EQ(last.value->sensor, "mic_array");
  EXPECT_GT(last.confidence, 0.5f);
  const cv::Vec3d expect_world = o.geometry.array_from_world_R.t() * last.value->direction_array;
  EXPECT_LT(cv::norm(last.value->direction_world - expect_world), 1e-9);
}

TEST(SoundDirectionAnalyzer, SilenceIsAbsentNotAnError) {
  auto a = make_sound_direction_analyzer({});
  ASSERT_TRUE(a.has_value());
  const auto r = run_analyzer(**a, std::vector<float>(static_cast<size_t>(kFs) * 4, 0.f), 4, kFs);
  EXPECT_EQ(r.errors, 0);
  ASSERT_FALSE(r.entries.empty());
  for (const auto& e : r.entries) EXPECT_FALSE(e.present());
}

TEST(SoundDirectionAnalyzer, WrongRateOrChannelsIsAClearError) {
  auto a = make_sound_direction_analyzer({});
  ASSERT_TRUE(a.has_value());
  auto r = run_analyzer(**a, std::vector<float>(48000 * 4 / 5, 0.01f), 4, 48000);
  EXPECT_GT(r.errors, 0);
  EXPECT_NE(r.last_error.find("48000 Hz"), std::string::npos) << r.last_error;
  EXPECT_NE(r.last_error.find("4 microphones at 16000 Hz"), std::string::npos) << r.last_error;
  r = run_analyzer(**a, std::vector<float>(16000 * 2 / 5, 0.01f), 2, kFs);
  EXPECT_GT(r.errors, 0);
  EXPECT_NE(r.last_error.find("2 channel(s)"), std::string::npos) << r.last_error;
  EXPECT_TRUE(r.entries.empty());
}

TEST(DoaEval, ParsesAzimuthGrid) {
  DoaEvalOptions o;
  ASSERT_TRUE(parse_azimuth_grid("-30:30:15", o).has_value());
  EXPECT_EQ(o.azimuth_from_deg, -30);
  EXPECT_EQ(o.azimuth_step_deg, 15);
  EXPECT_FALSE(parse_azimuth_grid("-30:30", o).has_value());
  EXPECT_FALSE(parse_azimuth_grid("30:-30:5", o).has_value());
}

TEST(DoaEval, SmallGridMeetsTheContract) {
  DoaEvalOptions o;
  if (!std::filesystem::exists(o.clips_dir / "goforward.raw"))
    GTEST_SKIP() << "pocketsphinx-testdata is not installed";
  o.azimuth_from_deg = -50;
  o.azimuth_to_deg = 50;
  o.azimuth_step_deg = 50;
  o.placements = 1;
  auto r = run_doa_eval(o);
  ASSERT_TRUE(r.has_value()) << r.error().message;
  EXPECT_EQ((*r)["task"], "doa");
  EXPECT_EQ((*r)["dataset"]["items"], 3);
  EXPECT_LE((*r)["metrics"]["mae_deg"].get<double>(), 5.0);
  EXPECT_LE((*r)["timing"]["cpu_fraction"].get<double>(), 0.05);
}

}  // namespace
}  // namespace dreamsense::sound_direction
