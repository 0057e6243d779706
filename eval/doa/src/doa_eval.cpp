#include "dreamsense/eval/doa_eval.hpp"

#include "dreamsense/audio/audio_file.hpp"
#include "dreamsense/sim/room_acoustics.hpp"

#include <algorithm>
#include <cmath>
#include <ctime>
#include <fstream>
#include <map>
#include <random>
#include <span>
#include <sstream>

namespace dreamsense::sound_direction {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

const char* const kClips[] = {"goforward.raw",
                              "cards/001.wav",
                              "cards/002.wav",
                              "cards/003.wav",
                              "cards/004.wav",
                              "cards/005.wav",
                              "librivox/sense_and_sensibility_01_austen_64kb-0870.wav",
                              "librivox/sense_and_sensibility_01_austen_64kb-0880.wav",
                              "librivox/sense_and_sensibility_01_austen_64kb-0890.wav",
                              "librivox/sense_and_sensibility_01_austen_64kb-0920.wav",
                              "librivox/sense_and_sensibility_01_austen_64kb-0930.wav"};

Result<std::vector<double>> load_clip(const fs::path& path, int rate) {
  if (!fs::exists(path))
    return make_error(ErrorCode::kNotFound,
                      "{}: missing speech clip (install Debian package pocketsphinx-testdata)",
                      path.string());
  audio::ReadAudioOptions ro;
  ro.require_mono = true;
  ro.expected_sample_rate = rate;  // also checks that .raw clips (16 kHz) match the array
  DS_ASSIGN_OR_RETURN(audio::AudioClip clip, audio::read_audio(path, ro));
  return std::vector<double>(clip.samples.begin(), clip.samples.end());
}

// Speech extent of a clean clip (seconds): 20 ms frames within 30 dB of the loudest one.
std::pair<double, double> speech_extent(const std::vector<double>& x, double fs) {
  const size_t n = static_cast<size_t>(0.02 * fs);
  std::vector<double> e;
  for (size_t i = 0; i + n <= x.size(); i += n) {
    double s = 0;
    for (size_t k = 0; k < n; ++k) s += x[i + k] * x[i + k];
    e.push_back(s / static_cast<double>(n));
  }
  if (e.empty()) return {0, 0};
  const double top = *std::max_element(e.begin(), e.end());
  size_t a = 0, b = e.size();
  while (a < e.size() && e[a] < top * 1e-3) ++a;
  while (b > a && e[b - 1] < top * 1e-3) --b;
  return {static_cast<double>(a * n) / fs, static_cast<double>(b * n) / fs};
}

double thread_cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

double angle_error(double est, double truth, bool linear) {
  double d = std::abs(est - truth);
  if (!linear) d = std::min(d, 360 - d);
  return d;
}

double mean(const std::vector<double>& v) {
  if (v.empty()) return 0;
  double s = 0;
  for (double x : v) s += x;
  return s / static_cast<double>(v.size());
}
double fraction_within(const std::vector<double>& v, double limit) {
  if (v.empty()) return 0;
  return static_cast<double>(
             std::count_if(v.begin(), v.end(), [&](double e) { return e <= limit; })) /
         static_cast<double>(v.size());
}

}  // namespace

Status DoaEvalOptions::check() const {
  std::string bad;
  if (!(rt60_s >= 0 && rt60_s <= 2)) bad += " rt60 must be in [0, 2] s;";
  if (!(snr_db >= -20 && snr_db <= 100)) bad += " snr must be in [-20, 100] dB;";
  if (!(azimuth_step_deg > 0) || !(azimuth_to_deg >= azimuth_from_deg))
    bad += " azimuths need FROM <= TO and STEP > 0;";
  if (azimuth_from_deg < -180 || azimuth_to_deg > 180) bad += " azimuths must be in [-180, 180];";
  if (placements < 1) bad += " placements must be >= 1;";
  if (!(distance_min_m >= 0.5 && distance_max_m >= distance_min_m && distance_max_m <= 2.2))
    bad += " source distance must be within [0.5, 2.2] m;";
  if (!(height_m >= 0 && height_m <= 0.5)) bad += " height_m must be in [0, 0.5];";
  if (!bad.empty()) return make_error(ErrorCode::kInvalidArgument, "eval doa:" + bad);
  return ok_status();
}

Status parse_azimuth_grid(const std::string& text, DoaEvalOptions& o) {
  double a = 0, b = 0, s = 0;
  char c1 = 0, c2 = 0;
  std::istringstream in(text);
  if (!(in >> a >> c1 >> b >> c2 >> s) || c1 != ':' || c2 != ':' || !(in >> std::ws).eof())
    return make_error(ErrorCode::kInvalidArgument,
                      "--azimuths '{}': expected FROM:TO:STEP in degrees, e.g. -60:60:10", text);
  o.azimuth_from_deg = a;
  o.azimuth_to_deg = b;
  o.azimuth_step_deg = s;
  return o.check();
}

