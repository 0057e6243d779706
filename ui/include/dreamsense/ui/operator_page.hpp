#pragma once
// The operator page of `dreamsense live --ui PORT`: a small web page, served on 127.0.0.1 by
// default (spec/system.md: network exposure is opt-in), that shows what the system perceives
// while a session runs: the latest record of every primitive (status, value, confidence), the
// latest frame of each camera, and the run's counters. It only reads: nothing on the page can
// change the analysis.
//
//   GET /                   the page (plain HTML + a few lines of JavaScript polling the API)
//   GET /api/primitives     {"stamp_ns": tick, "primitives": {name: primitives.jsonl record}}
//   GET /api/status         what set_status() last gave (ticks, dropped frames, ...)
//   GET /api/cameras        ["camera_left", ...]
//   GET /camera/<id>.jpg    the camera's latest frame, JPEG, at most max_image_width wide
//
// cpp-httplib (Debian libcpp-httplib-dev) serves on its own threads; updates are cheap (frames
// are kept by reference and only encoded when the page asks).

#include "dreamsense/core/sensor_frame.hpp"
#include "dreamsense/core/status.hpp"
#include "dreamsense/primitives/catalogue.hpp"

#include <nlohmann/json.hpp>

#include <memory>
#include <string>
#include <vector>

namespace dreamsense::ui {

struct OperatorPageOptions {
  std::string host = "127.0.0.1";  // "0.0.0.0" exposes the page (and the children's faces!)
  int port = 8080;                 // 0 = any free port (see OperatorPage::port())
  int jpeg_quality = 75;
  int max_image_width = 640;
  // Privacy (`live --blur-faces`): pixelate the faces of the latest getFaces answer (each camera's
  // boxes grown by 25 %) in the camera pictures served (export/overlay.hpp blur_regions).
  bool blur_faces = false;
  Status check() const;
};

class OperatorPage {
 public:
  // Binds and starts serving; a busy port or a bad host is an error naming them.
  static Result<std::unique_ptr<OperatorPage>> start(const OperatorPageOptions& options);
  ~OperatorPage();  // stops serving
  OperatorPage(const OperatorPage&) = delete;
  OperatorPage& operator=(const OperatorPage&) = delete;

  void update(const std::vector<primitives::PrimitiveRecord>& records);
  void update_frame(const SensorId& camera, FramePtr frame);  // colour frames only
  void set_status(nlohmann::json status);
  int port() const;
  std::string url() const;

 private:
  struct Impl;
  explicit OperatorPage(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace dreamsense::ui
