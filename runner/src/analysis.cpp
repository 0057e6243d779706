#include "dreamsense/runner/analysis.hpp"

#include "dreamsense/body/body_analyzer.hpp"
#include "dreamsense/core/camera_model.hpp"
#include "dreamsense/core/log.hpp"
#include "dreamsense/core/perception.hpp"
#include "dreamsense/export/report.hpp"
#include "dreamsense/export/writers.hpp"
#include "dreamsense/face_detection/face_detection_analyzer.hpp"
#include "dreamsense/sound_direction/sound_direction_analyzer.hpp"
#include "dreamsense/sources/session.hpp"
#include "dreamsense/speech/speech_analyzer.hpp"

namespace dreamsense::runner {
namespace fs = std::filesystem;

Status AnalysisOptions::check() const {
  if (session_dir.empty())
    return make_error(ErrorCode::kInvalidArgument, "analysis: no session folder given");
  return evaluator.check();
}

nlohmann::json AnalysisSummary::to_json() const {
  nlohmann::json stages = nlohmann::json::array();
  for (const auto& a : pipeline.analyzers) {
    std::vector<double> v = a.latency_ms;
    std::sort(v.begin(), v.end());
    stages.push_back({{"name", a.name},
                      {"calls", a.calls},
                      {"errors", a.errors},
                      {"latency_ms_median", v.empty() ? 0.0 : v[v.size() / 2]},
                      {"latency_ms_p95", v.empty() ? 0.0 : v[v.size() * 95 / 100]}});
  }
  nlohmann::json outs = nlohmann::json::array();
  for (const auto& o : outputs) outs.push_back(o.filename().string());
  return {{"ticks", pipeline.ticks},
          {"frames", pipeline.frames},
          {"media_seconds", pipeline.media_seconds},
          {"wall_seconds", pipeline.wall_seconds},
          {"analyzers", analyzers},
          {"stages", stages},
          {"dropped_frames", pipeline.sync.dropped_frames()},
          {"status_counts", status_counts},
          {"outputs", outs}};
}

namespace {

// world_from_sensor of a stream from its calibration file (identity when it has none).
Status sensor_pose(const sources::SessionReader& reader, const sources::StreamEntry& s,
                   cv::Matx33d& R, cv::Vec3d& t) {
  R = cv::Matx33d::eye();
  t = {0, 0, 0};
  if (s.calibration.empty()) return ok_status();
  auto m = read_camera_model(reader.dir() / s.calibration);
  if (!m) return tl::unexpected(m.error());
  R = m->R.t();
  t = -(m->R.t() * m->t);
  return ok_status();
}

// Session errors name files relative to the session folder; show where that folder is.
Error in_session(Error e, const fs::path& session_dir) {
  if (!e.message.empty() && e.message.front() != '/')
    e.message = (session_dir / e.message).string();
  return e;
}

}  // namespace

Result<AnalysisSummary> analyze_session(const AnalysisOptions& options,
                                        const AnalysisProgress& progress) {
  if (auto s = options.check(); !s) return tl::unexpected(s.error());

  // Validate the whole session first (every stream, even those no analyser reads yet), so a
  // damaged recording is reported before any output is written.
  auto full = sources::SessionReader::open(options.session_dir);
  if (!full) return tl::unexpected(in_session(full.error(), options.session_dir));
  if (!options.out_dir.empty())
    if (auto s = exporters::ensure_writable_dir(options.out_dir); !s)
      return tl::unexpected(s.error());
  const sources::SessionManifest manifest = (*full)->manifest();
  const SourceInfo full_info = (*full)->info();

  // Analysers the session's streams support.
  std::vector<std::unique_ptr<Analyzer>> analyzers;
  std::vector<SensorId> used;
  SensorId body_sensor;
  for (const auto& s : manifest.streams) {
    if (s.kind != SensorKind::kSkeleton || !body_sensor.empty()) continue;
    body::BodyAnalyzerOptions bo;
    bo.skeleton_sensor = s.id;
    if (auto st = sensor_pose(**full, s, bo.world_from_sensor_R, bo.world_from_sensor_t); !st)
      return tl::unexpected(st.error());
    auto a = body::make_body_analyzer(bo);
    if (!a) return tl::unexpected(a.error());
    analyzers.push_back(std::move(*a));
    body_sensor = s.id;
    used.push_back(s.id);
  }
  // Sound direction on the first audio stream: array geometry from its calibration file
  // (calib/<id>.yaml: mic positions, rate, extrinsics), Kinect v1 when it has none.
  SensorId audio_sensor;
  for (const auto& s : manifest.streams) {
    if (s.kind != SensorKind::kAudio || !audio_sensor.empty()) continue;
    sound_direction::SoundDirectionAnalyzerOptions so;
    so.audio_sensor = s.id;
    if (!s.calibration.empty()) {
      auto g = sound_direction::read_mic_array((*full)->dir() / s.calibration);
      if (!g) return tl::unexpected(g.error());
      so.geometry = *g;
    } else {
      log::info("audio stream '{}' has no calibration: assuming the Kinect v1 array", s.id);
      so.geometry.sample_rate = s.sample_rate;
    }
    if (s.channels != static_cast<int>(so.geometry.mics_m.size()) ||
        s.sample_rate != so.geometry.sample_rate)
      return make_error(ErrorCode::kInvalidArgument,
                        "{}: audio stream '{}' has {} channel(s) at {} Hz but its microphone "
                        "array{} has {} microphones at {} Hz",
                        (options.session_dir / sources::kManifestName).string(), s.id, s.channels,
                        s.sample_rate,
                        s.calibration.empty() ? " (Kinect v1 default)" : " (" + s.calibration + ")",
                        so.geometry.mics_m.size(), so.geometry.sample_rate);
    auto a = sound_direction::make_sound_direction_analyzer(so);
    if (!a) return tl::unexpected(a.error());
    analyzers.push_back(std::move(*a));
    audio_sensor = s.id;
    used.push_back(s.id);
  }

  // Speech recognition on the same audio stream, when a grammar is known.
  SensorId speech_sensor;
  if (!audio_sensor.empty()) {
    fs::path grammar = options.speech_grammar;
    if (grammar.empty()) {
      auto g = manifest.metadata.find("speech_grammar");
      if (g != manifest.metadata.end()) grammar = (*full)->dir() / g->second;
    }
    if (!grammar.empty()) {
      speech::SpeechAnalyzerOptions so;
      so.audio_sensor = audio_sensor;
      so.grammar = grammar;
      auto a = speech::make_speech_analyzer(so);
      if (!a) return tl::unexpected(a.error());
      analyzers.push_back(std::move(*a));
      speech_sensor = audio_sensor;
    }
  }

  // Face detection on the colour cameras that watch the child (ids "camera*", DREAM's three
  // 1280x960 cameras); their calibrations give the faces' 3-D positions.
  std::map<SensorId, CameraModel> face_cameras;
  for (const auto& s : manifest.streams) {
    if (s.kind != SensorKind::kColor || s.id.rfind("camera", 0) != 0) continue;
    if (s.calibration.empty()) {
      log::warn("camera '{}' has no calibration: no face positions from it", s.id);
      continue;
    }
    auto m = read_camera_model((*full)->dir() / s.calibration);
    if (!m) return tl::unexpected(m.error());
    face_cameras[s.id] = *m;
  }
  if (!face_cameras.empty()) {
    face_detection::FaceDetectionAnalyzerOptions fo;
    fo.cameras.clear();
    for (const auto& [id, m] : face_cameras) {
      fo.cameras.push_back(id);
      used.push_back(id);
    }
    auto a = face_detection::make_face_detection_analyzer(fo);
    if (!a) return tl::unexpected(a.error());
    analyzers.push_back(std::move(*a));
  }

  sources::SessionReaderOptions ro;
  ro.only = used;
  auto reader =
      used.empty() ? std::move(full) : sources::SessionReader::open(options.session_dir, ro);
  if (!reader) return tl::unexpected(in_session(reader.error(), options.session_dir));
  full = {};

  PipelineOptions po;
  po.sync.policy = options.policy;
  po.sync.tick_period = period_from_rate(manifest.frame_rate > 0 ? manifest.frame_rate : 25.0);
  po.sync.tolerance = po.sync.tick_period / 2;
  po.sync.start = full_info.start;  // ticks on the session clock, whatever streams are read
  po.pace_source = options.pace_source;
  AnalysisSummary summary;
  for (const auto& a : analyzers) summary.analyzers.emplace_back(a->name());
  auto pipeline = Pipeline::build(po, (*reader)->info(), std::move(analyzers));
  if (!pipeline) return tl::unexpected(pipeline.error());

  const bool write = !options.out_dir.empty();
  exporters::PrimitivesJsonlWriter jsonl;
  exporters::EventLogWriter events;
  exporters::DreamExport dream;
  exporters::HtmlReport report;
  if (write) {
    if (auto s = jsonl.open(options.out_dir / "primitives.jsonl"); !s)
      return tl::unexpected(s.error());
    if (auto s = events.open(options.out_dir / "events.log", manifest.clock_origin_unix_ns); !s)
      return tl::unexpected(s.error());
  }
  primitives::Evaluator evaluator(options.evaluator, body_sensor, audio_sensor);
  if (!face_cameras.empty()) evaluator.enable_faces(face_cameras);
  if (!speech_sensor.empty()) evaluator.enable_speech(speech_sensor);

  auto on_tick = [&](const MultiFrame& tick, const BlackboardView& view) -> Status {
    const auto records = evaluator.evaluate(tick, view);
    for (const auto& r : records)
      summary.status_counts[primitives::info(r.id).name][primitives::to_string(r.status)]++;
    if (!write) return ok_status();
    if (auto s = jsonl.write(records); !s) return s;
    if (auto s = events.write(records); !s) return s;
    report.add(records);
    exporters::DreamExport::Frame f;
    if (auto body = view.get(keys::kChildBody);
        body && body->present() && tick.stamp - body->stamp <= options.evaluator.freshness)
      f.skeleton = body->value->body;
    dream.add(f);
    return ok_status();
  };
  const Timestamp t0 = full_info.start, t1 = full_info.end;
  auto on_progress = [&](Timestamp t) {
    if (progress && t0.is_set() && t1.is_set() && t1 > t0)
      progress(std::clamp((t - t0).seconds() / (t1 - t0).seconds(), 0.0, 1.0));
  };
  if (auto s = (*pipeline)->run(**reader, on_tick, on_progress); !s)
    return tl::unexpected(in_session(s.error(), options.session_dir));
  summary.pipeline = (*pipeline)->stats();

  if (write) {
    if (auto s = jsonl.commit(); !s) return tl::unexpected(s.error());
    if (auto s = events.commit(); !s) return tl::unexpected(s.error());
    if (auto s = dream.write(options.out_dir / "dream.json", manifest); !s)
      return tl::unexpected(s.error());
    std::string names;
    for (const auto& a : summary.analyzers) names += (names.empty() ? "" : ", ") + a;
    const auto& ps = (*pipeline)->stats();
    if (auto s = report.write(
            options.out_dir / "report.html", manifest,
            {fmt::format("{} ticks, {:.1f} s of session time", ps.ticks, ps.media_seconds),
             "analysers: " + (names.empty() ? std::string("none") : names)});
        !s)
      return tl::unexpected(s.error());
    summary.outputs = {options.out_dir / "primitives.jsonl", options.out_dir / "events.log",
                       options.out_dir / "dream.json", options.out_dir / "report.html",
                       options.out_dir / "summary.json"};
    exporters::OutputFile f;
    if (auto s = f.open(options.out_dir / "summary.json"); !s) return tl::unexpected(s.error());
    nlohmann::json sj = summary.to_json();
    sj["session"] = fs::absolute(options.session_dir).string();
    if (auto s = f.write(sj.dump(2) + "\n"); !s) return tl::unexpected(s.error());
    if (auto s = f.commit(); !s) return tl::unexpected(s.error());
  }
  return summary;
}

}  // namespace dreamsense::runner
