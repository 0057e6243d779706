#include "dreamsense/sources/depth_sensor_source.hpp"

#include <opencv2/imgproc.hpp>

#include <atomic>
#include <cmath>
#include <deque>
#include <optional>
#include <thread>

#ifdef DREAMSENSE_HAVE_FREENECT
#include <libfreenect_sync.h>
#endif
#ifdef DREAMSENSE_HAVE_OPENNI2
#include <OpenNI.h>
#endif

namespace dreamsense::sources {
namespace {

using Grab = DepthSensorSource::Grab;

class DepthDevice {
 public:
  virtual ~DepthDevice() = default;
  // Blocks until the next frame pair (or fails).
  virtual Result<Grab> grab() = 0;
  virtual double fps() const = 0;
};

// A table plane 1.2 m away, tilted, with a ball 0.1 m in radius circling over it; colour = a
// shaded view of the same scene. Paced at `fps` on the steady clock.
class FakeDevice : public DepthDevice {
 public:
  // unplug_after > 0: the grab after that many frames fails as an unplugged sensor would.
  FakeDevice(double fps, bool color, uint64_t unplug_after)
      : fps_(fps), color_(color), unplug_after_(unplug_after) {}
  Result<Grab> grab() override {
    if (unplug_after_ > 0 && k_ >= unplug_after_)
      return make_error(ErrorCode::kIoError, "fake sensor unplugged after {} frames",
                        unplug_after_);
    const auto period = std::chrono::duration<double>(1.0 / fps_);
    next_ = next_.time_since_epoch().count() == 0 ? std::chrono::steady_clock::now() : next_;
    std::this_thread::sleep_until(next_);
    next_ += std::chrono::duration_cast<std::chrono::steady_clock::duration>(period);
    const double t = static_cast<double>(k_++) / fps_;
    Grab g;
    g.registered = true;
    g.depth_mm.create(240, 320, CV_16UC1);
    const double fx = 285, cx = 160, cy = 120;  // Kinect v1 depth intrinsics at 320x240
    const cv::Vec3d ball(0.25 * std::cos(t), 0.05, 1.1 + 0.25 * std::sin(t));
    for (int v = 0; v < g.depth_mm.rows; ++v)
      for (int u = 0; u < g.depth_mm.cols; ++u) {
        const cv::Vec3d ray((u - cx) / fx, (v - cy) / fx, 1.0);
        // Plane y = 0.2 + 0.15 z (a table seen from above the front): hit at z = 0.2/(ry-0.15).
        double z = ray[1] > 0.16 ? 0.2 / (ray[1] - 0.15) : 0.0;
        if (z > 4.0) z = 0.0;
        // Ball: nearest ray-sphere intersection.
        const cv::Vec3d d = cv::normalize(ray);
        const double b = d.dot(ball), c = ball.dot(ball) - 0.01;
        if (const double disc = b * b - c; disc >= 0) {
          const double s = b - std::sqrt(disc);
          if (s > 0 && (z == 0.0 || s * d[2] < z)) z = s * d[2];
        }
        g.depth_mm.at<uint16_t>(v, u) = static_cast<uint16_t>(std::lround(z * 1000.0));
      }
    if (color_) {
      cv::Mat grey;
      g.depth_mm.convertTo(grey, CV_8U, -255.0 / 4000.0, 255.0);
      cv::cvtColor(grey, g.color, cv::COLOR_GRAY2BGR);
    }
    return g;
  }
  double fps() const override { return fps_; }

 private:
  double fps_;
  bool color_;
  uint64_t unplug_after_;
  uint64_t k_ = 0;
  std::chrono::steady_clock::time_point next_{};
};

#ifdef DREAMSENSE_HAVE_FREENECT
// Kinect v1 through libfreenect's sync wrapper: depth registered to the RGB camera, in mm.
class FreenectDevice : public DepthDevice {
 public:
  FreenectDevice(int index, bool color) : index_(index), color_(color) {}
  ~FreenectDevice() override { freenect_sync_stop(); }
  Result<Grab> grab() override {
    void* depth = nullptr;
    uint32_t ts = 0;
    if (freenect_sync_get_depth(&depth, &ts, index_, FREENECT_DEPTH_REGISTERED) != 0)
      return make_error(ErrorCode::kIoError, "freenect: no depth from Kinect {}", index_);
    Grab g;
    g.registered = true;
    g.depth_mm = cv::Mat(480, 640, CV_16UC1, depth).clone();
    if (color_) {
      void* rgb = nullptr;
      if (freenect_sync_get_video(&rgb, &ts, index_, FREENECT_VIDEO_RGB) != 0)
        return make_error(ErrorCode::kIoError, "freenect: no colour from Kinect {}", index_);
      cv::cvtColor(cv::Mat(480, 640, CV_8UC3, rgb), g.color, cv::COLOR_RGB2BGR);
    }
    return g;
  }
  double fps() const override { return 30; }

