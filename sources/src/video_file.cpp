#include "dreamsense/sources/video_file.hpp"

#include "dreamsense/core/log.hpp"

#include <fmt/format.h>
#include <opencv2/videoio.hpp>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <optional>
#include <system_error>

namespace dreamsense::sources {
namespace fs = std::filesystem;

bool has_video_extension(const fs::path& path) {
  static constexpr std::array<const char*, 14> kExtensions = {
      ".mp4",  ".avi", ".mov", ".mkv", ".m4v", ".webm", ".mpg",
      ".mpeg", ".wmv", ".ogv", ".flv", ".3gp", ".ts",   ".mts"};
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return std::find(kExtensions.begin(), kExtensions.end(), ext) != kExtensions.end();
}

CameraModel approximate_camera(int width, int height, const std::string& frame) {
  CameraModel m;
  m.frame = frame;
  m.image_size = cv::Size(width, height);
  const double f = 500.0 * width / 640.0;  // OpenFace's default for uncalibrated video
  m.K = cv::Matx33d(f, 0, width / 2.0, 0, f, height / 2.0, 0, 0, 1);
  return m;  // R = I, t = 0: the world is the camera's optical frame
}

namespace {

std::string fourcc_text(double v) {
  const auto c = static_cast<uint32_t>(v);
  std::string s;
  for (int i = 0; i < 4; ++i) {
    const char ch = static_cast<char>((c >> (8 * i)) & 0xff);
    if (std::isprint(static_cast<unsigned char>(ch))) s += ch;
  }
  return s;
}

}  // namespace

struct VideoFileSource::Impl {
  VideoFileInfo info;
  cv::VideoCapture capture;
  std::optional<cv::Mat> first;  // decoded by open(), returned by the first next()
  int64_t first_pts_ns = 0;
  int64_t last_stamp_ns = -1;
  uint64_t read = 0;
  int64_t repaired = 0;  // frames whose stamp was not after the previous one (see next())
  bool ended = false;

  std::string name() const { return info.path.string(); }

