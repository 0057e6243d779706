#include "dreamsense/self_calibration/live.hpp"

#include "dreamsense/core/log.hpp"

#include <fmt/format.h>

#include <condition_variable>
#include <ctime>
#include <mutex>
#include <sys/resource.h>
#include <thread>
#include <unistd.h>

namespace dreamsense::self_calibration {
namespace {

// CPU seconds of the calling thread (the search thread's own cost, not the analysis's).
double thread_cpu_seconds() {
  timespec t{};
  if (clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t) != 0) return 0;
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

}  // namespace

Status LiveSelfCalibrationOptions::check() const {
  if (attempts < 1)
    return make_error(ErrorCode::kInvalidArgument, "LiveSelfCalibrationOptions: attempts >= 1");
  if (nice < 0 || nice > 19)
    return make_error(ErrorCode::kInvalidArgument, "LiveSelfCalibrationOptions: nice in [0, 19]");
  if (work_dir.empty())
    return make_error(ErrorCode::kInvalidArgument, "LiveSelfCalibrationOptions: work_dir needed");
  return search.check();
}

struct LiveSelfCalibration::State {
  enum class SearchState { kSearching, kConverged, kNotConverged, kFailed };
  static const char* name(SearchState s) {
    switch (s) {
      case SearchState::kSearching:
        return "searching";
      case SearchState::kConverged:
        return "converged";
      case SearchState::kNotConverged:
        return "not_converged";
      case SearchState::kFailed:
        return "failed";
    }
    return "?";
  }
  LiveSelfCalibrationOptions options;
  std::map<SensorId, CameraModel> cameras;
  std::thread thread;

  struct Tick {
    int64_t stamp_ns = 0;
    std::vector<FramePtr> frames;
  };
  // Guarded by mutex: the one tick waiting for the search thread, and what it reports.
  mutable std::mutex mutex;
  mutable std::condition_variable changed;
  std::optional<Tick> pending;
  bool stopping = false;
  SearchState state = SearchState::kSearching;
  int attempts = 0;
  double cpu_s = 0;
  nlohmann::json last;  // the last finished attempt's to_json()
  std::string error;

  // Ticks with camera frames offered, handed to the search thread, not searched (it was busy).
  uint64_t ticks_offered = 0, ticks_queued = 0, ticks_skipped = 0;
  std::optional<int64_t> used_from_ns;  // the tick at which the files were handed over, if yet