Result<eval::EvalReport> run_doa_eval(const DoaEvalOptions& o,
                                      const std::function<void(double)>& progress) {
  if (auto s = o.check(); !s) return tl::unexpected(s.error());
  auto geometry = named_geometry(o.geometry);
  if (!geometry) return tl::unexpected(geometry.error());
  const int fs = geometry->sample_rate;
  auto finder = DirectionFinder::create(*geometry, o.finder);
  if (!finder) return tl::unexpected(finder.error());
  const bool linear = geometry->rank() <= 1;

  std::vector<std::vector<double>> clips;
  std::vector<std::pair<double, double>> extents;
  for (const char* c : kClips) {
    auto x = load_clip(o.clips_dir / c, fs);
    if (!x) return tl::unexpected(x.error());
    extents.push_back(speech_extent(*x, fs));
    clips.push_back(std::move(*x));
  }

  std::vector<double> azimuths;
  for (int i = 0;; ++i) {
    const double az = o.azimuth_from_deg + i * o.azimuth_step_deg;
    if (az > o.azimuth_to_deg + 1e-9) break;
    azimuths.push_back(az);
  }
  // Three shoebox rooms (width x height x depth); the array faces +z from near one wall.
  const cv::Vec3d rooms[] = {{5.0, 3.0, 4.0}, {6.0, 2.7, 5.0}, {5.5, 3.2, 4.5}};

  std::vector<double> utt_err, all_err, frame_err;
  int missing = 0;
  std::map<double, std::vector<double>> per_az;
  struct Bin {
    int frames = 0, within = 0;
  };
  std::vector<Bin> bins(10);
  double cpu_s = 0, audio_s = 0, sim_s = 0;
  int64_t voiced = 0, speech_frames = 0;
  json items = json::array();
  const size_t total = azimuths.size() * static_cast<size_t>(o.placements);
  size_t done = 0;
  const size_t chunk = static_cast<size_t>(fs / 10);  // 100 ms, as the demo session's chunks
  std::vector<FrameEstimate> est;

  for (size_t ai = 0; ai < azimuths.size(); ++ai) {
    for (int p = 0; p < o.placements; ++p, ++done) {
      std::mt19937_64 rng(o.seed * 1000003ULL + ai * 1009ULL + static_cast<uint64_t>(p));
      auto uni = [&](double a, double b) {
        return a + (b - a) * (static_cast<double>(rng() >> 11) * 0x1.0p-53);
      };
      const size_t clip_index = static_cast<size_t>(rng() % clips.size());
      // One second of room noise before the clip: the VAD learns the noise floor there, as it
      // does in the pauses of a session.
      const size_t lead = static_cast<size_t>(fs);
      std::vector<double> clip(lead, 0.0);
      clip.insert(clip.end(), clips[clip_index].begin(), clips[clip_index].end());
      sim::RoomOptions ro;
      ro.size_m = rooms[static_cast<size_t>(rng() % 3)];
      ro.rt60_s = o.rt60_s;
      ro.sample_rate_hz = fs;
      const cv::Vec3d array_room(0.5 * ro.size_m[0] + uni(-0.3, 0.3), uni(1.0, 1.3), uni(0.8, 1.2));
      const double az = azimuths[ai];
      const double dist = uni(o.distance_min_m, o.distance_max_m);
      const double h = uni(-o.height_m, o.height_m);  // up = -y
      const double a = az * M_PI / 180;
      const cv::Vec3d src_array(dist * std::sin(a), -h, dist * std::cos(a));
      sim::AcousticPlacement pl;
      pl.source_m = array_room + src_array;
      for (const auto& m : geometry->mics_m) pl.mics_m.push_back(array_room + m);
      const double t_sim0 = thread_cpu_seconds();
      auto mix = sim::simulate(clip, ro, pl);
      if (!mix) return tl::unexpected(mix.error());
      const double delay = cv::norm(src_array) / ro.speed_of_sound_m_s;
      const auto [s0, s1] = extents[clip_index];
      const size_t b0 = lead + static_cast<size_t>((s0 + delay) * fs);
      const size_t b1 = std::min((*mix)[0].size(), lead + static_cast<size_t>((s1 + delay) * fs));
      const double speech_power = sim::mean_power(*mix, b0, b1);
      sim::add_noise(*mix, o.snr_db, sim::NoiseColor::kPink, rng(), speech_power);
      sim_s += thread_cpu_seconds() - t_sim0;

      const size_t frames = (*mix)[0].size();
      const size_t channels = mix->size();
      std::vector<float> inter(frames * channels);
      for (size_t n = 0; n < frames; ++n)
        for (size_t c = 0; c < channels; ++c)
          inter[n * channels + c] = static_cast<float>(std::clamp((*mix)[c][n], -1.0, 1.0));

      est.clear();
      const double t0 = thread_cpu_seconds();
      (*finder)->reset();
      for (size_t n = 0; n < frames; n += chunk) {
        const size_t len = std::min(chunk, frames - n) * channels;
        if (auto s = (*finder)->push(std::span<const float>(inter.data() + n * channels, len), est);
            !s)
          return tl::unexpected(s.error());
      }
      const auto utt = (*finder)->utterance_peak();
      cpu_s += thread_cpu_seconds() - t0;
      audio_s += static_cast<double>(frames) / fs;

      // Truth azimuth: the source seen from the array centre (far field; elevation ignored by a
      // linear array, which measures the cone angle asin(sin(az) cos(el))).
      // An item without any voiced frame has no estimate: it counts as a miss in within_10deg
      // (and its error as 90 deg, chance level for a half-plane, in per_class) but is left out
      // of mae_deg, which is over the items with an estimate (items_without_estimate says how
      // many).
      double item_err = 90;
      if (utt) {
        item_err = angle_error(utt->azimuth_deg, az, linear);
        utt_err.push_back(item_err);
      } else {
        ++missing;
      }
      all_err.push_back(item_err);
      per_az[az].push_back(item_err);
      int item_frames = 0;
      for (const auto& e : est) {
        const int64_t c = e.centre_sample;
        if (c < static_cast<int64_t>(b0) || c > static_cast<int64_t>(b1)) continue;
        ++speech_frames;
        if (!e.voiced || !e.smoothed_peak) continue;
        ++voiced;
        ++item_frames;
        const double err = angle_error(e.smoothed_peak->azimuth_deg, az, linear);
        frame_err.push_back(err);
        Bin& bin = bins[std::min<size_t>(9, static_cast<size_t>(e.confidence * 10))];
        bin.frames++;
        if (err <= 10) bin.within++;
      }
      items.push_back({{"azimuth_deg", az},
                       {"clip", kClips[clip_index]},
                       {"distance_m", dist},
                       {"height_m", h},
                       {"room_m", {ro.size_m[0], ro.size_m[1], ro.size_m[2]}},
                       {"estimate_deg", utt ? json(utt->azimuth_deg) : json(nullptr)},
                       {"error_deg", item_err},
                       {"voiced_frames", item_frames}});
      if (progress) progress(static_cast<double>(done + 1) / static_cast<double>(total));
    }
  }

  json per_class = json::object();
  for (const auto& [az, errs] : per_az)
    per_class[fmt::format("{:g}", az)] = {{"mae_deg", mean(errs)},
                                          {"within_10deg", fraction_within(errs, 10)},
                                          {"items", errs.size()}};
  json calibration = json::array();
  for (size_t i = 0; i < bins.size(); ++i)
    calibration.push_back(
        {{"confidence", {0.1 * static_cast<double>(i), 0.1 * (i + 1.0)}},
         {"frames", bins[i].frames},
         {"within_10deg", bins[i].frames
                              ? json(static_cast<double>(bins[i].within) / bins[i].frames)
                              : json(nullptr)}});
  std::vector<double> confident;
  {
    int n = 0, w = 0;
    for (size_t i = 7; i < bins.size(); ++i) n += bins[i].frames, w += bins[i].within;
    confident = {static_cast<double>(n), n ? static_cast<double>(w) / n : 0.0};
  }
  eval::EvalReport out;
  out.task = "doa";
  out.dataset =
      fmt::format("simulated rooms ({} geometry, pocketsphinx-testdata speech)", o.geometry);
  out.items = all_err.size();
  out.protocol = fmt::format(
      "image-source rooms (5x3x4, 6x2.7x5, 5.5x3.2x4.5 m), RT60 {} s, pink noise at SNR {} dB "
      "(speech-active power); azimuths {}:{}:{} deg, {} seeded placements each (1 s of noise, then "
      "the clip; distance {}-{} m, height +-{} m, seed {}); utterance estimate = peak of the "
      "SRP-PHAT map averaged "
      "over VAD-voiced frames (weighted by their confidence; mae_deg over items with an estimate, "
      "within_10deg over all items); frame metrics over voiced frames inside the speech extent",
      o.rt60_s, o.snr_db, o.azimuth_from_deg, o.azimuth_to_deg, o.azimuth_step_deg, o.placements,
      o.distance_min_m, o.distance_max_m, o.height_m, o.seed);
  out.metrics = {
      {"mae_deg", utt_err.empty() ? json(nullptr) : json(mean(utt_err))},
      {"within_10deg", fraction_within(all_err, 10)},
      {"items_without_estimate", missing},
      {"frame_mae_deg", mean(frame_err)},
      {"frame_within_10deg", fraction_within(frame_err, 10)},
      {"voiced_fraction", speech_frames ? static_cast<double>(voiced) / speech_frames : 0.0},
      {"confident_frames_within_10deg", confident[1]},
      {"confident_frame_fraction", voiced ? confident[0] / static_cast<double>(voiced) : 0.0}};
  out.timing = {{"cpu_fraction", audio_s > 0 ? cpu_s / audio_s : 0.0},
                {"cpu_seconds", cpu_s},
                {"audio_seconds", audio_s},
                {"simulation_cpu_seconds", sim_s}};
  out.per_class = per_class;
  out.extra["confidence_calibration"] = calibration;
  out.extra["items"] = items;
  return out;
}

}  // namespace dreamsense::sound_direction