  // Decodes the next frame and its container stamp (ns); nullopt at the end.
  std::optional<std::pair<cv::Mat, int64_t>> decode() {
    cv::Mat image;
    bool ok = false;
    try {
      ok = capture.read(image);
    } catch (const cv::Exception&) {
      ok = false;
    }
    if (!ok || image.empty()) return std::nullopt;
    const double ms = capture.get(cv::CAP_PROP_POS_MSEC);
    return std::make_pair(image, static_cast<int64_t>(std::llround(ms * 1e6)));
  }
};

VideoFileSource::VideoFileSource() : impl_(std::make_unique<Impl>()) {}
VideoFileSource::~VideoFileSource() = default;

Result<std::unique_ptr<VideoFileSource>> VideoFileSource::open(const fs::path& path,
                                                               const VideoFileOptions& options) {
  std::error_code ec;
  if (!fs::exists(path, ec))
    return make_error(ErrorCode::kNotFound, "{}: no such file", path.string());
  if (fs::is_directory(path, ec))
    return make_error(ErrorCode::kInvalidArgument,
                      "{}: a folder without session.yaml (for a folder of videos use "
                      "`dreamsense batch`)",
                      path.string());
  if (fs::file_size(path, ec) == 0)
    return make_error(ErrorCode::kCorruptData, "{}: empty file (0 bytes)", path.string());
  std::unique_ptr<VideoFileSource> src(new VideoFileSource());
  Impl& s = *src->impl_;
  s.info.path = fs::absolute(path).lexically_normal();
  // FFmpeg's own messages ("moov atom not found", ...) would break the one-line error; the
  // error below says it. A user's OPENCV_FFMPEG_LOGLEVEL is kept.
  ::setenv("OPENCV_FFMPEG_LOGLEVEL", "-8", 0);
  try {
    s.capture.open(s.info.path.string(), cv::CAP_FFMPEG);
  } catch (const cv::Exception&) {
  }
  if (!s.capture.isOpened())
    return make_error(ErrorCode::kCorruptData,
                      "{}: not a readable video (OpenCV/FFmpeg cannot open it)", path.string());
  auto first = s.decode();
  if (!first)
    return make_error(ErrorCode::kCorruptData,
                      "{}: no frame can be decoded (zero-length or corrupt video)", path.string());
  s.first = first->first;
  s.first_pts_ns = first->second;
  VideoFileInfo& v = s.info;
  v.width = first->first.cols;
  v.height = first->first.rows;
  v.nominal_fps = s.capture.get(cv::CAP_PROP_FPS);
  if (!std::isfinite(v.nominal_fps) || v.nominal_fps <= 0 || v.nominal_fps > 1000)
    v.nominal_fps = 0;
  const double count = s.capture.get(cv::CAP_PROP_FRAME_COUNT);
  v.frame_count = std::isfinite(count) && count > 0 ? static_cast<int64_t>(count) : 0;
  v.duration_s = v.nominal_fps > 0 && v.frame_count > 0 ? v.frame_count / v.nominal_fps : 0;
  v.codec = fourcc_text(s.capture.get(cv::CAP_PROP_FOURCC));
  v.audio =
      "not analysed: OpenCV's video reader gives no audio on Debian 12 (speech and voice need a "
      "session with a mic_array stream)";
  if (!options.calibration.empty()) {
    auto m = read_camera_model(options.calibration);
    if (!m) return tl::unexpected(m.error());
    if (m->image_size.width != v.width || m->image_size.height != v.height)
      return make_error(ErrorCode::kInvalidArgument,
                        "{}: calibration is for {}x{} images, the video {} is {}x{}",
                        options.calibration.string(), m->image_size.width, m->image_size.height,
                        path.string(), v.width, v.height);
    v.camera = *m;
    v.camera.frame = kVideoStreamId;
    v.approximate_calibration = false;
  } else {
    v.camera = approximate_camera(v.width, v.height, kVideoStreamId);
    v.approximate_calibration = true;
  }

  SessionManifest& m = v.manifest;
  m.name = v.path.stem().string();
  m.frame_rate = v.nominal_fps > 0 ? v.nominal_fps : 25.0;
  m.complete = true;
  StreamEntry e;
  e.id = kVideoStreamId;
  e.kind = SensorKind::kColor;
  e.encoding = "video";
  e.file = v.path.string();
  e.rate_hz = m.frame_rate;
  e.width = v.width;
  e.height = v.height;
  e.frame = kVideoStreamId;
  e.roles = {"child_camera"};
  if (!options.calibration.empty()) e.calibration = fs::absolute(options.calibration).string();
  m.streams.push_back(e);
  m.metadata["source_video"] = v.path.string();
  // Mutual gaze = looking at the camera: the "robot head" is the camera's centre (the world
  // origin, unless a calibration file's extrinsics place the camera elsewhere).
  const cv::Vec3d centre = v.camera.centre_world();
  m.metadata["robot_head_m"] = fmt::format("{} {} {}", centre[0], centre[1], centre[2]);
  m.metadata["calibration"] =
      v.approximate_calibration ? "approximate" : fs::absolute(options.calibration).string();
  return src;
}

Result<FramePtr> VideoFileSource::next() {
  Impl& s = *impl_;
  if (s.ended) return make_error(ErrorCode::kEndOfStream, "{}: end of video", s.name());
  cv::Mat image;
  int64_t pts = 0;
  if (s.first) {
    image = *s.first;
    pts = s.first_pts_ns;
    s.first.reset();
  } else {
    auto f = s.decode();
    if (!f) {
      s.ended = true;
      // The container's frame count is an estimate; a video that stops well before it is
      // truncated or corrupt rather than finished.
      const auto expected = s.info.frame_count;
      if (expected > 0 &&
          static_cast<int64_t>(s.read) < expected - std::max<int64_t>(2, expected / 50))
        return make_error(ErrorCode::kCorruptData,
                          "{}: corrupt or truncated: frame {} of {} cannot be decoded", s.name(),
                          s.read, expected);
      return make_error(ErrorCode::kEndOfStream, "{}: end of video", s.name());
    }
    image = std::move(f->first);
    pts = f->second;
  }
  if (image.cols != s.info.width || image.rows != s.info.height)
    return make_error(ErrorCode::kCorruptData, "{}: frame {} is {}x{}, the video started {}x{}",
                      s.name(), s.read, image.cols, image.rows, s.info.width, s.info.height);
  int64_t stamp = pts - s.first_pts_ns;
  if (s.read > 0 && stamp <= s.last_stamp_ns) {
    // FFmpeg gives some frames no presentation time (often the last one of an AVI): an isolated
    // one is placed one nominal frame period after the previous frame; more than
    // max(2, 1 % of the frames) of them is a broken video.
    const int64_t allowed = std::max<int64_t>(2, s.info.frame_count / 100);
    if (s.info.nominal_fps <= 0 || ++s.repaired > allowed)
      return make_error(ErrorCode::kCorruptData,
                        "{}: broken timestamps: frame {} is at {:.3f} ms, not after frame {} at "
                        "{:.3f} ms",
                        s.name(), s.read, stamp * 1e-6, s.read - 1, s.last_stamp_ns * 1e-6);
    const int64_t repaired =
        s.last_stamp_ns + static_cast<int64_t>(std::llround(1e9 / s.info.nominal_fps));
    log::warn("{}: frame {} has no usable timestamp ({:.3f} ms); placed at {:.3f} ms", s.name(),
              s.read, stamp * 1e-6, repaired * 1e-6);
    stamp = repaired;
  }
  s.last_stamp_ns = stamp;
  ColorImage c;
  c.image = image;
  return make_frame(SensorId(kVideoStreamId), Timestamp::from_ns(stamp), s.read++, std::move(c));
}

SourceInfo VideoFileSource::info() const {
  const VideoFileInfo& v = impl_->info;
  SourceInfo i;
  i.sensors.push_back(SensorDescription{kVideoStreamId, SensorKind::kColor, v.manifest.frame_rate,
                                        v.width, v.height, 0, 0,
                                        v.manifest.streams.front().calibration, kVideoStreamId});
  i.start = Timestamp::from_ns(0);
  if (v.duration_s > 0)
    i.end = Timestamp::from_ns(static_cast<int64_t>(
        std::llround((v.frame_count - 1) / std::max(v.nominal_fps, 1e-9) * 1e9)));
  return i;
}

const VideoFileInfo& VideoFileSource::video() const { return impl_->info; }
uint64_t VideoFileSource::frames_read() const { return impl_->read; }

}  // namespace dreamsense::sources