 private:
  int index_;
  bool color_;
};
#endif

#ifdef DREAMSENSE_HAVE_OPENNI2
class OpenNi2Device : public DepthDevice {
 public:
  ~OpenNi2Device() override {
    depth_.stop();
    color_.stop();
    depth_.destroy();
    color_.destroy();
    device_.close();
  }
  Status open(const std::string& uri, bool with_color) {
    if (openni::OpenNI::initialize() != openni::STATUS_OK)
      return make_error(ErrorCode::kIoError, "openni2: {}", openni::OpenNI::getExtendedError());
    if (device_.open(uri.empty() ? openni::ANY_DEVICE : uri.c_str()) != openni::STATUS_OK)
      return make_error(ErrorCode::kNotFound, "openni2: cannot open '{}': {}",
                        uri.empty() ? "any device" : uri, openni::OpenNI::getExtendedError());
    if (depth_.create(device_, openni::SENSOR_DEPTH) != openni::STATUS_OK ||
        depth_.start() != openni::STATUS_OK)
      return make_error(ErrorCode::kIoError, "openni2: no depth stream: {}",
                        openni::OpenNI::getExtendedError());
    if (with_color && device_.hasSensor(openni::SENSOR_COLOR) &&
        color_.create(device_, openni::SENSOR_COLOR) == openni::STATUS_OK &&
        color_.start() == openni::STATUS_OK) {
      have_color_ = true;
      registered_ =
          device_.isImageRegistrationModeSupported(openni::IMAGE_REGISTRATION_DEPTH_TO_COLOR) &&
          device_.setImageRegistrationMode(openni::IMAGE_REGISTRATION_DEPTH_TO_COLOR) ==
              openni::STATUS_OK;
    }
    fps_ = depth_.getVideoMode().getFps();
    return ok_status();
  }
  Result<Grab> grab() override {
    openni::VideoFrameRef f;
    if (depth_.readFrame(&f) != openni::STATUS_OK || !f.isValid())
      return make_error(ErrorCode::kEndOfStream, "openni2: depth stream ended");
    Grab g;
    g.registered = registered_;
    cv::Mat(f.getHeight(), f.getWidth(), CV_16UC1, const_cast<void*>(f.getData()),
            static_cast<size_t>(f.getStrideInBytes()))
        .copyTo(g.depth_mm);
    if (have_color_) {
      openni::VideoFrameRef c;
      if (color_.readFrame(&c) == openni::STATUS_OK && c.isValid())
        cv::cvtColor(cv::Mat(c.getHeight(), c.getWidth(), CV_8UC3, const_cast<void*>(c.getData()),
                             static_cast<size_t>(c.getStrideInBytes())),
                     g.color, cv::COLOR_RGB2BGR);
    }
    return g;
  }
  double fps() const override { return fps_ > 0 ? fps_ : 30; }

