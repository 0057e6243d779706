#pragma once
// A live RGB-D sensor (docs/recording.md "Depth sensors"): depth (uint16 millimetres, registered
// to the colour image where the driver can) and colour, as two streams `<id>.depth` and
// `<id>.color` of one Source. Drivers:
//   freenect  Kinect v1 through libfreenect's sync API (device = the sensor's index, "0");
//   openni2   OpenNI2 (Kinect via its driver, Asus Xtion, Orbbec; device = a URI, an .oni
//             recording, or "" for the first sensor);
//   fake      a synthetic sensor (a table plane with a ball moving over it), for dry runs and
//             tests without hardware; device "unplug_after=N": after N frames it fails as an
//             unplugged sensor would (what a session does when a device is lost).
// Frames are stamped on arrival with the capture clock (steady clock since clock_origin), like
// the cameras'. A device that does not open is an error naming the driver and the device.

#include "dreamsense/core/source.hpp"
#include "dreamsense/core/status.hpp"

#include <opencv2/core.hpp>

#include <chrono>
#include <memory>
#include <string>

namespace dreamsense::sources {

struct DepthSensorOptions {
  std::string id = "front";     // streams <id>.depth and <id>.color
  std::string driver = "fake";  // freenect | openni2 | fake
  std::string device;           // see above
  double fps = 30;              // fake: its rate; the real drivers deliver at the device's
  bool color = true;            // also the colour stream
  std::chrono::steady_clock::time_point clock_origin = std::chrono::steady_clock::now();
  Status check() const;
};

// Which drivers this build has ("fake" always).
bool depth_driver_available(const std::string& driver);

class DepthSensorSource : public Source {
 public:
  static Result<std::unique_ptr<DepthSensorSource>> open(const DepthSensorOptions& options);
  ~DepthSensorSource() override;
  DepthSensorSource(const DepthSensorSource&) = delete;
  DepthSensorSource& operator=(const DepthSensorSource&) = delete;
  // Blocks until the next frame (depth, then its colour frame). After stop(): kEndOfStream.
  Result<FramePtr> next() override;
  SourceInfo info() const override;  // the two streams
  void stop();                       // thread-safe
  cv::Size depth_size() const;
  cv::Size color_size() const;
  double fps() const;

  // The device behind a driver (internal; public so tests can count grabs).
  struct Grab {
    cv::Mat depth_mm;  // CV_16UC1, 0 = no measurement
    cv::Mat color;     // CV_8UC3 BGR, or empty
    bool registered = false;
  };

 private:
  struct Impl;
  explicit DepthSensorSource(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace dreamsense::sources
