#include "dreamsense/sim/demo_session.hpp"

#include "dreamsense/audio/audio_file.hpp"
#include "dreamsense/core/sensor_frame.hpp"
#include "dreamsense/sim/demo_children.hpp"
#include "dreamsense/sim/face_renderer.hpp"
#include "dreamsense/sim/room_acoustics.hpp"
#include "dreamsense/sim/scene_renderer.hpp"
#include "dreamsense/sources/session.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sndfile.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <fstream>
#include <mutex>
#include <optional>
#include <random>
#include <sstream>
#include <thread>

#include "sim_math.hpp"

namespace dreamsense::sim {
namespace {

using nlohmann::json;
namespace fs = std::filesystem;

constexpr const char* kGenerator = "dreamsense-sim demo v1";
// Session stamp 0 = 2016-01-01T00:00:00Z (fixed, so the manifest is deterministic).
constexpr int64_t kClockOriginUnixNs = 1451606400LL * 1000000000LL;

const std::vector<std::string> kCameraIds = {"camera_left", "camera_middle", "camera_right"};

int64_t stamp_ns(int64_t k, double rate_hz) {
  return static_cast<int64_t>(std::llround(static_cast<double>(k) * 1e9 / rate_hz));
}
int64_t frame_count(double duration_s, double rate_hz) {
  return static_cast<int64_t>(std::ceil(duration_s * rate_hz - 1e-9));
}

double gaussian(std::mt19937_64& rng) {  // Box-Muller (portable)
  double u1 = 0;
  do {
    u1 = static_cast<double>(rng() >> 11) * 0x1.0p-53;
  } while (u1 <= 0);
  const double u2 = static_cast<double>(rng() >> 11) * 0x1.0p-53;
  return std::sqrt(-2 * std::log(u1)) * std::cos(2 * CV_PI * u2);
}
using detail::uniform;

// Fixed decimal precision for truth values (stable text, no "-0").
double q(double v, double scale = 1e6) {
  const double r = std::round(v * scale) / scale;
  return r == 0 ? 0.0 : r;
}
json vec_json(const cv::Vec3d& v, double scale = 1e6) {
  return json::array({q(v[0], scale), q(v[1], scale), q(v[2], scale)});
}
json px_json(const cv::Point2d& p) { return json::array({q(p.x, 1e3), q(p.y, 1e3)}); }

Error media_error(const fs::path& file, const char* package) {
  return Error{ErrorCode::kNotFound, fmt::format("{}: missing demo media (install the Debian "
                                                 "package {})",
                                                 file.string(), package)};
}

// ---------------------------------------------------------------- media

Result<std::vector<double>> load_clip(const fs::path& path, int expected_rate) {
  if (!fs::exists(path)) return tl::unexpected(media_error(path, "pocketsphinx-testdata"));
  audio::ReadAudioOptions ro;
  ro.require_mono = true;
  ro.expected_sample_rate = expected_rate;  // .raw clips are 16 kHz
  DS_ASSIGN_OR_RETURN(audio::AudioClip clip, audio::read_audio(path, ro));
  return std::vector<double>(clip.samples.begin(), clip.samples.end());
}

// The child-like voice (DemoOptions::child_voice_shift): x read as sampled at rate x factor and
// converted to `rate`: played at `rate` it is `factor` times faster and higher.
std::vector<double> shift_voice(const std::vector<double>& x, double factor, int rate) {
  if (factor == 1.0) return x;
  std::vector<float> f(x.begin(), x.end());
  const std::vector<int16_t> pcm = audio::to_pcm16(f);
  const std::vector<int16_t> y = audio::resample_pcm16(
      pcm, static_cast<int>(std::lround(rate * factor)), rate, audio::Pcm16Resampler::kSoxr);
  std::vector<double> out(y.size());
  for (size_t i = 0; i < y.size(); ++i) out[i] = y[i] / 32768.0;
  return out;
}

// "<s> ten of clubs  </s> (001)" lines -> id -> text.
Result<std::map<std::string, std::string>> read_transcription(const fs::path& path) {
  if (!fs::exists(path)) return tl::unexpected(media_error(path, "pocketsphinx-testdata"));
  std::ifstream in(path);
  std::map<std::string, std::string> out;
  std::string line;
  while (std::getline(in, line)) {
    const auto open = line.rfind('('), close = line.rfind(')');
    if (open == std::string::npos || close == std::string::npos || close < open) continue;
    std::string text = line.substr(0, open);
    for (const char* tag : {"<s>", "</s>"}) {
      const auto p = text.find(tag);
      if (p != std::string::npos) text.erase(p, std::string(tag).size());
    }
    const auto b = text.find_first_not_of(' '), e = text.find_last_not_of(' ');
    out[line.substr(open + 1, close - open - 1)] =
        b == std::string::npos ? "" : text.substr(b, e - b + 1);
  }
  return out;
}

// Speech extent by an energy gate: 20 ms frames within 30 dB of the loudest frame.
std::pair<double, double> speech_extent(const std::vector<double>& x, double fs) {
  const size_t win = static_cast<size_t>(0.02 * fs);
  std::vector<double> e;
  for (size_t i = 0; i + win <= x.size(); i += win) {
    double s = 0;
    for (size_t j = i; j < i + win; ++j) s += x[j] * x[j];
    e.push_back(s / static_cast<double>(win));
  }
  if (e.empty()) return {0.0, static_cast<double>(x.size()) / fs};
  const double thr = *std::max_element(e.begin(), e.end()) * std::pow(10.0, -30.0 / 10.0);
  size_t first = 0, last = e.size() - 1;
  while (first < e.size() && e[first] < thr) ++first;
  while (last > first && e[last] < thr) --last;
  return {static_cast<double>(first * win) / fs, static_cast<double>((last + 1) * win) / fs};
}

struct ClipSpec {
  const char* file;
  const char* transcription;  // file holding the text, or nullptr
  const char* id;             // id in the transcription, or the literal text
  const char* speaker;
};
// goforward.raw carries no transcription file; its text is the one pocketsphinx's own tests
// expect ("go forward ten meters").
const ClipSpec kClips[] = {
    {"cards/001.wav", "cards/cards.transcription", "001", "child"},
    {"cards/002.wav", "cards/cards.transcription", "002", "child"},
    {"cards/003.wav", "cards/cards.transcription", "003", "child"},
    {"cards/004.wav", "cards/cards.transcription", "004", "child"},
    {"goforward.raw", nullptr, "go forward ten meters", "child"},
    {"librivox/sense_and_sensibility_01_austen_64kb-0880.wav", "librivox/transcription",
     "sense_and_sensibility_01_austen_64kb-0880", "therapist"},
    {"librivox/sense_and_sensibility_01_austen_64kb-0930.wav", "librivox/transcription",
     "sense_and_sensibility_01_austen_64kb-0930", "therapist"},
    {"librivox/sense_and_sensibility_01_austen_64kb-0890.wav", "librivox/transcription",
     "sense_and_sensibility_01_austen_64kb-0890", "therapist"},
};

// Enrolment audio for speaker identification (identifyVoice): other recordings of the session's
// speakers that the session never plays. The child's clips come from two talkers (cards/*.wav;
// goforward.raw, whose talker also says numbers.raw and something.raw), the therapist's from the
// LibriVox reader.
const std::pair<const char*, const char*> kEnrolClips[] = {
    {"child", "cards/005.wav"},
    {"child", "numbers.raw"},
    {"child", "something.raw"},
    {"therapist", "librivox/sense_and_sensibility_01_austen_64kb-0870.wav"},
    {"therapist", "librivox/sense_and_sensibility_01_austen_64kb-0920.wav"},
};

// enroll/<speaker>/<n>.wav (session metadata voice_enroll): what the array's first microphone
// records in the same room before the session, the child at the head rest, the therapist at the
// side (45 deg, 1.6 m), with the session's noise level. 16-bit mono at the demo rate.
Status write_enrolment(const fs::path& dir, const DemoOptions& o, const DemoGeometry& g,
                       const RoomOptions& room, const std::vector<cv::Vec3d>& mics_room) {
  std::map<std::string, int> count;
  uint64_t index = 0;
  for (const auto& [speaker, file] : kEnrolClips) {
    auto x = load_clip(o.pocketsphinx_data_dir / file, o.audio_sample_rate);
    if (!x) return tl::unexpected(x.error());
    if (std::string(speaker) == "child")
      *x = shift_voice(*x, o.child_voice_shift, o.audio_sample_rate);
    const double az = 45 * CV_PI / 180;
    const cv::Vec3d source =
        std::string(speaker) == "child"
            ? g.head_rest_m + cv::Vec3d(0, 0.075, -0.01)  // mouth
            : g.mic_array_m + cv::Vec3d(1.6 * std::sin(az), -0.3, 1.6 * std::cos(az));
    auto wet =
        simulate(*x, room, AcousticPlacement{g.room_from_world(source), {mics_room.front()}});
    if (!wet) return tl::unexpected(wet.error());
    const auto [a, b] = speech_extent(*x, o.audio_sample_rate);
    const size_t n = (*wet)[0].size();
    add_noise(*wet, o.snr_db, NoiseColor::kPink, sub_seed(o.seed, "enrol_noise", index++),
              mean_power(*wet, std::min(n, static_cast<size_t>(a * o.audio_sample_rate)),
                         std::min(n, static_cast<size_t>(b * o.audio_sample_rate))));
    double peak = 1e-12;
    for (double v : (*wet)[0]) peak = std::max(peak, std::abs(v));
    for (double& v : (*wet)[0]) v *= 0.5 / peak;
    const fs::path folder = dir / "enroll" / speaker;
    std::error_code ec;
    fs::create_directories(folder, ec);
    const fs::path out = folder / fmt::format("{:02d}.wav", count[speaker]++);
    SF_INFO info{};
    info.samplerate = o.audio_sample_rate;
    info.channels = 1;
    info.format = SF_FORMAT_WAV | SF_FORMAT_PCM_16;
    SNDFILE* f = sf_open(out.string().c_str(), SFM_WRITE, &info);
    if (!f) return make_error(ErrorCode::kIoError, "{}: cannot write", out.string());
    const auto frames = static_cast<sf_count_t>(n);
    const bool ok = sf_writef_double(f, (*wet)[0].data(), frames) == frames;
    sf_close(f);
    if (!ok) return make_error(ErrorCode::kIoError, "{}: write failed", out.string());
  }
  return ok_status();
}

struct Media {
  std::unique_ptr<FaceRenderer> face;
  bool moving_eyes = false;
  std::vector<std::shared_ptr<const cv::Mat>> object_textures;  // by DREAM label 0..3
  std::shared_ptr<const cv::Mat> poster;
  std::vector<SpeechClipInfo> clips;
  std::vector<std::vector<double>> clip_samples;
};

Result<std::shared_ptr<const cv::Mat>> load_texture(const fs::path& path, cv::Rect crop,
                                                    cv::Size size) {
  if (!fs::exists(path)) return tl::unexpected(media_error(path, "opencv-doc"));
  cv::Mat img = cv::imread(path.string(), cv::IMREAD_COLOR);
  if (img.empty()) return make_error(ErrorCode::kCorruptData, "{}: cannot decode", path.string());
  crop &= cv::Rect(0, 0, img.cols, img.rows);
  cv::Mat out;
  cv::resize(img(crop), out, size, 0, 0, cv::INTER_AREA);
  return std::make_shared<const cv::Mat>(out);
}

Result<Media> load_media(const DemoOptions& o) {
  Media m;
  if (!fs::exists(o.portrait)) return tl::unexpected(media_error(o.portrait, "python3-skimage"));
  if (o.face_model == DemoOptions::FaceModel::kMesh) {
    MeshFaceOptions fo;
    fo.portrait = o.portrait;
    fo.landmarks = o.portrait_landmarks;
    if (o.child != 0) {  // another child (demo_children.hpp)
      const DemoChild& c = demo_children().at(static_cast<size_t>(o.child));
      if (!fs::exists(c.portrait))
        return tl::unexpected(media_error(c.portrait, c.package.c_str()));
      fo.portrait = c.portrait;
      fo.landmarks = c.landmarks;
      fo.crop_px = c.crop_px;
      fo.mask_centre_px = c.mask_centre_px;
      fo.mask_axes_px = c.mask_axes_px;
      fo.face_width_px = c.face_width_px;
      fo.face_width_m = c.face_width_m;
    }
    auto face = MeshFaceRenderer::create(fo);
    if (!face) return tl::unexpected(face.error());
    m.face = std::move(*face);
    m.moving_eyes = true;
  } else {
    PlanarFaceOptions fo;
    fo.portrait = o.portrait;
    auto face = PlanarFaceRenderer::create(fo);
    if (!face) return tl::unexpected(face.error());
    m.face = std::move(*face);
  }

  // Toy textures by DREAM label: 0 car, 1 cup, 2 flower, 3 plane (the pictures are stand-ins).
  struct Tex {
    const char* file;
    cv::Rect crop;
  };
  const Tex tex[] = {{"HappyFish.jpg", {0, 0, 259, 194}},
                     {"fruits.jpg", {40, 60, 400, 300}},
                     {"butterfly.jpg", {40, 20, 400, 300}},
                     {"aero1.jpg", {0, 0, 640, 480}}};
  for (const auto& t : tex) {
    auto r = load_texture(o.opencv_samples_dir / t.file, t.crop, cv::Size(160, 120));
    if (!r) return tl::unexpected(r.error());
    m.object_textures.push_back(*r);
  }
  auto poster =
      load_texture(o.opencv_samples_dir / "starry_night.jpg", {0, 0, 752, 600}, cv::Size(376, 300));
  if (!poster) return tl::unexpected(poster.error());
  m.poster = *poster;

  std::map<std::string, std::map<std::string, std::string>> transcriptions;
  for (const auto& c : kClips) {
    SpeechClipInfo info;
    info.file = c.file;
    info.speaker = c.speaker;
    if (c.transcription) {
      if (!transcriptions.count(c.transcription)) {
        auto t = read_transcription(o.pocketsphinx_data_dir / c.transcription);
        if (!t) return tl::unexpected(t.error());
        transcriptions[c.transcription] = *t;
      }
      const auto& t = transcriptions[c.transcription];
      const auto it = t.find(c.id);
      if (it == t.end())
        return make_error(ErrorCode::kCorruptData, "{}: no transcription for '{}'",
                          (o.pocketsphinx_data_dir / c.transcription).string(), c.id);
      info.text = it->second;
    } else {
      info.text = c.id;
    }
    auto samples = load_clip(o.pocketsphinx_data_dir / c.file, o.audio_sample_rate);
    if (!samples) return tl::unexpected(samples.error());
    if (std::string(c.speaker) == "child")
      *samples = shift_voice(*samples, o.child_voice_shift, o.audio_sample_rate);
    info.duration_s = static_cast<double>(samples->size()) / o.audio_sample_rate;
    std::tie(info.speech_start_s, info.speech_end_s) = speech_extent(*samples, o.audio_sample_rate);
    m.clips.push_back(info);
    m.clip_samples.push_back(std::move(*samples));
  }
  return m;
}

// The robot's prompts (data/demo/robot/prompts.txt: "file in_grammar text..." lines).
Result<std::vector<RobotPrompt>> read_robot_prompts(const fs::path& dir) {
  const fs::path list = dir / "prompts.txt";
  std::ifstream in(list);
  if (!in)
    return make_error(ErrorCode::kNotFound,
                      "{}: missing demo robot prompts (tools/make_robot_prompts.sh makes them)",
                      list.string());
  std::vector<RobotPrompt> out;
  std::string line;
  int n = 0;
  while (std::getline(in, line)) {
    ++n;
    if (line.empty() || line[0] == '#') continue;
    std::istringstream ls(line);
    RobotPrompt p;
    int in_grammar = -1;
    ls >> p.file >> in_grammar;
    std::getline(ls, p.text);
    const auto b = p.text.find_first_not_of(' ');
    p.text = b == std::string::npos ? "" : p.text.substr(b);
    if (p.file.empty() || (in_grammar != 0 && in_grammar != 1) || p.text.empty())
      return make_error(ErrorCode::kCorruptData, "{}:{}: expected \"file in_grammar(0|1) text...\"",
                        list.string(), n);
    p.in_grammar = in_grammar == 1;
    out.push_back(std::move(p));
  }
  if (out.empty()) return make_error(ErrorCode::kCorruptData, "{}: no prompts", list.string());
  return out;
}

// ---------------------------------------------------------------- scene

const cv::Vec3f kShirt(150, 95, 45), kSkin(135, 165, 215), kTrousers(70, 60, 55),
    kTable(80, 130, 175), kWall(195, 205, 212), kFloor(105, 115, 125), kCeiling(230, 230, 230),
    kShoe(40, 40, 40), kTableLeg(60, 90, 120);

std::vector<Primitive> static_scene(const DemoGeometry& g, const Media& media) {
  std::vector<Primitive> p;
  const cv::Vec3d lo = g.room_min_m, hi = g.room_max_m;
  // Back wall (z = hi.z), side walls, floor, ceiling.
  p.push_back(Quad{{lo[0], lo[1], hi[2]}, {hi[0] - lo[0], 0, 0}, {0, hi[1] - lo[1], 0}, kWall, {}});
  p.push_back(
      Quad{{lo[0], lo[1], lo[2]}, {0, 0, hi[2] - lo[2]}, {0, hi[1] - lo[1], 0}, kWall * 0.95f, {}});
  p.push_back(
      Quad{{hi[0], lo[1], lo[2]}, {0, 0, hi[2] - lo[2]}, {0, hi[1] - lo[1], 0}, kWall * 0.95f, {}});
  p.push_back(
      Quad{{lo[0], hi[1], lo[2]}, {hi[0] - lo[0], 0, 0}, {0, 0, hi[2] - lo[2]}, kFloor, {}});
  p.push_back(
      Quad{{lo[0], lo[1], lo[2]}, {hi[0] - lo[0], 0, 0}, {0, 0, hi[2] - lo[2]}, kCeiling, {}});
  // Poster on the back wall, off to the side of the child's head (image right in front view).
  p.push_back(Quad{{0.55, -1.05, hi[2] - 0.005}, {0.9, 0, 0}, {0, 0.72, 0}, kWall, media.poster});
  // Table: top, apron on the robot side and the child side, four legs.
  const double ty = g.table_top_y_m;
  p.push_back(Quad{{g.table_x_min_m, ty, g.table_z_min_m},
                   {g.table_x_max_m - g.table_x_min_m, 0, 0},
                   {0, 0, g.table_z_max_m - g.table_z_min_m},
                   kTable,
                   {}});
  for (double z : {g.table_z_min_m, g.table_z_max_m})
    p.push_back(Quad{{g.table_x_min_m, ty, z},
                     {g.table_x_max_m - g.table_x_min_m, 0, 0},
                     {0, 0.05, 0},
                     kTable * 0.8f,
                     {}});
  for (double x : {g.table_x_min_m + 0.04, g.table_x_max_m - 0.04})
    for (double z : {g.table_z_min_m + 0.04, g.table_z_max_m - 0.04})
      p.push_back(Capsule{{x, ty + 0.05, z}, {x, hi[1], z}, 0.025, kTableLeg});
  return p;
}

std::vector<Primitive> dynamic_scene(const DemoScript& script, const Media& media, double t,
                                     const std::array<cv::Vec3d, kJointCount>& j,
                                     const HeadPose& hp) {
  auto J = [&](JointId id) { return j[static_cast<size_t>(id)]; };
  std::vector<Primitive> p;
  const cv::Matx33d R = hp.rotation();
  // Head: hair ellipsoid behind the face (shows when the face turns away).
  const FaceRenderer::BackOfHead back = media.face->back_of_head();
  p.push_back(Ellipsoid{hp.position_m + R * back.centre_head, R, back.radii_m, back.bgr});
  p.push_back(Capsule{J(JointId::kShoulderCenter) + cv::Vec3d(0, -0.02, 0),
                      hp.position_m + R * cv::Vec3d(0, 0.09, 0.07), 0.04, kSkin});
  p.push_back(Ellipsoid{
      0.5 * (J(JointId::kShoulderCenter) + J(JointId::kHipCenter)) + cv::Vec3d(0, 0.03, 0),
      cv::Matx33d::eye(),
      {0.13, 0.19, 0.08},
      kShirt});
  p.push_back(Capsule{J(JointId::kShoulderLeft), J(JointId::kShoulderRight), 0.05, kShirt});
  for (bool left : {true, false}) {
    const JointId s = left ? JointId::kShoulderLeft : JointId::kShoulderRight;
    const JointId e = left ? JointId::kElbowLeft : JointId::kElbowRight;
    const JointId w = left ? JointId::kWristLeft : JointId::kWristRight;
    const JointId h = left ? JointId::kHandLeft : JointId::kHandRight;
    const JointId hip = left ? JointId::kHipLeft : JointId::kHipRight;
    const JointId k = left ? JointId::kKneeLeft : JointId::kKneeRight;
    const JointId a = left ? JointId::kAnkleLeft : JointId::kAnkleRight;
    const JointId f = left ? JointId::kFootLeft : JointId::kFootRight;
    p.push_back(Capsule{J(s), J(e), 0.037, kShirt});
    p.push_back(Capsule{J(e), J(w), 0.03, kSkin});
    p.push_back(Capsule{J(w), J(h), 0.033, kSkin * 0.97f});
    p.push_back(Capsule{J(hip), J(k), 0.06, kTrousers});
    p.push_back(Capsule{J(k), J(a), 0.045, kTrousers});
    p.push_back(Capsule{J(a), J(f), 0.035, kShoe});
  }
  // Toys on the table: boxes with the picture on top.
  const auto states = script.object_states(t);
  for (size_t i = 0; i < states.size(); ++i) {
    const auto& s = states[i];
    const auto& tex = media.object_textures[static_cast<size_t>(script.objects()[i].label)];
    const cv::Scalar mean = cv::mean(*tex);
    const cv::Vec3f side(static_cast<float>(mean[0] * 0.6), static_cast<float>(mean[1] * 0.6),
                         static_cast<float>(mean[2] * 0.6));
    const auto& c = s.corners;
    // Top face: texture u along corner1 -> corner0 so it reads unmirrored from above.
    p.push_back(Quad{c[1], c[0] - c[1], c[2] - c[1], side, tex});
    for (int e = 0; e < 4; ++e)
      p.push_back(Quad{c[e], c[(e + 1) % 4] - c[e], c[e + 4] - c[e], side, {}});
  }
  return p;
}

// Noise tiles shared by every frame of one image size; per frame a seeded offset picks a window.
struct NoiseTile {
  cv::Mat pos, neg;
  static constexpr int kPad = 64;
  NoiseTile(cv::Size size, double sigma, uint64_t seed) {
    cv::Mat n(size.height + kPad, size.width + kPad, CV_32FC3);
    cv::RNG rng(seed);
    rng.fill(n, cv::RNG::NORMAL, 0, sigma);
    cv::Mat p = cv::max(n, 0), m = cv::max(-n, 0);
    p.convertTo(pos, CV_8UC3);
    m.convertTo(neg, CV_8UC3);
  }
  void apply(cv::Mat& img, uint64_t frame_seed) const {
    std::mt19937_64 rng(frame_seed);
    const int dx = static_cast<int>(rng() % kPad), dy = static_cast<int>(rng() % kPad);
    const cv::Rect r(dx, dy, img.cols, img.rows);
    cv::add(img, pos(r), img);
    cv::subtract(img, neg(r), img);
  }
};

struct StreamPlan {
  std::string id;
  SensorKind kind;
  double rate_hz;
  int64_t count;
  int camera = -1;  // index into cameras for image streams
};

struct Job {
  int64_t stamp;
  int stream;
  int64_t index;
};

// The scene geometry of the session's child (demo_children.hpp: eye height).
DemoGeometry child_geometry(const DemoOptions& o) {
  DemoGeometry g;
  if (o.face_model == DemoOptions::FaceModel::kMesh)
    g.head_rest_m[1] += demo_children().at(static_cast<size_t>(o.child)).eye_height_offset_m;
  return g;
}

class Generator {
 public:
  Generator(const DemoOptions& o, Media media)
      : o_(o),
        media_(std::move(media)),
        script_(o.seed, o.duration_s, child_geometry(o), o.script),
        cameras_(make_demo_cameras()) {
    const auto statics = static_scene(script_.geometry(), media_);
    for (const auto& cam : cameras_) {
      RenderTarget t = RenderTarget::empty(cam.image_size);
      render_primitives(cam, statics, light_, t);
      backgrounds_.push_back(std::move(t));
      // Large images: the moving body is ray-cast at half resolution (4x fewer rays) and
      // composited with a linearly upsampled coverage mask (smooth edges); see render().
      CameraModel half = cam;
      if (cam.image_size.width > 640) {
        half.image_size = cam.image_size / 2;
        half.K(0, 0) *= 0.5;
        half.K(1, 1) *= 0.5;
        half.K(0, 2) = (cam.K(0, 2) + 0.5) * 0.5 - 0.5;
        half.K(1, 2) = (cam.K(1, 2) + 0.5) * 0.5 - 0.5;
        RenderTarget h = RenderTarget::empty(half.image_size);
        render_primitives(half, statics, light_, h);
        half_backgrounds_.push_back(std::move(h));
      } else {
        half_backgrounds_.emplace_back();
      }
      half_cameras_.push_back(half);
    }
    noise_big_.emplace(cameras_[0].image_size, o.image_noise_sigma, sub_seed(o.seed, "noise_big"));
    noise_small_.emplace(cameras_[3].image_size, o.image_noise_sigma,
                         sub_seed(o.seed, "noise_small"));
  }