  void search_loop();
};

void LiveSelfCalibration::State::search_loop() {
  // Lowering one's own priority needs no privilege; when it fails the search runs as it is.
  if (options.nice > 0 && setpriority(PRIO_PROCESS, static_cast<id_t>(gettid()), options.nice) != 0)
    log::debug("live self-calibration: nice {} not applied", options.nice);
  const int64_t max_ns = static_cast<int64_t>(options.search.max_seconds * 1e9);
  std::unique_ptr<TickSelfCalibration> search;
  std::optional<int64_t> attempt_first_ns;
  // The search is over: its state, error, last attempt's status.
  auto end_with = [this](SearchState s, const std::string& why, nlohmann::json j) {
    std::lock_guard lock(mutex);
    if (!j.is_null()) last = std::move(j);
    error = why;
    state = s;
    cpu_s = thread_cpu_seconds();
    changed.notify_all();
  };
  while (true) {
    Tick tick;
    {
      std::unique_lock lock(mutex);
      changed.wait(lock, [this] { return stopping || pending.has_value(); });
      if (stopping) return;
      tick = std::move(*pending);
      pending.reset();
      changed.notify_all();  // a waiting offer() may hand over the next tick
    }
    if (!search) {
      auto created = TickSelfCalibration::create(cameras, options.search);
      if (!created) return end_with(SearchState::kFailed, created.error().message, {});
      search = std::move(*created);
      attempt_first_ns = tick.stamp_ns;
    }
    if (auto s = search->add(tick.stamp_ns, tick.frames); !s) {
      log::warn("live self-calibration stopped: {}", s.error().message);
      return end_with(SearchState::kFailed, s.error().message, {});
    }
    tick.frames.clear();  // the frames are not held while the face model is fitted
    const double seconds = static_cast<double>(tick.stamp_ns - *attempt_first_ns) * 1e-9;
    if (!search->enough() && tick.stamp_ns - *attempt_first_ns <= max_ns) continue;

    SessionSelfCalibration c = search->finish("live");
    c.seconds_searched = seconds;
    c.cpu_s = thread_cpu_seconds();
    nlohmann::json j = c.to_json();
    const int attempt = [this] {
      std::lock_guard lock(mutex);
      return ++attempts;
    }();
    if (c.face.converged()) {
      if (auto s = write_self_calibration(c, options.work_dir); !s) {
        log::warn("live self-calibration: {}", s.error().message);
        return end_with(SearchState::kFailed, s.error().message, std::move(j));
      }
      log::info(
          "live self-calibration converged after {:.1f} s of the session ({} ticks searched, "
          "{:.1f} s CPU): {}",
          seconds, c.ticks_searched, c.cpu_s, c.face.reason);
      return end_with(SearchState::kConverged, "", std::move(j));
    }
    log::warn("live self-calibration attempt {} of {} did not converge ({}): {}", attempt,
              options.attempts, head_pose::to_string(c.face.status), c.face.reason);
    if (attempt >= options.attempts) return end_with(SearchState::kNotConverged, "", std::move(j));
    {
      std::lock_guard lock(mutex);
      last = std::move(j);
    }
    search.reset();  // a fresh attempt from the next tick offered
  }
}

LiveSelfCalibration::LiveSelfCalibration(std::unique_ptr<State> state) : state_(std::move(state)) {}

LiveSelfCalibration::~LiveSelfCalibration() {
  {
    std::lock_guard lock(state_->mutex);
    state_->stopping = true;
    state_->changed.notify_all();
  }
  if (state_->thread.joinable()) state_->thread.join();
}

Result<std::unique_ptr<LiveSelfCalibration>> LiveSelfCalibration::start(
    const sources::SessionManifest& manifest, const std::filesystem::path& dir,
    const LiveSelfCalibrationOptions& options_in) {
  DS_RETURN_IF_ERROR(options_in.check());
  auto state = std::make_unique<State>();
  state->options = options_in;
  DS_ASSIGN_OR_RETURN(state->options.search,
                      with_fixation_target(options_in.search, manifest.metadata,
                                           "live configuration's session metadata"));
  DS_ASSIGN_OR_RETURN(state->cameras,
                      self_calibration_cameras(dir, manifest, state->options.search));
  std::error_code ec;
  std::filesystem::create_directories(options_in.work_dir, ec);
  // An earlier run's files (analysis --force) must not pass for this session's.
  for (const char* name : {"face_model.yaml", "gaze.yaml", "self_calibration.json"})
    if (!ec) std::filesystem::remove(options_in.work_dir / name, ec);
  if (ec)
    return make_error(ErrorCode::kIoError, "{}: {}", options_in.work_dir.string(), ec.message());
  State* s = state.get();
  state->thread = std::thread([s] { s->search_loop(); });
  return std::unique_ptr<LiveSelfCalibration>(new LiveSelfCalibration(std::move(state)));
}

std::optional<SubjectFiles> LiveSelfCalibration::offer(const MultiFrame& tick) {
  State& s = *state_;
  std::unique_lock lock(s.mutex);
  if (s.used_from_ns) return std::nullopt;  // handed over already
  if (s.state == State::SearchState::kConverged) {
    s.used_from_ns = tick.stamp.ns();
    SubjectFiles files;
    files.face_model = s.options.work_dir / "face_model.yaml";
    files.gaze_model = s.options.work_dir / "gaze.yaml";
    return files;
  }
  if (s.state != State::SearchState::kSearching) return std::nullopt;
  State::Tick t;
  t.stamp_ns = tick.stamp.ns();
  for (const auto& [id, frame] : tick.frames)
    if (frame && s.cameras.count(id) > 0) t.frames.push_back(frame);
  if (t.frames.empty()) return std::nullopt;
  if (s.ticks_offered++ % static_cast<uint64_t>(s.options.search.tick_step) != 0)
    return std::nullopt;
  if (s.options.wait_when_busy)
    s.changed.wait(lock, [&s] { return !s.pending || s.state != State::SearchState::kSearching; });
  if (s.state != State::SearchState::kSearching) return std::nullopt;
  if (s.pending) {
    ++s.ticks_skipped;  // the search thread is behind: the waiting tick is kept
    return std::nullopt;
  }
  s.pending = std::move(t);
  ++s.ticks_queued;
  s.changed.notify_all();
  return std::nullopt;
}

std::string LiveSelfCalibration::model_in_use() const {
  std::lock_guard lock(state_->mutex);
  if (state_->used_from_ns) return "the child's self-calibrated model";
  if (state_->state == State::SearchState::kNotConverged)
    return "generic model (self-calibration did not converge)";
  if (state_->state == State::SearchState::kFailed)
    return "generic model (self-calibration failed)";
  return "generic model, self-calibrating";
}

void LiveSelfCalibration::wait() const {
  std::unique_lock lock(state_->mutex);
  state_->changed.wait(
      lock, [this] { return state_->stopping || state_->state != State::SearchState::kSearching; });
}

nlohmann::json LiveSelfCalibration::status() const {
  const State& s = *state_;
  std::lock_guard lock(s.mutex);
  nlohmann::json j = s.last.is_object() ? s.last : nlohmann::json::object();
  j["live"] = true;
  j["state"] = State::name(s.state);
  j["attempts"] = s.attempts;
  j["ticks_offered"] = s.ticks_offered;
  j["ticks_queued"] = s.ticks_queued;
  j["ticks_skipped_busy"] = s.ticks_skipped;
  if (s.state != State::SearchState::kSearching) j["cpu_s"] = s.cpu_s;
  if (!s.error.empty()) j["error"] = s.error;
  if (s.state == State::SearchState::kConverged) j["files"] = s.options.work_dir.string();
  j["used_from_ns"] = s.used_from_ns ? nlohmann::json(*s.used_from_ns) : nlohmann::json();
  return j;
}

}  // namespace dreamsense::self_calibration
