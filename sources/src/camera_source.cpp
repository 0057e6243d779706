#include "dreamsense/sources/camera_source.hpp"

#include "dreamsense/core/log.hpp"

#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include <algorithm>
#include <atomic>
#include <filesystem>
#include <mutex>
#include <optional>
#include <thread>

#include "capture_queue.hpp"

namespace dreamsense::sources {

namespace {

bool all_digits(const std::string& s) {
  return !s.empty() && std::all_of(s.begin(), s.end(), [](char c) { return c >= '0' && c <= '9'; });
}

}  // namespace

Status CameraSourceOptions::check() const {
  std::string bad;
  auto add = [&](const std::string& s) { bad += (bad.empty() ? "" : "; ") + s; };
  if (sensor.empty()) add("sensor is empty");
  if (device.empty()) add("device is empty");
  if (width < 0 || height < 0 || (width == 0) != (height == 0))
    add(fmt::format("width and height must both be 0 or both > 0 (are {} x {})", width, height));
  if (!(fps >= 0 && fps <= 1000)) add(fmt::format("fps must be in [0, 1000] (is {})", fps));
  if (max_queued < 1) add("max_queued must be >= 1");
  if (!bad.empty()) return make_error(ErrorCode::kInvalidArgument, "CameraSourceOptions: {}", bad);
  return ok_status();
}

struct CameraSource::Impl {
  CameraSourceOptions options;
  cv::VideoCapture capture;
  bool is_file = false;  // played back at its own rate
  cv::Size size;
  double fps = 0;
  std::thread thread;
  std::atomic<bool> stop{false};
  std::unique_ptr<detail::CaptureQueue> queue;
  mutable std::mutex stats_mutex;
  CameraCaptureStats stats;

  ~Impl() {
    stop = true;
    if (thread.joinable()) thread.join();
  }

  int64_t now_ns() const {
    return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now() -
                                                                options.clock_origin)
        .count();
  }

  void run() {
    const auto start = std::chrono::steady_clock::now();
    uint64_t sequence = 0;
    while (!stop) {
      if (is_file && fps > 0) {
        // A file stands in for a camera: deliver frame k at start + k / fps.
        const auto due = start + std::chrono::nanoseconds(static_cast<int64_t>(
                                     static_cast<double>(sequence) * 1e9 / fps));
        std::this_thread::sleep_until(due);
      }
      if (!capture.grab()) {
        queue->finish(
            is_file ? std::nullopt
                    : std::optional<Error>(Error{ErrorCode::kIoError,
                                                 fmt::format("camera '{}' ({}): the device stopped "
                                                             "delivering frames",
                                                             options.sensor, options.device)}));
        return;
      }
      const int64_t stamp = now_ns();
      cv::Mat image;
      if (!capture.retrieve(image) || image.empty()) continue;
      if (image.channels() == 4) cv::cvtColor(image, image, cv::COLOR_BGRA2BGR);
      if (image.size() != size) {
        log::warn("camera '{}': frame is {}x{}, expected {}x{}; dropped", options.sensor,
                  image.cols, image.rows, size.width, size.height);
        continue;
      }
      auto frame = make_frame(options.sensor, Timestamp::from_ns(stamp), sequence++,
                              ColorImage{std::move(image)});
      const size_t dropped = queue->push(std::move(frame));
      std::lock_guard lock(stats_mutex);
      ++stats.frames;
      stats.dropped_frames += dropped;
    }
    queue->finish(std::nullopt);
  }
};

CameraSource::CameraSource(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
CameraSource::~CameraSource() = default;

Result<std::unique_ptr<CameraSource>> CameraSource::open(const CameraSourceOptions& options) {
  if (auto st = options.check(); !st) return tl::unexpected(st.error());
  auto m = std::make_unique<Impl>();
  m->options = options;
  m->queue = std::make_unique<detail::CaptureQueue>(options.max_queued);
  m->is_file = std::filesystem::is_regular_file(options.device);
  // A path that does not exist: say so without letting every OpenCV backend try it.
  const bool looks_like_path = options.device.find("://") == std::string::npos &&
                               options.device.find('/') != std::string::npos;
  if (looks_like_path && !std::filesystem::exists(options.device))
    return make_error(ErrorCode::kNotFound, "camera '{}': {} does not exist", options.sensor,
                      options.device);
  const bool opened = all_digits(options.device)
                          ? m->capture.open(std::stoi(options.device), cv::CAP_V4L2)
                          : m->capture.open(options.device);
  if (!opened || !m->capture.isOpened())
    return make_error(ErrorCode::kNotFound,
                      "camera '{}': cannot open '{}' (a V4L2 index such as 0, /dev/videoN, a "
                      "video file or URL; list devices with v4l2-ctl --list-devices)",
                      options.sensor, options.device);
  if (!m->is_file) {
    if (options.width > 0) {
      m->capture.set(cv::CAP_PROP_FRAME_WIDTH, options.width);
      m->capture.set(cv::CAP_PROP_FRAME_HEIGHT, options.height);
    }
    if (options.fps > 0) m->capture.set(cv::CAP_PROP_FPS, options.fps);
  }
  // The size frames really have: the first frame decides (devices may ignore the request).
  cv::Mat first;
  if (!m->capture.read(first) || first.empty())
    return make_error(ErrorCode::kIoError, "camera '{}' ({}): opened but delivered no frame",
                      options.sensor, options.device);
  m->size = first.size();
  m->fps = m->capture.get(cv::CAP_PROP_FPS);
  if (!(m->fps > 0 && m->fps <= 1000)) m->fps = options.fps > 0 ? options.fps : 30;
  if (m->is_file) m->capture.set(cv::CAP_PROP_POS_FRAMES, 0);  // replay from the start
  if (options.width > 0 && m->size != cv::Size(options.width, options.height))
    log::warn("camera '{}': asked for {}x{}, the device delivers {}x{}", options.sensor,
              options.width, options.height, m->size.width, m->size.height);
  Impl* raw = m.get();
  m->thread = std::thread([raw] { raw->run(); });
  return std::unique_ptr<CameraSource>(new CameraSource(std::move(m)));
}

Result<FramePtr> CameraSource::next() {
  return impl_->queue->pop(fmt::format("camera '{}': capture stopped", impl_->options.sensor));
}

SourceInfo CameraSource::info() const {
  SourceInfo i;
  SensorDescription d;
  d.id = impl_->options.sensor;
  d.kind = SensorKind::kColor;
  d.rate_hz = impl_->fps;
  d.width = impl_->size.width;
  d.height = impl_->size.height;
  d.frame = d.id;
  i.sensors.push_back(d);
  i.live = true;
  return i;
}

void CameraSource::stop() { impl_->stop = true; }  // the capture thread then finishes the queue

CameraCaptureStats CameraSource::stats() const {
  std::lock_guard lock(impl_->stats_mutex);
  return impl_->stats;
}

cv::Size CameraSource::size() const { return impl_->size; }
double CameraSource::fps() const { return impl_->fps; }

}  // namespace dreamsense::sources