  const DemoScript& script() const { return script_; }
  const DemoOptions& options() const { return o_; }
  const std::vector<CameraModel>& cameras() const { return cameras_; }
  const Media& media() const { return media_; }

  // Colour (and optional depth) image of camera `c` at time t.
  void render(int c, int64_t stamp, const std::string& stream, int64_t index, cv::Mat* bgr,
              cv::Mat* depth_mm) const {
    const double t = static_cast<double>(stamp) * 1e-9;
    const CameraModel& cam = cameras_[static_cast<size_t>(c)];
    RenderTarget target = backgrounds_[static_cast<size_t>(c)].clone();
    const HeadPose hp = script_.head_pose(t);
    const auto joints = script_.joints(t);
    const auto dynamic = dynamic_scene(script_, media_, t, joints, hp);
    const RenderTarget& half_bg = half_backgrounds_[static_cast<size_t>(c)];
    if (half_bg.bgr.empty()) {
      render_primitives(cam, dynamic, light_, target);
    } else {
      RenderTarget small = half_bg.clone();
      render_primitives(half_cameras_[static_cast<size_t>(c)], dynamic, light_, small);
      cv::Mat hit = small.depth < half_bg.depth;  // 255 where a moving primitive is in front
      cv::Rect roi = cv::boundingRect(hit);
      if (!roi.empty()) {
        roi = cv::Rect(roi.x - 2, roi.y - 2, roi.width + 4, roi.height + 4) &
              cv::Rect(cv::Point(0, 0), small.bgr.size());
        const cv::Rect big(roi.x * 2, roi.y * 2, roi.width * 2, roi.height * 2);
        cv::Mat colour, alpha, depth;
        // cv::resize maps big pixel x to small (x + 0.5) / 2 - 0.5: the half camera's convention.
        cv::resize(small.bgr(roi), colour, big.size(), 0, 0, cv::INTER_LINEAR);
        cv::resize(hit(roi), alpha, big.size(), 0, 0, cv::INTER_LINEAR);
        cv::resize(small.depth(roi), depth, big.size(), 0, 0, cv::INTER_NEAREST);
        for (int v = 0; v < big.height; ++v) {
          const cv::Vec3b* cp = colour.ptr<cv::Vec3b>(v);
          const uchar* ap = alpha.ptr<uchar>(v);
          const float* dp = depth.ptr<float>(v);
          cv::Vec3b* out = target.bgr.ptr<cv::Vec3b>(v + big.y) + big.x;
          float* zb = target.depth.ptr<float>(v + big.y) + big.x;
          for (int u = 0; u < big.width; ++u) {
            if (ap[u] == 0) continue;
            const int a = ap[u];
            for (int k = 0; k < 3; ++k)
              out[u][k] = static_cast<uchar>((cp[u][k] * a + out[u][k] * (255 - a) + 127) / 255);
            if (a >= 128) zb[u] = std::min(zb[u], dp[u]);
          }
        }
      }
    }
    media_.face->render(cam, demo_face_state(script_, t), light_, target);
    if (bgr) {
      cv::GaussianBlur(target.bgr, *bgr, cv::Size(3, 3), 0.6);
      if (o_.image_noise_sigma > 0) {
        const NoiseTile& tile =
            bgr->cols == noise_big_->pos.cols - NoiseTile::kPad ? *noise_big_ : *noise_small_;
        tile.apply(*bgr, sub_seed(o_.seed, stream, static_cast<uint64_t>(index)));
      }
    }
    if (depth_mm) {
      // Kinect v1 range 0.4 .. 4.0 m; 0 = no measurement.
      depth_mm->create(target.depth.size(), CV_16UC1);
      for (int v = 0; v < target.depth.rows; ++v) {
        const float* z = target.depth.ptr<float>(v);
        uint16_t* d = depth_mm->ptr<uint16_t>(v);
        for (int u = 0; u < target.depth.cols; ++u)
          d[u] = (z[u] >= 0.4f && z[u] <= 4.0f) ? static_cast<uint16_t>(std::lround(z[u] * 1000.0))
                                                : 0;
      }
    }
  }

