#include "dreamsense/runner/analysis.hpp"

#include "dreamsense/body/body_analyzer.hpp"
#include "dreamsense/core/camera_model.hpp"
#include "dreamsense/core/log.hpp"
#include "dreamsense/core/perception.hpp"
#include "dreamsense/export/overlay.hpp"
#include "dreamsense/export/report.hpp"
#include "dreamsense/export/writers.hpp"
#include "dreamsense/eye_centers/eye_center_analyzer.hpp"
#include "dreamsense/face_detection/face_detection_analyzer.hpp"
#include "dreamsense/face_landmarks/face_landmarks_analyzer.hpp"
#include "dreamsense/face_tracks/face_tracks_analyzer.hpp"
#include "dreamsense/gaze/gaze_analyzer.hpp"
#include "dreamsense/head_pose/face_shape_fit.hpp"
#include "dreamsense/head_pose/head_pose_analyzer.hpp"
#include "dreamsense/sound_direction/sound_direction_analyzer.hpp"
#include "dreamsense/sources/recorder.hpp"
#include "dreamsense/sources/session.hpp"
#include "dreamsense/speech/acoustic_adaptation.hpp"
#include "dreamsense/speech/speech_analyzer.hpp"
#include "dreamsense/voice_id/audio_files.hpp"
#include "dreamsense/voice_id/voice_id_analyzer.hpp"

#include <cmath>
#include <optional>
#include <sstream>