 private:
  openni::Device device_;
  openni::VideoStream depth_, color_;
  bool have_color_ = false, registered_ = false;
  double fps_ = 0;
};
#endif

}  // namespace

bool depth_driver_available(const std::string& driver) {
  if (driver == "fake") return true;
#ifdef DREAMSENSE_HAVE_FREENECT
  if (driver == "freenect") return true;
#endif
#ifdef DREAMSENSE_HAVE_OPENNI2
  if (driver == "openni2") return true;
#endif
  return false;
}

namespace {

// The fake driver's device: "" (delivers until stopped) or "unplug_after=N" (N >= 1 frames, then
// fails as an unplugged sensor: what a session does when a device is lost). nullopt: malformed.
std::optional<uint64_t> fake_unplug_after(const std::string& device) {
  if (device.empty()) return 0;
  const std::string key = "unplug_after=";
  if (device.rfind(key, 0) != 0) return std::nullopt;
  const std::string n = device.substr(key.size());
  if (n.empty() || n.size() > 9 || n.find_first_not_of("0123456789") != std::string::npos)
    return std::nullopt;
  const uint64_t v = std::stoull(n);
  return v >= 1 ? std::optional<uint64_t>(v) : std::nullopt;
}

}  // namespace

Status DepthSensorOptions::check() const {
  std::string bad;
  if (id.empty()) bad += " id must not be empty;";
  if (driver != "freenect" && driver != "openni2" && driver != "fake")
    bad += " driver must be freenect, openni2 or fake;";
  if (!(fps > 0) || fps > 120) bad += " fps must be in (0, 120];";
  if (driver == "freenect" && !device.empty() &&
      device.find_first_not_of("0123456789") != std::string::npos)
    bad += " freenect device must be a sensor index (0, 1, ...);";
  if (driver == "fake" && !fake_unplug_after(device))
    bad += " fake device must be empty or unplug_after=N (N >= 1);";
  if (!bad.empty()) return make_error(ErrorCode::kInvalidArgument, "depth sensor '{}':{}", id, bad);
  return ok_status();
}

struct DepthSensorSource::Impl {
  DepthSensorOptions options;
  std::unique_ptr<DepthDevice> device;
  std::atomic<bool> stopped{false};
  std::deque<FramePtr> pending;  // the colour frame of the last grab
  uint64_t sequence = 0;
  cv::Size depth_size, color_size;
};

DepthSensorSource::DepthSensorSource(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
DepthSensorSource::~DepthSensorSource() = default;

Result<std::unique_ptr<DepthSensorSource>> DepthSensorSource::open(
    const DepthSensorOptions& options) {
  if (auto s = options.check(); !s) return tl::unexpected(s.error());
  if (!depth_driver_available(options.driver))
    return make_error(ErrorCode::kUnsupported,
                      "depth sensor '{}': driver {} is not in this build (Debian libfreenect-dev / "
                      "libopenni2-dev)",
                      options.id, options.driver);
  auto m = std::make_unique<Impl>();
  m->options = options;
  if (options.driver == "fake")
    m->device = std::make_unique<FakeDevice>(options.fps, options.color,
                                             fake_unplug_after(options.device).value_or(0));
#ifdef DREAMSENSE_HAVE_FREENECT
  if (options.driver == "freenect")
    m->device = std::make_unique<FreenectDevice>(
        options.device.empty() ? 0 : std::stoi(options.device), options.color);
#endif
#ifdef DREAMSENSE_HAVE_OPENNI2
  if (options.driver == "openni2") {
    auto d = std::make_unique<OpenNi2Device>();
    if (auto s = d->open(options.device, options.color); !s)
      return make_error(s.error().code, "depth sensor '{}': {}", options.id, s.error().message);
    m->device = std::move(d);
  }
#endif
  // The first grab tells the sizes (and whether the device delivers at all).
  auto first = m->device->grab();
  if (!first)
    return make_error(first.error().code, "depth sensor '{}': {}", options.id,
                      first.error().message);
  m->depth_size = first->depth_mm.size();
  m->color_size = first->color.size();
  auto source = std::unique_ptr<DepthSensorSource>(new DepthSensorSource(std::move(m)));
  return source;
}

Result<FramePtr> DepthSensorSource::next() {
  Impl& m = *impl_;
  if (!m.pending.empty()) {
    FramePtr f = m.pending.front();
    m.pending.pop_front();
    return f;
  }
  if (m.stopped)
    return make_error(ErrorCode::kEndOfStream, "depth sensor '{}' stopped", m.options.id);
  auto g = m.device->grab();
  if (!g) return tl::unexpected(g.error());
  const auto stamp =
      Timestamp::from_ns(std::chrono::duration_cast<std::chrono::nanoseconds>(
                             std::chrono::steady_clock::now() - m.options.clock_origin)
                             .count());
  const uint64_t seq = m.sequence++;
  if (m.options.color && !g->color.empty())
    m.pending.push_back(make_frame(m.options.id + ".color", stamp, seq, ColorImage{g->color}));
  DepthImage d;
  d.depth_mm = g->depth_mm;
  d.registered_to_color = g->registered;
  return make_frame(m.options.id + ".depth", stamp, seq, std::move(d));
}

SourceInfo DepthSensorSource::info() const {
  SourceInfo i;
  i.live = true;
  SensorDescription d;
  d.id = impl_->options.id + ".depth";
  d.kind = SensorKind::kDepth;
  d.rate_hz = impl_->device->fps();
  d.width = impl_->depth_size.width;
  d.height = impl_->depth_size.height;
  d.frame = d.id;
  i.sensors.push_back(d);
  if (impl_->options.color && !impl_->color_size.empty()) {
    SensorDescription c = d;
    c.id = impl_->options.id + ".color";
    c.kind = SensorKind::kColor;
    c.width = impl_->color_size.width;
    c.height = impl_->color_size.height;
    c.frame = c.id;
    i.sensors.push_back(c);
  }
  return i;
}

void DepthSensorSource::stop() { impl_->stopped = true; }
cv::Size DepthSensorSource::depth_size() const { return impl_->depth_size; }
cv::Size DepthSensorSource::color_size() const { return impl_->color_size; }
double DepthSensorSource::fps() const { return impl_->device->fps(); }

}  // namespace dreamsense::sources
