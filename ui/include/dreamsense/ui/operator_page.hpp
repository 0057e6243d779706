#pragma once
// The operator page of `dreamsense live --ui PORT` (ui/README.md): a web page for the person
// running a session, served on 127.0.0.1 by default (spec/system.md: network exposure is
// opt-in). Per camera the latest image with the face boxes and landmarks (the selected camera
// highlighted); large indicators for mutual gaze (with its held time), the last utterance (text,
// speaker, direction) and the current gesture; a status strip (session clock, recording on/off
// and size, dropped frames per stream, sensors offline); a "mark" button (key M) that writes a
// timestamped marker into the session. The analysis itself cannot be changed from the page.
//
//   GET  /                   the page (self-contained HTML/CSS/JS polling the API once a second)
//   GET  /api/operator       what the page shows, rounded, with units (operator_state_json)
//   GET  /api/primitives     {"stamp_ns", "primitives": {name: record}, "order": [names]}
//   GET  /api/status         what set_status() last gave
//   GET  /api/cameras        ["camera_left", ...]
//   GET  /camera/<id>.jpg    the camera's latest frame with the overlay (export/overlay.hpp),
//                            JPEG, at most max_image_width wide
//   POST /api/marker         {"label": "..."} (Content-Type application/json): a marker, through
//                            set_marker_handler; 201 + the marker's JSON
//
// Access: every request's Host must be this page's own name (DNS rebinding); a POST that carries
// an Origin must come from the page itself. On an address other than loopback every request also
// needs the access token (`?token=` or header X-Dreamsense-Token): a random one is made when none
// is given, and url() carries it (live prints it once on stderr).
//
// cpp-httplib (Debian libcpp-httplib-dev) serves on its own threads; updates are cheap (frames and
// the blackboard are kept by reference; pictures are drawn and encoded only when asked).

#include "dreamsense/core/blackboard.hpp"
#include "dreamsense/core/camera_model.hpp"
#include "dreamsense/core/multi_frame.hpp"
#include "dreamsense/core/sensor_frame.hpp"
#include "dreamsense/core/status.hpp"
#include "dreamsense/primitives/catalogue.hpp"

#include <nlohmann/json.hpp>

#include <functional>
#include <map>
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
  // Required on every request when set; made at random by start() when the host is not a
  // loopback address and this is empty. Letters, digits, '-' and '_' only.
  std::string token;
  Status check() const;
};

// The page's rounding: the session clock as "01:23.4" (minutes:seconds.tenths; "1:02:03.4" from
// an hour on), a size as "0 B", "830 kB", "12.3 MB", "1.23 GB".
std::string session_clock_text(int64_t ns);
std::string byte_size_text(uint64_t bytes);

class OperatorPage {
 public:
  // Binds and starts serving; a busy port or a bad host is an error naming them.
  static Result<std::unique_ptr<OperatorPage>> start(const OperatorPageOptions& options);
  ~OperatorPage();  // stops serving
  OperatorPage(const OperatorPage&) = delete;
  OperatorPage& operator=(const OperatorPage&) = delete;

  void update(const std::vector<primitives::PrimitiveRecord>& records);
  void update_frame(const SensorId& camera, FramePtr frame);  // colour frames only
  // The tick's colour frames and the blackboard after its analysers ran: the pictures then show
  // face boxes, landmarks, gaze and the selected camera (drawn when the page asks for them).
  void update_view(const MultiFrame& tick, const BlackboardView& view);
  // The cameras' models, for the head axes and gaze rays of the pictures (without: not drawn).
  void set_camera_models(std::map<SensorId, CameraModel> models);
  // The run's figures (live_analysis.cpp): {"stamp_ns", "ticks", "recording": {"on", "bytes"},
  // "streams": {id: {"dropped", "offline"}}, optional "face_model": what head pose and gaze use
  // during a live self-calibration}; shown in the status strip.
  void set_status(nlohmann::json status);
  // Makes a marker (label from the page): returns its JSON ({"n", "stamp_ns", "label", ...}) or
  // an error (the page shows it). Without a handler POST /api/marker answers 503.
  using MarkerHandler = std::function<Result<nlohmann::json>(const std::string& label)>;
  void set_marker_handler(MarkerHandler handler);
  // What GET /api/operator returns: the indicators and the status strip, rounded, with units.
  nlohmann::json operator_state_json() const;
  int port() const;
  const std::string& token() const;  // empty: none needed
  std::string url() const;           // with ?token= when one is needed

 private:
  struct Impl;
  explicit OperatorPage(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace dreamsense::ui