namespace dreamsense::runner {
namespace fs = std::filesystem;

std::filesystem::path default_subjects_dir() { return DREAMSENSE_SUBJECTS_DIR; }

Status AnalysisOptions::check() const {
  if (session_dir.empty())
    return make_error(ErrorCode::kInvalidArgument, "analysis: no session folder given");
  if (voice_method != "off")
    if (auto m = voice_id::parse_voice_id_method(voice_method); !m)
      return tl::unexpected(m.error());
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
Status sensor_pose(const fs::path& session_dir, const sources::StreamEntry& s, cv::Matx33d& R,
                   cv::Vec3d& t) {
  R = cv::Matx33d::eye();
  t = {0, 0, 0};
  if (s.calibration.empty()) return ok_status();
  auto m = read_camera_model(session_dir / s.calibration);
  if (!m) return tl::unexpected(m.error());
  R = m->R.t();
  t = -(m->R.t() * m->t);
  return ok_status();
}

// "x y z" (spaces and/or commas) -> a vector; nullopt unless exactly three finite numbers.
std::optional<cv::Vec3d> parse_vec3(std::string text) {
  std::replace(text.begin(), text.end(), ',', ' ');
  std::istringstream in(text);
  cv::Vec3d v;
  if (!(in >> v[0] >> v[1] >> v[2])) return std::nullopt;
  std::string rest;
  if (in >> rest) return std::nullopt;
  for (int i = 0; i < 3; ++i)
    if (!std::isfinite(v[i])) return std::nullopt;
  return v;
}

// The voice id analyser that the options and the session ask for; null: identifyVoice disabled.
Result<std::unique_ptr<Analyzer>> make_voice_analyzer(const AnalysisOptions& o,
                                                      const sources::SessionManifest& manifest,
                                                      const fs::path& session_dir,
                                                      const SensorId& audio) {
  if (o.voice_method == "off") return std::unique_ptr<Analyzer>{};
  auto method = voice_id::parse_voice_id_method(o.voice_method);
  if (!method) return tl::unexpected(method.error());
  voice_id::VoiceIdAnalyzerOptions vo;
  vo.audio_sensor = audio;
  vo.method = *method;
  if (vo.method == voice_id::VoiceIdMethod::kGmmUbm) {
    const auto enroll = manifest.metadata.find("voice_enroll");
    if (!o.voice_model.empty()) {
      vo.model_file = o.voice_model;
    } else if (enroll == manifest.metadata.end()) {
      log::info(
          "identifyVoice disabled: no voice model given and the session has no enrolment "
          "audio (metadata voice_enroll)");
      return std::unique_ptr<Analyzer>{};
    } else {
      auto audio_files = voice_id::read_speaker_folders(session_dir / enroll->second);
      if (!audio_files) return tl::unexpected(audio_files.error());
      auto m = voice_id::train_voice_model(*audio_files, {}, voice_id::VoiceTrainOptions{});
      if (!m)
        return make_error(m.error().code, "{}: {}", (session_dir / enroll->second).string(),
                          m.error().message);
      std::string who;
      for (const auto& s : m->speakers)
        who += fmt::format("{}{} ({:.1f} s)", who.empty() ? "" : ", ", s.id,
                           s.frames * m->features.hop_s);
      log::info("voice models from the session's enrolment: {}", who);
      vo.model = std::make_shared<const voice_id::VoiceModel>(std::move(*m));
    }
  }
  auto a = voice_id::make_voice_id_analyzer(vo);
  if (!a) return tl::unexpected(a.error());
  return std::move(*a);
}

// Session errors name files relative to the session folder; show where that folder is.
Error in_session(Error e, const fs::path& session_dir) {
  if (!e.message.empty() && e.message.front() != '/')
    e.message = (session_dir / e.message).string();
  return e;
}

struct SubjectCalibration {
  std::filesystem::path face_model, gaze_model, speech_model;  // empty = none
};

// The calibration files in effect (AnalysisOptions: explicit files, else the subject folder's).
Result<SubjectCalibration> subject_calibration(const AnalysisOptions& options,
                                               const sources::SessionManifest& manifest) {
  SubjectCalibration c;
  std::filesystem::path dir = options.subject_dir;
  if (dir.empty() && options.subject_from_session) {
    if (auto it = manifest.metadata.find("subject"); it != manifest.metadata.end()) {
      const std::filesystem::path candidate = options.subjects_dir / it->second;
      if (std::filesystem::is_directory(candidate))
        dir = candidate;
      else
        log::info("no calibration for subject '{}' in {}: generic face model", it->second,
                  options.subjects_dir.string());
    }
  } else if (!dir.empty() && !std::filesystem::is_directory(dir)) {
    return make_error(ErrorCode::kNotFound, "{}: subject calibration folder not found",
                      dir.string());
  }
  if (!dir.empty()) {
    if (std::filesystem::exists(dir / "face_model.yaml")) c.face_model = dir / "face_model.yaml";
    if (std::filesystem::exists(dir / "gaze.yaml")) c.gaze_model = dir / "gaze.yaml";
    if (std::filesystem::is_directory(dir / "speech_model")) c.speech_model = dir / "speech_model";
    if (c.face_model.empty() && c.gaze_model.empty() && c.speech_model.empty())
      return make_error(ErrorCode::kNotFound,
                        "{}: a subject folder needs face_model.yaml, gaze.yaml and/or "
                        "speech_model/",
                        dir.string());
  }
  if (!options.face_model.empty()) c.face_model = options.face_model;
  if (!options.gaze_model.empty()) c.gaze_model = options.gaze_model;
  if (!options.speech_model.empty()) c.speech_model = options.speech_model;
  return c;
}

}  // namespace

namespace {

struct AnalysisPlan {
  std::vector<std::unique_ptr<Analyzer>> analyzers;
  std::vector<SensorId> used;  // streams the analysers read
  SensorId body_sensor, audio_sensor, speech_sensor, voice_sensor;
  std::map<SensorId, CameraModel> face_cameras;
};

// Builds the analysers a session's streams support. File references of the manifest
// (calibrations, grammar, enrolment) are relative to `dir` (or absolute: live capture).
Result<AnalysisPlan> plan_analysis(const AnalysisOptions& options,
                                   const sources::SessionManifest& manifest, const fs::path& dir) {
  // Analysers the session's streams support.
  AnalysisPlan plan;
  auto& analyzers = plan.analyzers;
  auto& used = plan.used;
  SensorId& body_sensor = plan.body_sensor;
  for (const auto& s : manifest.streams) {
    if (s.kind != SensorKind::kSkeleton || !body_sensor.empty()) continue;
    body::BodyAnalyzerOptions bo;
    bo.skeleton_sensor = s.id;
    if (auto st = sensor_pose(dir, s, bo.world_from_sensor_R, bo.world_from_sensor_t); !st)
      return tl::unexpected(st.error());
    auto a = body::make_body_analyzer(bo);
    if (!a) return tl::unexpected(a.error());
    analyzers.push_back(std::move(*a));
    body_sensor = s.id;
    used.push_back(s.id);
  }
  // Sound direction on the first audio stream: array geometry from its calibration file
  // (calib/<id>.yaml: mic positions, rate, extrinsics), Kinect v1 when it has none.
  SensorId& audio_sensor = plan.audio_sensor;
  std::vector<cv::Vec3d> audio_mics;  // the array's geometry, for the speech beamformer
  for (const auto& s : manifest.streams) {
    if (s.kind != SensorKind::kAudio || !audio_sensor.empty()) continue;
    sound_direction::SoundDirectionAnalyzerOptions so;
    so.audio_sensor = s.id;
    if (!s.calibration.empty()) {
      auto g = sound_direction::read_mic_array(dir / s.calibration);
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
                        (dir / sources::kManifestName).string(), s.id, s.channels, s.sample_rate,
                        s.calibration.empty() ? " (Kinect v1 default)" : " (" + s.calibration + ")",
                        so.geometry.mics_m.size(), so.geometry.sample_rate);
    auto a = sound_direction::make_sound_direction_analyzer(so);
    if (!a) return tl::unexpected(a.error());
    analyzers.push_back(std::move(*a));
    audio_sensor = s.id;
    audio_mics = so.geometry.mics_m;
    used.push_back(s.id);
  }

  // The child's calibration files (face model, gaze constants, speech model).
  auto calibration = subject_calibration(options, manifest);
  if (!calibration) return tl::unexpected(calibration.error());

  // Speech recognition on the same audio stream, when a grammar is known.
  SensorId& speech_sensor = plan.speech_sensor;
  if (!audio_sensor.empty()) {
    fs::path grammar = options.speech_grammar;
    if (grammar.empty()) {
      auto g = manifest.metadata.find("speech_grammar");
      if (g != manifest.metadata.end()) grammar = dir / g->second;
    }
    if (!grammar.empty()) {
      speech::SpeechAnalyzerOptions so;
      so.audio_sensor = audio_sensor;
      so.grammar = grammar;
      if (!calibration->speech_model.empty()) {
        if (auto st = speech::use_acoustic_model(so.recognizer, calibration->speech_model); !st)
          return tl::unexpected(st.error());
        log::info("speech: acoustic model {}", calibration->speech_model.string());
      }
      so.mic_positions_m = audio_mics;  // steers toward the sound direction (runs before it)
      auto a = speech::make_speech_analyzer(so);
      if (!a) return tl::unexpected(a.error());
      analyzers.push_back(std::move(*a));
      speech_sensor = audio_sensor;
    }
  }

  // Speaker identification on the same audio stream, after the sound direction analyser (the
  // direction rule reads its directions).
  SensorId& voice_sensor = plan.voice_sensor;
  if (!audio_sensor.empty()) {
    auto a = make_voice_analyzer(options, manifest, dir, audio_sensor);
    if (!a) return tl::unexpected(a.error());
    if (*a) {
      analyzers.push_back(std::move(*a));
      voice_sensor = audio_sensor;
    }
  }

  // Face detection on the colour cameras that watch the child (ids "camera*", DREAM's three
  // 1280x960 cameras); their calibrations give the faces' 3-D positions.
  auto calibrated = sources::read_color_calibrations(dir, manifest);
  if (!calibrated) return tl::unexpected(calibrated.error());
  std::map<SensorId, CameraModel>& face_cameras = plan.face_cameras;
  for (const auto& s : manifest.streams) {
    if (s.kind != SensorKind::kColor || s.id.rfind("camera", 0) != 0) continue;
    if (const auto c = calibrated->find(s.id); c != calibrated->end())
      face_cameras[s.id] = c->second;
    else
      log::warn("camera '{}' has no calibration: no face positions from it", s.id);
  }
  if (!face_cameras.empty()) {
    face_detection::FaceDetectionAnalyzerOptions fo;
    fo.cameras.clear();
    fo.camera_models = face_cameras;  // select the camera by head yaw (D4.2)
    for (const auto& [id, m] : face_cameras) {
      fo.cameras.push_back(id);
      used.push_back(id);
    }
    auto a = face_detection::make_face_detection_analyzer(fo);
    if (!a) return tl::unexpected(a.error());
    analyzers.push_back(std::move(*a));

    // Landmarks and head pose on the selected camera's face.
    face_landmarks::FaceLandmarksAnalyzerOptions lo;
    lo.cameras = fo.cameras;
    auto l = face_landmarks::make_face_landmarks_analyzer(lo);
    if (!l) return tl::unexpected(l.error());
    analyzers.push_back(std::move(*l));
    head_pose::HeadPoseAnalyzerOptions ho;
    ho.cameras = face_cameras;
    std::optional<gaze::GazeModelFile> gaze_model;
    if (!calibration->gaze_model.empty()) {
      auto m = gaze::read_gaze_model(calibration->gaze_model);
      if (!m) return tl::unexpected(m.error());
      gaze_model = *m;
      ho.model_from_head = m->model_from_head;  // the subject's head-model offset
    }
    if (!calibration->face_model.empty()) {
      auto m = head_pose::read_face_model(calibration->face_model.string());
      if (!m) return tl::unexpected(m.error());
      ho.estimator.model = *m;
    }
    log::info("head pose: face model {}; gaze constants {}",
              calibration->face_model.empty() ? "generic_51 (no subject calibration)"
                                              : calibration->face_model.string(),
              calibration->gaze_model.empty() ? "built-in" : calibration->gaze_model.string());
    auto h = head_pose::make_head_pose_analyzer(ho);
    if (!h) return tl::unexpected(h.error());
    analyzers.push_back(std::move(*h));
    // Pupil centres in the landmarks' eye regions, then gaze and mutual gaze.
    eye_centers::EyeCenterAnalyzerOptions eo;
    eo.cameras = fo.cameras;
    auto e = eye_centers::make_eye_center_analyzer(eo);
    if (!e) return tl::unexpected(e.error());
    analyzers.push_back(std::move(*e));
    gaze::GazeAnalyzerOptions go;
    go.cameras = face_cameras;
    go.mutual = options.mutual_gaze;
    if (gaze_model) {
      go.estimator.plane = gaze_model->plane;
      go.estimator.right_eye = gaze_model->right_eye;
      go.estimator.left_eye = gaze_model->left_eye;
      if (gaze_model->right_eyeball && gaze_model->left_eyeball) {
        go.estimator.method = gaze::GazeMethod::kEyeball;
        go.estimator.right_eyeball = *gaze_model->right_eyeball;
        go.estimator.left_eyeball = *gaze_model->left_eyeball;
      }
    }
    if (options.robot_head_from_session) {
      if (auto it = manifest.metadata.find("robot_head_m"); it != manifest.metadata.end()) {
        auto v = parse_vec3(it->second);
        if (!v)
          return make_error(ErrorCode::kCorruptData,
                            "{}: metadata robot_head_m must be three numbers \"x y z\" in metres "
                            "(got \"{}\")",
                            (dir / sources::kManifestName).string(), it->second);
        go.mutual.robot_head_m = *v;
      } else {
        log::info("the session has no robot_head_m metadata: mutual gaze uses ({}, {}, {}) m",
                  go.mutual.robot_head_m[0], go.mutual.robot_head_m[1], go.mutual.robot_head_m[2]);
      }
    }
    auto g = gaze::make_gaze_analyzer(go);
    if (!g) return tl::unexpected(g.error());
    analyzers.push_back(std::move(*g));

    // 3-D face tracks (F23 trackFace).
    face_tracks::FaceTracksAnalyzerOptions to;
    to.cameras = face_cameras;
    auto t = face_tracks::make_face_tracks_analyzer(to);
    if (!t) return tl::unexpected(t.error());
    analyzers.push_back(std::move(*t));
  }

  return plan;
}

// Runs the planned analysers over `source` and writes the outputs (options.out_dir).
// [t0, t1] is the media span for progress (unset for live sources).
Result<AnalysisSummary> run_plan(const AnalysisOptions& options, AnalysisPlan plan,
                                 const sources::SessionManifest& manifest, Source& source,
                                 const PipelineOptions& po, const AnalysisProgress& progress,
                                 Timestamp t0, Timestamp t1, const fs::path& error_dir,
                                 const std::string& session_name) {
  auto& analyzers = plan.analyzers;
  const SensorId& body_sensor = plan.body_sensor;
  const SensorId& audio_sensor = plan.audio_sensor;
  const SensorId& speech_sensor = plan.speech_sensor;
  const SensorId& voice_sensor = plan.voice_sensor;
  const auto& face_cameras = plan.face_cameras;
  AnalysisSummary summary;
  for (const auto& a : analyzers) summary.analyzers.emplace_back(a->name());
  auto pipeline = Pipeline::build(po, source.info(), std::move(analyzers));
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
  if (!face_cameras.empty()) {
    evaluator.enable_faces(face_cameras);
    evaluator.enable_gaze();
  }
  if (!speech_sensor.empty()) evaluator.enable_speech(speech_sensor);
  if (!voice_sensor.empty()) evaluator.enable_voice(voice_sensor);

  exporters::OverlayWriter overlay;
  const bool want_overlay = write && options.overlay && !face_cameras.empty();
  if (want_overlay) {
    exporters::OverlayOptions oo;
    oo.cameras = face_cameras;
    oo.fps = manifest.frame_rate > 0 ? manifest.frame_rate : 25.0;
    if (auto s = overlay.open(options.out_dir / "overlay.mp4", oo); !s)
      return tl::unexpected(s.error());
  }
  auto on_tick = [&](const MultiFrame& tick, const BlackboardView& view) -> Status {
    if (want_overlay)
      if (auto s = overlay.add(tick, view); !s) return s;
    if (options.on_tick_frames) options.on_tick_frames(tick);
    const auto records = evaluator.evaluate(tick, view);
    for (const auto& r : records)
      summary.status_counts[primitives::info(r.id).name][primitives::to_string(r.status)]++;
    if (options.on_records)
      if (auto s = options.on_records(records); !s) return s;
    if (!write) return ok_status();
    if (auto s = jsonl.write(records); !s) return s;
    if (auto s = events.write(records); !s) return s;
    report.add(records);
    exporters::DreamExport::Frame f;
    if (auto body = view.get(keys::kChildBody);
        body && body->present() && tick.stamp - body->stamp <= options.evaluator.freshness)
      f.skeleton = body->value->body;
    if (auto h = view.get(keys::kHeadPose);
        h && h->present() && tick.stamp - h->stamp <= options.evaluator.freshness)
      f.head_gaze = h->value->gaze_direction_world;
    if (auto g = view.get(keys::kEyeGaze);
        g && g->present() && tick.stamp - g->stamp <= options.evaluator.freshness)
      f.eye_gaze = g->value->both.direction_world;
    dream.add(f);
    return ok_status();
  };
  auto on_progress = [&](Timestamp t) {
    if (progress && t0.is_set() && t1.is_set() && t1 > t0)
      progress(std::clamp((t - t0).seconds() / (t1 - t0).seconds(), 0.0, 1.0));
  };
  if (auto s = (*pipeline)->run(source, on_tick, on_progress); !s)
    return tl::unexpected(in_session(s.error(), error_dir));
  summary.pipeline = (*pipeline)->stats();

  if (write) {
    if (auto s = jsonl.commit(); !s) return tl::unexpected(s.error());
    if (auto s = events.commit(); !s) return tl::unexpected(s.error());
    if (want_overlay) {
      if (auto s = overlay.commit(); !s) return tl::unexpected(s.error());
    }
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
    if (want_overlay) summary.outputs.push_back(options.out_dir / "overlay.mp4");
    exporters::OutputFile f;
    if (auto s = f.open(options.out_dir / "summary.json"); !s) return tl::unexpected(s.error());
    nlohmann::json sj = summary.to_json();
    sj["session"] = session_name;
    if (auto s = f.write(sj.dump(2) + "\n"); !s) return tl::unexpected(s.error());
    if (auto s = f.commit(); !s) return tl::unexpected(s.error());
  }
  return summary;
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

  auto plan = plan_analysis(options, manifest, (*full)->dir());
  if (!plan) return tl::unexpected(plan.error());
  const std::vector<SensorId> used = plan->used;

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
  return run_plan(options, std::move(*plan), manifest, **reader, po, progress, full_info.start,
                  full_info.end, options.session_dir, fs::absolute(options.session_dir).string());
}

Result<AnalysisSummary> analyze_live(const AnalysisOptions& options,
                                     sources::LiveCapture& capture) {
  if (options.voice_method != "off")
    if (auto m = voice_id::parse_voice_id_method(options.voice_method); !m)
      return tl::unexpected(m.error());
  if (auto s = options.evaluator.check(); !s) return tl::unexpected(s.error());
  if (!options.out_dir.empty())
    if (auto s = exporters::ensure_writable_dir(options.out_dir); !s)
      return tl::unexpected(s.error());
  const sources::SessionManifest& manifest = capture.manifest();
  // The live manifest's file references are absolute.
  auto plan = plan_analysis(options, manifest, fs::current_path());
  if (!plan) return tl::unexpected(plan.error());
  PipelineOptions po;
  po.sync.policy = SyncPolicy::kLatestWithinTolerance;
  po.sync.tick_period = period_from_rate(manifest.frame_rate > 0 ? manifest.frame_rate : 25.0);
  po.sync.tolerance = po.sync.tick_period / 2;
  po.pace_source = false;  // the devices deliver in real time
  return run_plan(options, std::move(*plan), manifest, capture, po, nullptr, Timestamp::unset(),
                  Timestamp::unset(), fs::path("live"), manifest.name);
}

}  // namespace dreamsense::runner