 private:
  const DemoOptions& o_;
  Media media_;
  DemoScript script_;
  std::vector<CameraModel> cameras_;
  Lighting light_;
  std::vector<RenderTarget> backgrounds_;
  std::vector<RenderTarget> half_backgrounds_;  // empty for images rendered at full resolution
  std::vector<CameraModel> half_cameras_;
  std::optional<NoiseTile> noise_big_, noise_small_;
};

// ---------------------------------------------------------------- truth

// ---- Hands in front of the eyes (issue 13: the DREAM gestures cover_eyes and drink) ----
// The truth must not claim a face is visible, or a gaze meets the robot, through the child's
// hands: a line of sight is blocked when it passes through a forearm or hand capsule (the same
// capsules, radii included, that dynamic_scene renders).

// Distance between the segments [p0, p1] and [q0, q1].
double segment_distance(const cv::Vec3d& p0, const cv::Vec3d& p1, const cv::Vec3d& q0,
                        const cv::Vec3d& q1) {
  const cv::Vec3d d1 = p1 - p0, d2 = q1 - q0, r = p0 - q0;
  const double a = d1.dot(d1), e = d2.dot(d2), f = d2.dot(r);
  double s = 0, u = 0;
  if (a <= 1e-12 && e <= 1e-12) return cv::norm(r);
  if (a <= 1e-12) {
    u = std::clamp(f / e, 0.0, 1.0);
  } else {
    const double c = d1.dot(r);
    if (e <= 1e-12) {
      s = std::clamp(-c / a, 0.0, 1.0);
    } else {
      const double b = d1.dot(d2), den = a * e - b * b;
      s = den > 1e-12 ? std::clamp((b * f - c * e) / den, 0.0, 1.0) : 0.0;
      u = (b * s + f) / e;
      if (u < 0) {
        u = 0, s = std::clamp(-c / a, 0.0, 1.0);
      } else if (u > 1) {
        u = 1, s = std::clamp((b - c) / a, 0.0, 1.0);
      }
    }
  }
  return cv::norm((p0 + d1 * s) - (q0 + d2 * u));
}

// True when the line of sight from `eye` to `target` passes through a forearm or a hand.
bool hands_block(const std::array<cv::Vec3d, kJointCount>& j, const cv::Vec3d& eye,
                 const cv::Vec3d& target) {
  auto J = [&](JointId id) { return j[static_cast<size_t>(id)]; };
  for (bool left : {true, false}) {
    const JointId e = left ? JointId::kElbowLeft : JointId::kElbowRight;
    const JointId w = left ? JointId::kWristLeft : JointId::kWristRight;
    const JointId h = left ? JointId::kHandLeft : JointId::kHandRight;
    if (segment_distance(eye, target, J(e), J(w)) < 0.03 ||
        segment_distance(eye, target, J(w), J(h)) < 0.033)
      return true;
  }
  return false;
}

json face_record(const Generator& gen, int64_t stamp) {
  const DemoScript& s = gen.script();
  const DemoGeometry& g = s.geometry();
  const double t = static_cast<double>(stamp) * 1e-9;
  const HeadPose hp = s.head_pose(t);
  const FaceState fs = demo_face_state(s, t);
  const auto& face = *gen.media().face;
  const EyesState eyes = face.eyes(fs);
  const cv::Vec3d left = eyes.left.pupil_m, right = eyes.right.pupil_m;
  const cv::Vec3d gaze = hp.gaze_dir();
  const cv::Vec3d eye_gaze = eyes.gaze_dir();
  const cv::Vec3d eye_mid = eyes.eye_midpoint();
  // Eye contact needs a line of sight: none while the hands cover both eyes from the robot.
  const auto joints = s.joints(t);
  const bool mutual =
      ray_point_distance(eye_mid, eye_gaze, g.robot_head_m) <= g.gaze_radius_m &&
      !(hands_block(joints, left, g.robot_head_m) && hands_block(joints, right, g.robot_head_m));
  json cams = json::object();
  std::string best;
  double best_yaw = 1e9;
  const auto region = face.face_region_head();
  for (size_t c = 0; c < kCameraIds.size(); ++c) {
    const CameraModel& cam = gen.cameras()[c];
    const double yaw_rel = cam.yaw_towards_deg(gaze);
    const cv::Vec3d to_cam = cam.centre_world() - hp.position_m;
    const double facing = gaze.dot(to_cam) / cv::norm(to_cam);
    const auto pl = cam.project(left), pr = cam.project(right);
    const cv::Rect2d img(0, 0, cam.image_size.width, cam.image_size.height);
    // Hidden: the hands cover both pupils from this camera (the face is not visible then).
    const bool hidden = hands_block(joints, left, cam.centre_world()) &&
                        hands_block(joints, right, cam.centre_world());
    bool visible = facing > std::cos(75 * CV_PI / 180) && pl && pr && img.contains(*pl) &&
                   img.contains(*pr) && !hidden;
    json rec;
    json box = nullptr;
    std::vector<cv::Point2d> pts;
    for (const auto& hpnt : region)
      if (auto p = cam.project(fs.to_world(hpnt))) pts.push_back(*p);
    if (!pts.empty() && pts.size() == region.size()) {
      double x0 = 1e18, y0 = 1e18, x1 = -1e18, y1 = -1e18;
      for (const auto& p : pts) {
        x0 = std::min(x0, p.x), y0 = std::min(y0, p.y), x1 = std::max(x1, p.x),
        y1 = std::max(y1, p.y);
      }
      box = json::array({q(x0, 1e3), q(y0, 1e3), q(x1 - x0, 1e3), q(y1 - y0, 1e3)});
    }
    rec["visible"] = visible;
    rec["eyes_hidden"] = hidden;
    rec["box"] = box;
    rec["yaw_deg"] = q(yaw_rel, 1e4);
    rec["eyes_px"] = json{{"left", pl ? px_json(*pl) : json(nullptr)},
                          {"right", pr ? px_json(*pr) : json(nullptr)}};
    cams[kCameraIds[c]] = rec;
    if (visible && std::abs(yaw_rel) < best_yaw) {
      best_yaw = std::abs(yaw_rel);
      best = kCameraIds[c];
    }
  }
  json r;
  r["type"] = "face";
  r["stamp_ns"] = stamp;
  r["head_position_m"] = vec_json(hp.position_m);
  r["yaw_deg"] = q(hp.yaw_deg, 1e4);
  r["pitch_deg"] = q(hp.pitch_deg, 1e4);
  r["roll_deg"] = q(hp.roll_deg, 1e4);
  r["head_gaze_dir"] = vec_json(gaze);
  r["eye_gaze_dir"] = vec_json(eye_gaze);
  r["eyes_m"] = json{{"left", vec_json(left)}, {"right", vec_json(right)}};
  r["eyeballs_m"] =
      json{{"left", vec_json(eyes.left.centre_m)}, {"right", vec_json(eyes.right.centre_m)}};
  r["eye_gaze_dirs"] =
      json{{"left", vec_json(eyes.left.gaze_dir)}, {"right", vec_json(eyes.right.gaze_dir)}};
  r["eyes_open"] = eyes.open;
  if (gen.media().moving_eyes) {
    const GazeState gs = s.gaze(t);
    r["gaze_target"] = std::string(gaze_target_label(gs.kind));
    if (gs.kind == GazeTargetKind::kObject) r["gaze_target_object"] = gs.object;
    r["gaze_target_m"] = vec_json(gs.target_m);
    r["eye_in_head_deg"] = json::array({q(gs.eye_yaw_deg, 1e4), q(gs.eye_pitch_deg, 1e4)});
  }
  r["mutual_gaze"] = mutual;
  r["robot_gaze_distance_m"] = q(ray_point_distance(eye_mid, eye_gaze, g.robot_head_m));
  r["best_camera"] = best.empty() ? json(nullptr) : json(best);
  r["cameras"] = cams;
  // faces (issue 12): who the face is (the mesh face is the session's subject; the planar face is
  // an uncalibrated stranger) and its expression: the NASA portrait smiles, and the renderer
  // does not animate the mouth, so it is "happy" throughout.
  const DemoChild& child = demo_children().at(static_cast<size_t>(gen.options().child));
  r["person"] = !gen.media().moving_eyes   ? json(nullptr)
                : child.in_shipped_gallery ? json(kDemoSubject)
                                           : json("unknown");
  // The same as the gallery's numeric id (person 0 of data/subjects/demo_child/face_gallery.yaml;
  // -1 = not enrolled), for analyses that carry ids only (no --include-names).
  r["person_id"] = !gen.media().moving_eyes   ? json(nullptr)
                   : child.in_shipped_gallery ? json(0)
                                              : json(-1);
  r["expression"] = child.expression;
  return r;
}

json skeleton_json(const std::array<cv::Vec3d, kJointCount>& j) {
  json joints = json::object();
  for (int i = 0; i < kJointCount; ++i)
    joints[std::string(joint_name(static_cast<JointId>(i)))] = vec_json(j[static_cast<size_t>(i)]);
  return joints;
}

Status write_mic_calibration(const fs::path& path, const DemoGeometry& g, int sample_rate) {
  try {
    cv::FileStorage f(path.string(), cv::FileStorage::WRITE);
    if (!f.isOpened()) return make_error(ErrorCode::kIoError, "{}: cannot write", path.string());
    const auto mics = demo_mic_positions(g);
    cv::Mat m(static_cast<int>(mics.size()), 3, CV_64F);
    for (int i = 0; i < m.rows; ++i)
      for (int k = 0; k < 3; ++k) m.at<double>(i, k) = mics[static_cast<size_t>(i)][k];
    f << "frame"
      << "mic_array";
    f << "sample_rate" << sample_rate;
    f.writeComment("Microphone positions in the array frame (metres), one row per channel");
    f << "mic_positions_m" << m;
    f.writeComment("Extrinsics: array_from_world, X_array = R * X_world + t (metres)");
    f << "array_from_world_R" << cv::Mat(cv::Matx33d::eye());
    f << "array_from_world_t" << cv::Mat(cv::Vec3d(-g.mic_array_m));
    f.writeComment("azimuth 0 = broadside (+z), positive towards +x; elevation positive up (-y)");
    return ok_status();
  } catch (const cv::Exception& e) {
    return make_error(ErrorCode::kIoError, "{}: {}", path.string(), e.msg);
  }
}

}  // namespace

// ================================================================= public

std::filesystem::path default_robot_prompts_dir() {
  return std::filesystem::path(DREAMSENSE_DEMO_DATA_DIR) / "robot";
}

std::vector<PlannedRobotUtterance> plan_robot_utterances(
    uint64_t seed, double duration_s, const std::vector<std::pair<double, double>>& busy_s,
    const std::vector<double>& prompt_durations_s, double margin_s) {
  std::vector<PlannedRobotUtterance> out;
  if (prompt_durations_s.empty()) return out;
  std::mt19937_64 rng(sub_seed(seed, "robot_voice"));
  std::vector<size_t> order(prompt_durations_s.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  for (size_t i = order.size(); i > 1; --i)
    std::swap(order[i - 1], order[static_cast<size_t>(rng() % i)]);
  std::vector<std::pair<double, double>> busy = busy_s;
  std::sort(busy.begin(), busy.end());
  std::vector<std::pair<double, double>> gaps;
  double t = 0;
  for (const auto& [a, b] : busy) {
    gaps.emplace_back(t, a);
    t = std::max(t, b);
  }
  gaps.emplace_back(t, duration_s - 0.5);
  size_t next = 0;
  for (const auto& [a, b] : gaps) {
    const double draw = uniform(rng, 0, 1);
    const size_t p = order[next % order.size()];
    const double need = prompt_durations_s[p] + 2 * margin_s;
    if (b - a < need || draw > 0.7) continue;
    PlannedRobotUtterance u;
    u.prompt = p;
    u.clip_start_s = 0.5 * (a + b) - 0.5 * prompt_durations_s[p];
    out.push_back(u);
    ++next;
  }
  return out;
}

Status DemoOptions::check() const {
  std::string bad;
  if (out_dir.empty()) bad += " out_dir is required;";
  if (!(duration_s > 0 && duration_s <= 600)) bad += " duration_s must be in (0, 600];";
  if (!(camera_rate_hz > 0 && camera_rate_hz <= 120)) bad += " camera_rate_hz must be in (0, 120];";
  if (!(kinect_rate_hz > 0 && kinect_rate_hz <= 120)) bad += " kinect_rate_hz must be in (0, 120];";
  if (audio_sample_rate != 16000) bad += " audio_sample_rate must be 16000 (the clips' rate);";
  if (!(audio_chunk_s > 0 && audio_chunk_s <= 1)) bad += " audio_chunk_s must be in (0, 1];";
  if (!(rt60_s >= 0 && rt60_s <= 2)) bad += " rt60_s must be in [0, 2];";
  if (!(snr_db > -20 && snr_db < 100)) bad += " snr_db must be in (-20, 100);";
  if (!(child_voice_shift >= 0.5 && child_voice_shift <= 2))
    bad += " child_voice_shift must be in [0.5, 2];";
  if (!(joint_noise_m >= 0 && joint_noise_m < 0.1)) bad += " joint_noise_m must be in [0, 0.1);";
  if (!(image_noise_sigma >= 0 && image_noise_sigma <= 40))
    bad += " image_noise_sigma must be in [0, 40];";
  if (child < 0 || child >= static_cast<int>(demo_children().size()))
    bad += fmt::format(" child must be in [0, {}];", demo_children().size() - 1);
  if (jpeg_quality < 1 || jpeg_quality > 100) bad += " jpeg_quality must be in [1, 100];";
  if (threads < 1 || threads > 64) bad += " threads must be in [1, 64];";
  if (robot_voice && robot_prompts_dir.empty()) bad += " robot_prompts_dir is empty;";
  if (auto s = script.check(); !s) bad += " script: " + s.error().message + ";";
  if (!bad.empty()) return make_error(ErrorCode::kInvalidArgument, "DemoOptions:{}", bad);
  return ok_status();
}

std::vector<CameraModel> make_demo_cameras(const DemoGeometry& g) {
  std::vector<CameraModel> out;
  auto colour = [&](const std::string& id, double azimuth_deg, double fx, double cx, double cy) {
    CameraModel m;
    m.frame = id;
    m.image_size = cv::Size(1280, 960);
    m.K = cv::Matx33d(fx, 0, cx, 0, fx, cy, 0, 0, 1);
    const double a = azimuth_deg * CV_PI / 180, d = 0.80;
    // Seen from the child (who faces -z): negative azimuth = world -x side.
    const cv::Vec3d eye = g.head_rest_m + cv::Vec3d(d * std::sin(a), -0.12, -d * std::cos(a));
    look_at(eye, g.head_rest_m, cv::Vec3d(0, 1, 0), m.R, m.t);
    out.push_back(m);
  };
  colour("camera_left", -35, 1050, 641.5, 478.0);
  colour("camera_middle", 0, 1075, 638.0, 482.5);
  colour("camera_right", 35, 1040, 636.5, 480.5);
  CameraModel front;
  front.frame = "front.color";
  front.image_size = cv::Size(640, 480);
  front.K = cv::Matx33d(525, 0, 319.5, 0, 525, 239.5, 0, 0, 1);  // Kinect v1-like; world frame
  out.push_back(front);
  front.frame = "front.depth";
  out.push_back(front);
  CameraModel top;
  top.frame = "top.color";
  top.image_size = cv::Size(640, 480);
  top.K = cv::Matx33d(525, 0, 319.5, 0, 525, 239.5, 0, 0, 1);
  const double zc = 0.5 * (g.table_z_min_m + g.table_z_max_m) - 0.03;
  // 1 m above the table, looking straight down; image down = world +z (the child at the bottom).
  look_at(cv::Vec3d(0, g.table_top_y_m - 1.0, zc), cv::Vec3d(0, g.table_top_y_m, zc),
          cv::Vec3d(0, 0, 1), top.R, top.t);
  out.push_back(top);
  return out;
}

SkeletonBody demo_skeleton_body(const DemoScript& script, uint64_t seed, const std::string& stream,
                                uint64_t sequence, int64_t stamp, double joint_noise_m) {
  std::mt19937_64 rng(sub_seed(seed, stream, sequence));
  const auto j = script.joints(static_cast<double>(stamp) * 1e-9);
  SkeletonBody body;
  body.body_id = 0;
  for (int i = 0; i < kJointCount; ++i) {
    auto& o = body.joints[static_cast<size_t>(i)];
    for (int k = 0; k < 3; ++k)
      o.position_m[k] = j[static_cast<size_t>(i)][k] + joint_noise_m * gaussian(rng);
    const auto id = static_cast<JointId>(i);
    // Legs are under the table: reported as "inferred", like a Kinect would.
    o.confidence = (id >= JointId::kKneeLeft && id <= JointId::kFootLeft) ||
                           (id >= JointId::kKneeRight && id <= JointId::kFootRight)
                       ? 0.5f
                       : 1.0f;
  }
  return body;
}

int64_t demo_stamp_ns(int64_t index, double rate_hz) { return stamp_ns(index, rate_hz); }

FaceState demo_face_state(const DemoScript& script, double t) {
  const HeadPose hp = script.head_pose(t);
  const GazeState gs = script.gaze(t);
  FaceState s;
  s.position_m = hp.position_m;
  s.world_from_head = hp.rotation();
  s.gaze_target_m = gs.target_m;
  s.eye_gaze_dir = cv::normalize(gs.target_m - hp.position_m);
  s.eyelid_closure = gs.eyelid_closure;
  return s;
}

std::vector<cv::Vec3d> demo_mic_positions(const DemoGeometry& g) {
  std::vector<cv::Vec3d> out;
  for (double x : g.mic_x_m) out.emplace_back(x, 0, 0);
  return out;
}

void array_direction(const DemoGeometry& g, const cv::Vec3d& world, double& azimuth_deg,
                     double& elevation_deg) {
  const cv::Vec3d p = world - g.mic_array_m;  // array axes = world axes
  azimuth_deg = std::atan2(p[0], p[2]) * 180 / CV_PI;
  elevation_deg = std::atan2(-p[1], std::hypot(p[0], p[2])) * 180 / CV_PI;
}

std::vector<PlannedUtterance> plan_utterances(const DemoScript& script,
                                              const std::vector<SpeechClipInfo>& clips) {
  std::mt19937_64 rng(sub_seed(script.seed(), "speech"));
  std::vector<size_t> pools[2];  // 0 child, 1 therapist
  for (size_t i = 0; i < clips.size(); ++i) pools[clips[i].speaker == "child" ? 0 : 1].push_back(i);
  for (auto& pool : pools)
    for (size_t i = pool.size(); i > 1; --i)
      std::swap(pool[i - 1], pool[static_cast<size_t>(rng() % i)]);
  const int target = 3 + static_cast<int>(rng() % 3);
  int speaker = static_cast<int>(rng() % 2);
  rng();  // (was the therapist's side; kept so the later draws do not shift)
  const double side = script.therapist_side();  // the side the child looks at the therapist
  const double min_gap = 0.3, tail = 0.5;
  std::vector<size_t> chosen;
  size_t next[2] = {0, 0};
  double total = 0;
  for (int i = 0; i < target; ++i, speaker = 1 - speaker) {
    const auto& pool = pools[speaker];
    if (pool.empty()) continue;
    const size_t c = pool[next[speaker]++ % pool.size()];
    const double need =
        total + clips[c].duration_s + min_gap * static_cast<double>(chosen.size() + 1);
    if (need > script.duration_s() - tail) continue;
    chosen.push_back(c);
    total += clips[c].duration_s;
  }
  std::vector<PlannedUtterance> out;
  if (chosen.empty()) return out;
  const double free_s =
      script.duration_s() - tail - total - min_gap * static_cast<double>(chosen.size());
  std::vector<double> w(chosen.size() + 1);
  double wsum = 0;
  for (double& x : w) wsum += (x = uniform(rng, 0.3, 1.5));
  double t = 0;
  const DemoGeometry& g = script.geometry();
  for (size_t i = 0; i < chosen.size(); ++i) {
    t += min_gap + free_s * w[i] / wsum;
    PlannedUtterance u;
    u.clip = chosen[i];
    u.clip_start_s = t;
    const SpeechClipInfo& clip = clips[chosen[i]];
    if (clip.speaker == "child") {
      const HeadPose hp = script.head_pose(t + 0.5 * (clip.speech_start_s + clip.speech_end_s));
      u.source_m = hp.position_m + hp.rotation() * cv::Vec3d(0, 0.065, -0.01);  // mouth
    } else {
      const double az = side * uniform(rng, 30, 60) * CV_PI / 180;
      const double dist = uniform(rng, 1.2, 2.0);
      const double y = uniform(rng, -0.35, -0.15);
      u.source_m =
          g.mic_array_m + cv::Vec3d(dist * std::sin(az), y - g.mic_array_m[1], dist * std::cos(az));
    }
    out.push_back(u);
    t += clip.duration_s;
  }
  return out;
}

// JSGF of the demo's speech commands: cards.gram and goforward.gram of pocketsphinx-testdata.
constexpr const char* kDemoGrammar = R"(#JSGF V1.0;
grammar demo;
public <command> = <cards> | <move>;
<cards> = <card> <card> <card> | <card> <card> | <card> | <rank> <card> | <rank> <rank>;
<card> = <rank> [ of ] <suits>;
<suits> = clubs | hearts | diamonds | spades;
<rank> = ace | two | three | four | five | six | seven | eight | nine | ten | jack | queen | king | lady;
<move> = go <direction> <distance> [ meter | meters ];
<direction> = forward | backward;
<distance> = one | two | three | four | five | six | seven | eight | nine | ten;
)";

Result<DemoSummary> generate_demo_session(const DemoOptions& options,
                                          const std::function<void(double)>& progress) {
  const auto t0 = std::chrono::steady_clock::now();
  if (auto st = options.check(); !st) return tl::unexpected(st.error());
  const fs::path& dir = options.out_dir;
  std::error_code ec;
  if (fs::exists(dir) && !fs::is_empty(dir, ec)) {
    if (!options.overwrite)
      return make_error(ErrorCode::kInvalidArgument,
                        "{}: output folder exists and is not empty (use overwrite)", dir.string());
    if (!fs::exists(dir / sources::kManifestName))
      return make_error(ErrorCode::kInvalidArgument,
                        "{}: refusing to overwrite a folder that is not a session", dir.string());
    fs::remove_all(dir, ec);
    if (ec)
      return make_error(ErrorCode::kIoError, "{}: cannot remove ({})", dir.string(), ec.message());
  }

  auto media = load_media(options);
  if (!media) return tl::unexpected(media.error());
  const Generator gen(options, std::move(*media));
  const DemoScript& script = gen.script();
  const DemoGeometry& g = script.geometry();
  const double dur = options.duration_s;

  // ---- streams
  std::vector<StreamPlan> plans = {
      {"camera_left", SensorKind::kColor, options.camera_rate_hz, 0, 0},
      {"camera_middle", SensorKind::kColor, options.camera_rate_hz, 0, 1},
      {"camera_right", SensorKind::kColor, options.camera_rate_hz, 0, 2},
      {"front.color", SensorKind::kColor, options.kinect_rate_hz, 0, 3},
      {"front.depth", SensorKind::kDepth, options.kinect_rate_hz, 0, 4},
      {"front.skeleton", SensorKind::kSkeleton, options.kinect_rate_hz, 0, -1},
      {"top.color", SensorKind::kColor, options.kinect_rate_hz, 0, 5},
      {"mic_array", SensorKind::kAudio, 1.0 / options.audio_chunk_s, 0, -1}};
  // The robot's voice as played (the reference for echo removal), after every other stream.
  if (options.robot_voice)
    plans.push_back({"robot_audio", SensorKind::kAudio, 1.0 / options.audio_chunk_s, 0, -1});
  for (auto& p : plans) p.count = frame_count(dur, p.rate_hz);
  // Streams written (audio_only: the audio streams; the truth always covers the whole scene).
  std::vector<int> written_streams;
  for (int i = 0; i < static_cast<int>(plans.size()); ++i)
    if (!options.audio_only || plans[static_cast<size_t>(i)].kind == SensorKind::kAudio)
      written_streams.push_back(i);

  sources::SessionManifest manifest;
  manifest.name = fmt::format("demo-seed-{}", options.seed);
  manifest.clock_origin_unix_ns = kClockOriginUnixNs;
  manifest.participant.id = 0;
  manifest.condition = "RET";
  manifest.task = "TT";
  manifest.frame_rate = options.camera_rate_hz;
  manifest.truth = "truth.jsonl";
  manifest.metadata = {
      {"generator", kGenerator},
      {"seed", std::to_string(options.seed)},
      {"speech_grammar", "speech.gram"},
      {"voice_enroll", "enroll"},  // speaker enrolment audio (identifyVoice)
      // Where the robot's head is (world, m): a setup calibration, for mutual gaze.
      {"robot_head_m",
       fmt::format("{} {} {}", g.robot_head_m[0], g.robot_head_m[1], g.robot_head_m[2])}};
  // Who the child is (a pseudonymous id, as a therapy session log would have it): analysis looks
  // up the child's calibration (face model, gaze constants) under this name. Every seed shows the
  // same rendered child; the planar face is another subject without a calibration.
  if (options.face_model == DemoOptions::FaceModel::kMesh) {
    const DemoChild& child = demo_children().at(static_cast<size_t>(options.child));
    manifest.metadata["subject"] = options.child == 0 ? std::string(kDemoSubject) : child.subject;
  }
  const int channels = static_cast<int>(g.mic_x_m.size());
  for (const int index : written_streams) {
    const StreamPlan& p = plans[static_cast<size_t>(index)];
    sources::StreamEntry e;
    e.id = p.id;
    e.kind = p.kind;
    e.rate_hz = p.rate_hz;
    if (p.kind == SensorKind::kColor || p.kind == SensorKind::kDepth) {
      const CameraModel& cam = gen.cameras()[static_cast<size_t>(p.camera)];
      e.width = cam.image_size.width;
      e.height = cam.image_size.height;
      e.encoding = p.kind == SensorKind::kColor ? "mjpeg" : "png16";
      e.file = p.id + (p.kind == SensorKind::kColor ? ".mjpg" : ".depth");
      e.index = p.id + ".idx";
      e.calibration = "calib/" + p.id + ".yaml";
    } else if (p.kind == SensorKind::kSkeleton) {
      e.encoding = "jsonl";
      e.file = p.id + ".jsonl";
      e.calibration = "calib/front.depth.yaml";  // joints are in the front sensor's frame
      e.frame = "front.depth";
    } else if (p.id == "robot_audio") {  // mono, what the robot's loudspeaker plays
      e.encoding = "wav";
      e.file = p.id + ".wav";
      e.sample_rate = options.audio_sample_rate;
      e.channels = 1;
      e.start_ns = 0;
      e.roles = {"robot_audio"};
    } else {
      e.encoding = "wav";
      e.file = p.id + ".wav";
      e.sample_rate = options.audio_sample_rate;
      e.channels = channels;
      e.start_ns = 0;
      e.calibration = "calib/mic_array.yaml";
      if (options.robot_voice) e.roles = {"mic_array"};
    }
    manifest.streams.push_back(e);
  }

  sources::SessionWriterOptions wopt;
  wopt.jpeg_quality = options.jpeg_quality;
  auto writer = sources::SessionWriter::create(dir, manifest, wopt);
  if (!writer) return tl::unexpected(writer.error());

  // ---- calibration
  fs::create_directories(dir / "calib", ec);
  for (const auto& cam : gen.cameras())
    if (auto st = write_camera_model(dir / "calib" / (cam.frame + ".yaml"), cam); !st)
      return tl::unexpected(st.error());
  if (auto st =
          write_mic_calibration(dir / "calib" / "mic_array.yaml", g, options.audio_sample_rate);
      !st)
    return tl::unexpected(st.error());
  // The command grammar of the session (what the robot listens for): the union of the two
  // pocketsphinx-testdata grammars whose clips the child says. The LibriVox sentences the
  // therapist reads are outside it and must be rejected.
  {
    std::ofstream g_out(dir / "speech.gram", std::ios::binary | std::ios::trunc);
    g_out << kDemoGrammar;
    if (!g_out)
      return make_error(ErrorCode::kIoError, "{}: cannot write", (dir / "speech.gram").string());
  }

  // ---- audio: image-source room + pink noise
  const auto& clips = gen.media().clips;
  const auto utterances = plan_utterances(script, clips);
  const double fs_hz = options.audio_sample_rate;
  const size_t n_samples = static_cast<size_t>(frame_count(dur, fs_hz));
  Channels mix(static_cast<size_t>(channels), std::vector<double>(n_samples, 0.0));
  RoomOptions room;
  room.size_m = g.room_size_m();
  room.rt60_s = options.rt60_s;
  room.sample_rate_hz = fs_hz;
  std::vector<cv::Vec3d> mics_room;
  for (const auto& m : demo_mic_positions(g))
    mics_room.push_back(g.room_from_world(m + g.mic_array_m));
  if (auto st = write_enrolment(dir, options, g, room, mics_room); !st)
    return tl::unexpected(st.error());
  std::vector<std::pair<size_t, size_t>> active;
  std::vector<json> speech_truth;
  for (const auto& u : utterances) {
    const auto& clip = clips[u.clip];
    auto wet = simulate(gen.media().clip_samples[u.clip], room,
                        AcousticPlacement{g.room_from_world(u.source_m), mics_room});
    if (!wet) return tl::unexpected(wet.error());
    const size_t off = static_cast<size_t>(std::llround(u.clip_start_s * fs_hz));
    for (size_t c = 0; c < mix.size(); ++c)
      for (size_t i = 0; i < (*wet)[c].size() && off + i < n_samples; ++i)
        mix[c][off + i] += (*wet)[c][i];
    const double delay = cv::norm(u.source_m - g.mic_array_m) / room.speed_of_sound_m_s;
    const double s0 = u.clip_start_s + clip.speech_start_s + delay;
    const double s1 = u.clip_start_s + clip.speech_end_s + delay;
    active.emplace_back(static_cast<size_t>(s0 * fs_hz),
                        std::min(n_samples, static_cast<size_t>(s1 * fs_hz)));
    double az = 0, el = 0;
    array_direction(g, u.source_m, az, el);
    json r;
    r["type"] = "speech";
    r["start_ns"] = static_cast<int64_t>(std::llround(s0 * 1e9));
    r["end_ns"] = static_cast<int64_t>(std::llround(s1 * 1e9));
    r["text"] = clip.text;
    r["source_file"] = clip.file;
    // Said from the session's command grammar (speech.gram): the cards and goforward clips.
    r["in_grammar"] = clip.file.rfind("librivox/", 0) != 0;
    r["speaker"] = clip.speaker;
    r["azimuth_deg"] = q(az, 1e4);
    r["elevation_deg"] = q(el, 1e4);
    r["source_position_m"] = vec_json(u.source_m);
    r["distance_m"] = q(cv::norm(u.source_m - g.mic_array_m));
    speech_truth.push_back(r);
  }
  double speech_power = 0;
  size_t speech_samples = 0;
  for (const auto& [a, b] : active) {
    speech_power += mean_power(mix, a, b) * static_cast<double>(b - a);
    speech_samples += b - a;
  }
  speech_power = speech_samples ? speech_power / static_cast<double>(speech_samples) : 1e-4;

  // ---- the robot's voice: prompts from the robot's loudspeaker in the gaps (after the speech
  // power is measured, so the noise level and the human audio are those of the demo without it)
  std::vector<double> robot_played(options.robot_voice ? n_samples : 0, 0.0);
  std::vector<json> robot_truth;
  if (options.robot_voice) {
    auto prompts = read_robot_prompts(options.robot_prompts_dir);
    if (!prompts) return tl::unexpected(prompts.error());
    // The loudspeaker plays at a talker's level: each prompt scaled to the child clips' mean
    // RMS (the array, 18 cm from the robot's head, then hears it ~15 dB above the child).
    double child_power = 0;
    int child_clips = 0;
    for (size_t i = 0; i < clips.size(); ++i)
      if (clips[i].speaker == "child") {
        const auto& x = gen.media().clip_samples[i];
        const size_t a = static_cast<size_t>(clips[i].speech_start_s * fs_hz);
        const size_t b = std::min(x.size(), static_cast<size_t>(clips[i].speech_end_s * fs_hz));
        double p = 0;
        for (size_t k = a; k < b; ++k) p += x[k] * x[k];
        child_power += b > a ? p / static_cast<double>(b - a) : 0;
        ++child_clips;
      }
    child_power = child_clips ? child_power / child_clips : 1e-3;
    std::vector<std::vector<double>> prompt_samples;
    std::vector<double> prompt_durations;
    std::vector<std::pair<double, double>> prompt_extent;
    for (const auto& pr : *prompts) {
      const fs::path file = options.robot_prompts_dir / pr.file;
      if (!fs::exists(file))
        return make_error(ErrorCode::kNotFound,
                          "{}: missing demo robot prompt (tools/make_robot_prompts.sh makes it)",
                          file.string());
      audio::ReadAudioOptions ro;
      ro.require_mono = true;
      ro.resample_to_hz = options.audio_sample_rate;
      DS_ASSIGN_OR_RETURN(audio::AudioClip clip, audio::read_audio(file, ro));
      std::vector<double> x(clip.samples.begin(), clip.samples.end());
      const auto [a, b] = speech_extent(x, fs_hz);
      double p = 0;
      const size_t ia = static_cast<size_t>(a * fs_hz),
                   ib = std::min(x.size(), static_cast<size_t>(b * fs_hz));
      for (size_t k = ia; k < ib; ++k) p += x[k] * x[k];
      p = ib > ia ? p / static_cast<double>(ib - ia) : 1e-6;
      const double scale = std::sqrt(child_power / std::max(p, 1e-12));
      for (double& v : x) v *= scale;
      prompt_durations.push_back(static_cast<double>(x.size()) / fs_hz);
      prompt_extent.emplace_back(a, b);
      prompt_samples.push_back(std::move(x));
    }
    std::vector<std::pair<double, double>> busy;
    for (const auto& u : utterances)
      busy.emplace_back(u.clip_start_s, u.clip_start_s + clips[u.clip].duration_s);
    const auto robot_plan = plan_robot_utterances(options.seed, dur, busy, prompt_durations);
    const cv::Vec3d speaker_m = g.robot_head_m;
    const double delay = cv::norm(speaker_m - g.mic_array_m) / room.speed_of_sound_m_s;
    double az = 0, el = 0;
    array_direction(g, speaker_m, az, el);
    for (const auto& ru : robot_plan) {
      const auto& x = prompt_samples[ru.prompt];
      auto wet = simulate(x, room, AcousticPlacement{g.room_from_world(speaker_m), mics_room});
      if (!wet) return tl::unexpected(wet.error());
      const size_t off = static_cast<size_t>(std::llround(ru.clip_start_s * fs_hz));
      for (size_t c = 0; c < mix.size(); ++c)
        for (size_t i = 0; i < (*wet)[c].size() && off + i < n_samples; ++i)
          mix[c][off + i] += (*wet)[c][i];
      for (size_t i = 0; i < x.size() && off + i < n_samples; ++i) robot_played[off + i] += x[i];
      const RobotPrompt& pr = (*prompts)[ru.prompt];
      json r;
      r["type"] = "robot_speech";
      r["start_ns"] = static_cast<int64_t>(
          std::llround((ru.clip_start_s + prompt_extent[ru.prompt].first + delay) * 1e9));
      r["end_ns"] = static_cast<int64_t>(
          std::llround((ru.clip_start_s + prompt_extent[ru.prompt].second + delay) * 1e9));
      r["played_start_ns"] = static_cast<int64_t>(std::llround(ru.clip_start_s * 1e9));
      r["text"] = pr.text;
      r["source_file"] = "robot/" + pr.file;
      r["in_grammar"] = pr.in_grammar;
      r["azimuth_deg"] = q(az, 1e4);
      r["elevation_deg"] = q(el, 1e4);
      r["source_position_m"] = vec_json(speaker_m);
      r["distance_m"] = q(cv::norm(speaker_m - g.mic_array_m));
      robot_truth.push_back(r);
    }
  }
  add_noise(mix, options.snr_db, NoiseColor::kPink, sub_seed(options.seed, "audio_noise"),
            speech_power);
  double peak = 1e-12;
  for (const auto& ch : mix)
    for (double v : ch) peak = std::max(peak, std::abs(v));
  const double gain = 0.5 / peak;
  double robot_peak = 1e-12;
  for (double v : robot_played) robot_peak = std::max(robot_peak, std::abs(v));
  const double robot_gain = 0.5 / std::max(robot_peak, 1e-3);

  // ---- truth
  std::vector<std::pair<std::pair<int64_t, int>, json>> truth;  // ((stamp, order), record)
  {
    for (int64_t k = 0; k < plans[0].count; ++k) {
      const int64_t s = stamp_ns(k, options.camera_rate_hz);
      truth.push_back({{s, 1}, face_record(gen, s)});
    }
    for (int64_t k = 0; k < plans[5].count; ++k) {
      const int64_t s = stamp_ns(k, options.kinect_rate_hz);
      json r;
      r["type"] = "skeleton";
      r["stamp_ns"] = s;
      r["joints"] = skeleton_json(script.joints(static_cast<double>(s) * 1e-9));
      // The gesture the child performs in this skeleton frame (F20 label and id, per frame).
      const ActionSegment& seg = script.segment_at(static_cast<double>(s) * 1e-9);
      r["action"] = script.segment_label(seg);
      r["action_id"] = script.segment_dream_id(seg);
      truth.push_back({{s, 2}, r});
    }
    const CameraModel& top = gen.cameras()[5];
    for (int64_t k = 0; k < plans[6].count; ++k) {
      const int64_t s = stamp_ns(k, options.kinect_rate_hz);
      const auto states = script.object_states(static_cast<double>(s) * 1e-9);
      for (size_t i = 0; i < states.size(); ++i) {
        const auto& st = states[i];
        const auto& spec = script.objects()[i];
        double x0 = 1e18, y0 = 1e18, x1 = -1e18, y1 = -1e18;
        for (const auto& c : st.corners)
          if (auto p = top.project(c)) {
            x0 = std::min(x0, p->x), y0 = std::min(y0, p->y);
            x1 = std::max(x1, p->x), y1 = std::max(y1, p->y);
          }
        json r;
        r["type"] = "object";
        r["stamp_ns"] = s;
        r["id"] = spec.id;
        r["label"] = spec.label;
        r["label_name"] = spec.label_name;
        r["position_m"] = vec_json(st.position_m);
        r["yaw_deg"] = q(st.yaw_deg, 1e4);
        r["size_m"] = vec_json(cv::Vec3d(spec.width_m, spec.height_m, spec.depth_m));
        r["top_box"] = json::array({q(x0, 1e3), q(y0, 1e3), q(x1 - x0, 1e3), q(y1 - y0, 1e3)});
        truth.push_back({{s, 3}, r});
      }
    }
    for (const auto& a : script.actions()) {
      json r;
      r["type"] = "action";
      r["start_ns"] = static_cast<int64_t>(std::llround(a.start_s * 1e9));
      r["end_ns"] = static_cast<int64_t>(std::llround(a.end_s * 1e9));
      r["label"] = script.segment_label(a);
      r["id"] = script.segment_dream_id(a);
      truth.push_back({{r["start_ns"].get<int64_t>(), 0}, r});
    }
    for (auto& r : speech_truth) truth.push_back({{r["start_ns"].get<int64_t>(), 0}, r});
    for (auto& r : robot_truth) truth.push_back({{r["start_ns"].get<int64_t>(), 0}, r});
    std::stable_sort(truth.begin(), truth.end(),
                     [](const auto& a, const auto& b) { return a.first < b.first; });
    json meta;
    meta["type"] = "meta";
    meta["truth_version"] = 1;
    meta["generator"] = kGenerator;
    meta["seed"] = options.seed;
    if (options.face_model == DemoOptions::FaceModel::kMesh) {  // which child (demo_children.hpp)
      const DemoChild& child = demo_children().at(static_cast<size_t>(options.child));
      meta["child"] = {{"index", options.child},
                       {"name", child.name},
                       {"face_width_m", child.face_width_m},
                       {"eye_height_offset_m", child.eye_height_offset_m}};
    }
    meta["duration_ns"] = static_cast<int64_t>(std::llround(dur * 1e9));
    meta["frame_rate"] = options.camera_rate_hz;
    meta["robot_head_m"] = vec_json(g.robot_head_m);
    meta["gaze_radius_m"] = g.gaze_radius_m;
    std::ofstream out(dir / "truth.jsonl", std::ios::binary | std::ios::trunc);
    if (!out)
      return make_error(ErrorCode::kIoError, "{}: cannot write", (dir / "truth.jsonl").string());
    out << meta.dump() << '\n';
    for (const auto& [key, r] : truth) out << r.dump() << '\n';
    if (!out)
      return make_error(ErrorCode::kIoError, "{}: write failed", (dir / "truth.jsonl").string());
  }

  // ---- frames: rendered ahead by worker threads, written in stamp order by this thread
  std::vector<Job> jobs;
  for (const int s : written_streams)
    for (int64_t k = 0; k < plans[static_cast<size_t>(s)].count; ++k)
      jobs.push_back({stamp_ns(k, plans[static_cast<size_t>(s)].rate_hz), s, k});
  std::stable_sort(jobs.begin(), jobs.end(), [](const Job& a, const Job& b) {
    return a.stamp != b.stamp ? a.stamp < b.stamp : a.stream < b.stream;
  });

  auto make = [&](const Job& job) -> Result<FramePtr> {
    const StreamPlan& p = plans[static_cast<size_t>(job.stream)];
    const Timestamp ts = Timestamp::from_ns(job.stamp);
    const auto seq = static_cast<uint64_t>(job.index);
    switch (p.kind) {
      case SensorKind::kColor: {
        cv::Mat bgr;
        gen.render(p.camera, job.stamp, p.id, job.index, &bgr, nullptr);
        return make_frame(p.id, ts, seq, ColorImage{bgr});
      }
      case SensorKind::kDepth: {
        cv::Mat depth;
        gen.render(p.camera, job.stamp, p.id, job.index, nullptr, &depth);
        return make_frame(p.id, ts, seq, DepthImage{depth, true});
      }
      case SensorKind::kSkeleton: {
        Skeleton sk;
        sk.bodies.push_back(
            demo_skeleton_body(script, options.seed, p.id, seq, job.stamp, options.joint_noise_m));
        return make_frame(p.id, ts, seq, std::move(sk));
      }
      case SensorKind::kAudio: {
        AudioChunk a;
        a.sample_rate = options.audio_sample_rate;
        const bool robot = p.id == "robot_audio";
        a.channels = robot ? 1 : channels;
        const size_t chunk = static_cast<size_t>(std::llround(options.audio_chunk_s * fs_hz));
        const size_t b = static_cast<size_t>(job.index) * chunk, e = std::min(n_samples, b + chunk);
        a.samples.reserve((e - b) * static_cast<size_t>(a.channels));
        for (size_t i = b; i < e; ++i) {
          if (robot) {
            a.samples.push_back(static_cast<float>(robot_played[i] * robot_gain));
            continue;
          }
          for (int c = 0; c < channels; ++c)
            a.samples.push_back(static_cast<float>(mix[static_cast<size_t>(c)][i] * gain));
        }
        return make_frame(p.id,
                          Timestamp::from_ns(static_cast<int64_t>(std::llround(b * 1e9 / fs_hz))),
                          seq, std::move(a));
      }
    }
    return make_error(ErrorCode::kInternal, "unknown stream kind");
  };

  const size_t n_jobs = jobs.size();
  const size_t window = 48;
  std::vector<std::optional<Result<FramePtr>>> slots(n_jobs);
  std::mutex mu;
  std::condition_variable cv_ready, cv_space;
  size_t written = 0;
  std::atomic<size_t> next_job{0};
  std::atomic<bool> abort{false};
  auto worker = [&]() {
    for (;;) {
      const size_t i = next_job.fetch_add(1);
      if (i >= n_jobs) return;
      {
        std::unique_lock lock(mu);
        cv_space.wait(lock, [&] { return abort || i < written + window; });
        if (abort) return;
      }
      Result<FramePtr> r = make_error(ErrorCode::kInternal, "not rendered");
      try {
        r = make(jobs[i]);
      } catch (const std::exception& e) {
        r = make_error(ErrorCode::kInternal, "demo frame {}: {}", i, e.what());
      }
      std::lock_guard lock(mu);
      slots[i] = std::move(r);
      cv_ready.notify_all();
    }
  };
  std::vector<std::thread> pool;
  for (int i = 0; i < options.threads; ++i) pool.emplace_back(worker);
  Status status = ok_status();
  DemoSummary summary;
  for (size_t i = 0; i < n_jobs && status; ++i) {
    Result<FramePtr> r = make_error(ErrorCode::kInternal, "");
    {
      std::unique_lock lock(mu);
      cv_ready.wait(lock, [&] { return slots[i].has_value(); });
      r = std::move(*slots[i]);
      slots[i].reset();
    }
    if (!r) {
      status = tl::unexpected(r.error());
    } else {
      status = (*writer)->write(**r);
      ++summary.frames[(*r)->sensor];
    }
    {
      std::lock_guard lock(mu);
      written = i + 1;
    }
    cv_space.notify_all();
    if (progress && (i % 64 == 0 || i + 1 == n_jobs))
      progress(static_cast<double>(i + 1) / static_cast<double>(n_jobs));
  }
  {
    std::lock_guard lock(mu);
    abort = !status;
  }
  cv_space.notify_all();
  for (auto& t : pool) t.join();
  if (!status) return tl::unexpected(status.error());
  if (auto st = (*writer)->close(); !st) return tl::unexpected(st.error());

  summary.out_dir = dir;
  summary.utterances = static_cast<int>(utterances.size());
  summary.robot_utterances = static_cast<int>(robot_truth.size());
  summary.action_segments = static_cast<int>(script.actions().size());
  summary.truth_records = static_cast<int64_t>(truth.size()) + 1;
  summary.generation_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return summary;
}

}  // namespace dreamsense::sim
