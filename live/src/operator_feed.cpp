#include "operator_feed.hpp"

#include <chrono>

namespace dreamsense::live {

namespace fs = std::filesystem;

namespace {
uint64_t folder_bytes(const fs::path& dir) {
  uint64_t n = 0;
  std::error_code ec;
  for (fs::recursive_directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec))
    if (it->is_regular_file(ec)) n += it->file_size(ec);
  return n;
}
}  // namespace

OperatorFeed::OperatorFeed(ui::OperatorPage& page, Duration offline_after)
    : page_(page), offline_after_(offline_after) {
  page_.set_marker_handler([this](const std::string& label) { return make_marker(label); });
}

OperatorFeed::~OperatorFeed() { page_.set_marker_handler(nullptr); }

void OperatorFeed::attach(runner::AnalysisOptions& analysis) {
  analysis.on_tick_view = [this](const MultiFrame& tick, const BlackboardView& view) {
    on_tick(tick, view);
  };
  analysis.markers = [this] {
    std::lock_guard lock(mutex_);
    return markers_;
  };
}

void OperatorFeed::set_capture(const sources::LiveCapture& capture,
                               const std::optional<fs::path>& record_dir) {
  std::lock_guard lock(mutex_);
  clock_origin_ = capture.clock_origin();
  record_dir_ = record_dir;
  if (record_dir) marker_writer_ = std::make_unique<sources::MarkerWriter>(*record_dir);
  for (const auto& s : capture.manifest().streams) streams_[s.id];
  // Head axes and gaze rays on the pictures (a calibration that does not read is the
  // analysis' error to report, not the page's).
  if (auto models = sources::read_color_calibrations(fs::current_path(), capture.manifest()))
    page_.set_camera_models(std::move(*models));
}

void OperatorFeed::set_face_model_status(std::function<std::string()> status) {
  std::lock_guard lock(mutex_);
  face_model_status_ = std::move(status);
}

void OperatorFeed::end() {
  std::lock_guard lock(mutex_);
  ended_ = true;
}

void OperatorFeed::on_tick(const MultiFrame& tick, const BlackboardView& view) {
  page_.update_view(tick, view);
  nlohmann::json status;
  {
    std::lock_guard lock(mutex_);
    if (!first_tick_.is_set()) first_tick_ = tick.stamp;
    // Frames the analysis never saw (dropped by the capture queue or the flow limiter, or not
    // matched to a tick): gaps in each stream's sequence numbers.
    auto seen = [this](const FramePtr& f) {
      if (!f) return;
      StreamFigures& s = streams_[f->sensor];
      if (s.last_sequence && f->sequence > *s.last_sequence)
        s.dropped += f->sequence - *s.last_sequence - 1;
      if (!s.last_sequence || f->sequence > *s.last_sequence) s.last_sequence = f->sequence;
      if (!s.last_stamp || f->stamp > *s.last_stamp) s.last_stamp = f->stamp;
    };
    for (const auto& [id, f] : tick.frames) seen(f);
    for (const auto& [id, chunks] : tick.chunks)
      for (const auto& c : chunks) seen(c);
    // The recording's size, about once a second of session time.
    if (record_dir_ &&
        (!size_checked_.is_set() || tick.stamp - size_checked_ >= Duration::from_seconds(1.0))) {
      record_bytes_ = folder_bytes(*record_dir_);
      size_checked_ = tick.stamp;
    }
    nlohmann::json streams = nlohmann::json::object();
    for (const auto& [id, s] : streams_) {
      const Timestamp since = s.last_stamp ? *s.last_stamp : first_tick_;
      streams[id] = {{"dropped", s.dropped}, {"offline", tick.stamp - since > offline_after_}};
    }
    status = {{"stamp_ns", tick.stamp.ns()},
              {"ticks", ++ticks_},
              {"recording", {{"on", record_dir_.has_value()}, {"bytes", record_bytes_}}},
              {"streams", streams}};
    if (face_model_status_) status["face_model"] = face_model_status_();
  }
  page_.set_status(std::move(status));
}

Result<nlohmann::json> OperatorFeed::make_marker(const std::string& label) {
  std::lock_guard lock(mutex_);
  if (!clock_origin_)
    return make_error(ErrorCode::kFailedPrecondition, "the devices have not started yet");
  if (ended_) return make_error(ErrorCode::kFailedPrecondition, "the session has ended");
  // The session clock: the capture's stamps count from its origin (stamp 0).
  sources::SessionMarker m;
  m.stamp_ns = std::chrono::duration_cast<std::chrono::nanoseconds>(
                   std::chrono::steady_clock::now() - *clock_origin_)
                   .count();
  m.label = label;
  m.source = "operator_page";
  m.n = static_cast<int>(markers_.size()) + 1;
  if (marker_writer_) DS_RETURN_IF_ERROR(marker_writer_->append(m));
  markers_.push_back(m);
  nlohmann::json j = sources::to_json(m);
  j["recorded"] = marker_writer_ != nullptr;
  return j;
}

}  // namespace dreamsense::live
