#include "dreamsense/runner/analysis.hpp"

#include "dreamsense/core/log.hpp"
#include "dreamsense/core/output_file.hpp"
#include "dreamsense/dream/writers.hpp"
#include "dreamsense/export/csv_tables.hpp"
#include "dreamsense/export/overlay.hpp"
#include "dreamsense/export/primitive_json.hpp"
#include "dreamsense/export/report.hpp"
#include "dreamsense/export/writers.hpp"
#include "dreamsense/primitives/values.hpp"
#include "dreamsense/sources/recorder.hpp"
#include "dreamsense/sources/session.hpp"
#include "dreamsense/sources/video_file.hpp"

#include <algorithm>
#include <fstream>
#include <sys/resource.h>
#include <variant>

namespace dreamsense::runner {
namespace fs = std::filesystem;

Status AnalysisOptions::check() const {
  if (session_dir.empty())
    return make_error(ErrorCode::kInvalidArgument, "analysis: no session folder given");
  PipelineOptions threads_only;  // checked before any data is read
  threads_only.threads = threads;
  DS_RETURN_IF_ERROR(threads_only.check());
  DS_RETURN_IF_ERROR(plan.check());
  return evaluator.check();
}

namespace {
nlohmann::json damage_json(const std::vector<sources::StreamDamage>& damage) {
  nlohmann::json out = nlohmann::json::array();
  for (const auto& d : damage) {
    nlohmann::json first = nlohmann::json::array();
    for (const auto& r : d.first)
      first.push_back({{"record", r.record},
                       {"stamp_ns", r.stamp_ns ? nlohmann::json(*r.stamp_ns) : nlohmann::json()},
                       {"what", r.what}});
    out.push_back({{"stream", d.stream},
                   {"file", d.file},
                   {"records", d.records},
                   {"damaged", d.damaged},
                   {"torn_tail", d.torn_tail},
                   {"empty_lines", d.empty_lines},
                   {"first_damaged", first}});
  }
  return out;
}
}  // namespace

nlohmann::json AnalysisSummary::to_json() const {
  nlohmann::json minutes = nlohmann::json::array();
  for (size_t i = 0; i < per_minute.size(); ++i) {
    const Minute& m = per_minute[i];
    const auto& all = pipeline.tick_latency_ms;
    const size_t begin = std::min<size_t>(m.first_tick, all.size());
    std::vector<double> v(
        all.begin() + static_cast<std::ptrdiff_t>(begin),
        all.begin() + static_cast<std::ptrdiff_t>(std::min<size_t>(begin + m.ticks, all.size())));
    std::sort(v.begin(), v.end());
    minutes.push_back({{"minute", i},
                       {"ticks", m.ticks},
                       {"tick_latency_ms_median", v.empty() ? 0.0 : v[v.size() / 2]},
                       {"peak_rss_mb", m.peak_rss_mb}});
  }
  nlohmann::json sensor_json = nlohmann::json::object();
  for (const auto& [id, st] : sensors)
    sensor_json[id] = {
        {"status", st.offline ? "sensor_offline" : "ok"},
        {"ticks_with_data", st.ticks_with_data},
        {"last_stamp_ns", st.last_stamp_ns ? nlohmann::json(*st.last_stamp_ns) : nlohmann::json()},
        {"offline_ticks", st.offline_ticks}};
  nlohmann::json stages = nlohmann::json::array();
  for (const auto& a : pipeline.analyzers) {
    std::vector<double> v = a.latency_ms;
    std::sort(v.begin(), v.end());
    stages.push_back({{"name", a.name},
                      {"calls", a.calls},
                      {"errors", a.errors},
                      {"latency_ms_median", v.empty() ? 0.0 : v[v.size() / 2]},
                      {"latency_ms_p95", v.empty() ? 0.0 : v[v.size() * 95 / 100]},
                      // The total decides throughput: a stage that is slow only now and then
                      // shows in neither the median nor the p95.
                      {"latency_ms_total", a.latency_total_ms}});
  }
  nlohmann::json outs = nlohmann::json::array();
  for (const auto& o : outputs) outs.push_back(o.filename().string());
  nlohmann::json markers_json = nlohmann::json::array();
  for (const auto& m : markers) markers_json.push_back(sources::to_json(m));
  return {{"ticks", pipeline.ticks},
          {"frames", pipeline.frames},
          {"media_seconds", pipeline.media_seconds},
          {"wall_seconds", pipeline.wall_seconds},
          {"analyzers", analyzers},
          {"pipeline", plan},
          {"stages", stages},
          {"dropped_frames", pipeline.sync.dropped_frames()},
          {"status_counts", status_counts},
          {"damage", damage_json(damage)},
          {"non_finite_values", non_finite},
          {"per_minute", minutes},
          {"sensors", sensor_json},
          {"markers", markers_json},
          {"gaze_fixation_yaw_deg", gaze_fixation_yaw_deg ? nlohmann::json(*gaze_fixation_yaw_deg)
                                                          : nlohmann::json(nullptr)},
          {"outputs", outs},
          {"input", input}};
}

bool is_video_input(const fs::path& path) {
  std::error_code ec;
  if (fs::is_directory(path, ec)) return false;
  if (sources::has_video_extension(path)) return true;
  return fs::is_regular_file(path, ec) && path.filename() != sources::kManifestName;
}

namespace {

// The process's peak resident memory so far (getrusage: kB on Linux).
double peak_rss_mb() {
  rusage u{};
  if (getrusage(RUSAGE_SELF, &u) != 0) return 0;
  return static_cast<double>(u.ru_maxrss) / 1024.0;
}

// Session errors name files relative to the session folder; show where that folder is.
Error in_session(Error e, const fs::path& session_dir) {
  if (!e.message.empty() && e.message.front() != '/')
    e.message = (session_dir / e.message).string();
  return e;
}

// The child cameras with a calibration (the overlay draws them).
std::map<SensorId, CameraModel> child_cameras(const PipelinePlan& plan) {
  std::map<SensorId, CameraModel> out;
  for (const auto& s : plan.streams)
    if (s.has_role(roles::kChildCamera) && s.camera) out.emplace(s.id, *s.camera);
  return out;
}

// The report's "Child calibration" paragraph when no self-calibration describes it: the files
// the plan used, or the generic models. A subject folder is named after the child's subject id,
// which may be a name: its path is shown only with --include-names.
std::vector<std::string> calibration_lines(const SubjectFiles& subject, bool include_names) {
  if (subject.face_model.empty() && subject.gaze_model.empty())
    return {"generic face model and built-in gaze constants (no calibration of this child)"};
  if (!include_names)
    return {
        "the child's own face model and gaze constants (files in summary.json's pipeline "
        "notes)"};
  std::vector<std::string> lines;
  if (!subject.folder.empty()) lines.push_back("subject folder " + subject.folder.string());
  lines.push_back("face model " + (subject.face_model.empty() ? std::string("generic")
                                                              : subject.face_model.string()));
  lines.push_back("gaze constants " + (subject.gaze_model.empty() ? std::string("built-in")
                                                                  : subject.gaze_model.string()));
  return lines;
}

// A key frame for the report: the selected camera (getFaces' source, else the first child camera
// in the tick) with the analysis overlay, 480 pixels wide.
void add_key_frame(exporters::HtmlReport& report, const MultiFrame& tick,
                   const BlackboardView& view,
                   const std::vector<primitives::PrimitiveRecord>& records,
                   const std::map<SensorId, CameraModel>& cameras, bool blur_faces) {
  SensorId camera;
  for (const auto& r : records)
    if (r.id == primitives::PrimitiveId::kGetFaces && r.ok()) camera = r.source;
  if (camera.empty() || tick.frames.count(camera) == 0)
    for (const auto& [id, frame] : tick.frames)
      if (cameras.count(id) > 0) {
        camera = id;
        break;
      }
  auto it = tick.frames.find(camera);
  if (it == tick.frames.end() || it->second == nullptr) return;
  const auto* image = it->second->as<ColorImage>();
  if (image == nullptr || image->image.empty()) return;
  exporters::OverlayOptions oo;
  oo.cameras = cameras;
  oo.blur_faces = blur_faces;
  const int w = 480;
  const int h = std::max(2, image->image.rows * w / std::max(1, image->image.cols)) & ~1;
  report.add_key_frame(tick.stamp, camera,
                       exporters::draw_overlay(image->image, camera, tick, view, oo, {w, h}));
}

// Runs the planned analysers over `source` and writes the outputs (options.out_dir).
// [t0, t1] is the media span for progress (unset for live sources).
Result<AnalysisSummary> run_plan(
    const AnalysisOptions& options, PipelinePlan plan, const sources::SessionManifest& manifest,
    Source& source, const PipelineOptions& po, const AnalysisProgress& progress, Timestamp t0,
    Timestamp t1, const fs::path& error_dir, const std::string& session_name, nlohmann::json input,
    const std::function<std::vector<sources::StreamDamage>()>& damage_of,
    const std::function<Result<std::vector<std::unique_ptr<Analyzer>>>(const SubjectFiles&)>&
        replan_subject = nullptr) {
  // Outputs are written into a staging folder and appear together at the end (or not at all).
  const bool write = !options.out_dir.empty();
  StagedOutputDir staging;
  if (write) {
    auto created = StagedOutputDir::create(options.out_dir);
    if (!created) return tl::unexpected(created.error());
    staging = std::move(*created);
  }
  auto out = [&](const char* name) { return staging.staged(name); };

  // Privacy (docs/outputs.md "Names"): the session's own name and its free metadata (which may
  // hold a participant's or operator's name, a date) reach the outputs only with --include-names;
  // otherwise the report and dream.json show the session folder's name (as summary.json does).
  sources::SessionManifest shown = manifest;
  if (!options.plan.include_names) {
    shown.name = session_name;
    shown.metadata.clear();
  }

  const SubjectFiles plan_subject = plan.subject;
  AnalysisSummary summary;
  summary.input = std::move(input);
  for (const auto& a : plan.analyzers) summary.analyzers.emplace_back(a->name());
  summary.plan = plan.to_json();
  const auto overlay_cameras = child_cameras(plan);
  const auto& plan_cameras = overlay_cameras;
  primitives::Evaluator evaluator(options.evaluator, plan.key_sensors, plan.cameras);
  auto pipeline = Pipeline::build(po, source.info(), std::move(plan.analyzers));
  if (!pipeline) return tl::unexpected(pipeline.error());

  exporters::PrimitivesJsonlWriter jsonl;
  dream::EventLogWriter events;
  dream::DreamExport dream_export;
  exporters::HtmlReport report;
  report.set_span(t0, t1);
  if (write) {
    DS_RETURN_IF_ERROR(jsonl.open(out("primitives.jsonl")));
    DS_RETURN_IF_ERROR(events.open(out("events.log"), manifest.clock_origin_unix_ns));
  }

  exporters::OverlayWriter overlay;
  const bool want_overlay = write && options.overlay && !overlay_cameras.empty();
  if (want_overlay) {
    exporters::OverlayOptions oo;
    oo.cameras = overlay_cameras;
    oo.mosaic = options.overlay_mosaic;
    oo.fps = manifest.frame_rate > 0 ? manifest.frame_rate : 25.0;
    oo.blur_faces = options.blur_faces;
    DS_RETURN_IF_ERROR(overlay.open(out("overlay.mp4"), oo));
  }
  // Sensors that go silent while the others deliver are marked (and logged) sensor_offline.
  for (const auto& id : plan.used) summary.sensors[id];
  const Duration offline_after = options.evaluator.offline_after;
  Timestamp first_tick = Timestamp::unset();
  auto track_sensors = [&summary, &first_tick, offline_after](const MultiFrame& tick) {
    auto seen = [&summary](const SensorId& id, Timestamp stamp) {
      auto& s = summary.sensors[id];
      s.ticks_with_data++;
      s.last_stamp_ns = stamp.ns();
    };
    for (const auto& [id, f] : tick.frames)
      if (f) seen(id, f->stamp);
    for (const auto& [id, c] : tick.chunks)
      if (!c.empty()) seen(id, c.back()->stamp);
    for (auto& [id, s] : summary.sensors) {
      // A sensor that has not delivered yet counts from the first tick.
      const Timestamp since = s.last_stamp_ns ? Timestamp::from_ns(*s.last_stamp_ns) : first_tick;
      const bool offline = tick.stamp - since > offline_after;
      if (offline && !s.offline)
        log::warn("{}: no data since {} (more than {} s): sensor_offline", id, since.to_string(),
                  offline_after.seconds());
      else if (!offline && s.offline)
        log::info("{}: delivering again at {}", id, tick.stamp.to_string());
      s.offline = offline;
      s.offline_ticks += offline ? 1 : 0;
    }
  };
  // Minute boundaries of the input: the peak memory so far is sampled as each minute ends.
  uint64_t ticks_seen = 0;
  bool subject_models_replaced = false;  // AnalysisOptions::live_subject_models, once
  auto close_minute = [&summary] {
    if (!summary.per_minute.empty()) summary.per_minute.back().peak_rss_mb = peak_rss_mb();
  };
  auto on_tick = [&](const MultiFrame& tick, const BlackboardView& view) -> Status {
    if (!first_tick.is_set()) first_tick = tick.stamp;
    const auto minute = static_cast<size_t>((tick.stamp - first_tick).seconds() / 60.0);
    while (summary.per_minute.size() <= minute) {
      close_minute();
      summary.per_minute.push_back({ticks_seen, 0, 0});
    }
    ++summary.per_minute.back().ticks;
    ++ticks_seen;
    track_sensors(tick);
    if (want_overlay) DS_RETURN_IF_ERROR(overlay.add(tick, view));
    if (options.on_tick_frames) options.on_tick_frames(tick);
    if (options.on_tick_view) options.on_tick_view(tick, view);
    auto records = evaluator.evaluate(tick, view);
    for (auto& r : records) {
      // No ok answer ever carries a NaN or infinity (a bad calibration or sensor value that got
      // through): it becomes no_data, counted in summary.json.
      if (r.ok() && !exporters::value_is_finite(r)) {
        if (summary.non_finite[primitives::info(r.id).name]++ == 0)
          log::warn("{}: an analyser produced a non-finite value at {}; reported as no_data",
                    primitives::info(r.id).name, r.stamp.to_string());
        r.status = primitives::PrimitiveStatus::kNoData;
        r.value = primitives::PrimitiveValue{};
        r.confidence.reset();
      }
      summary.status_counts[primitives::info(r.id).name][primitives::to_string(r.status)]++;
      if (const auto* gaze = std::get_if<primitives::EyeGazeValue>(&r.value); gaze && r.ok())
        summary.gaze_fixation_yaw_deg = gaze->fixation_yaw_deg;
    }
    if (options.on_records) DS_RETURN_IF_ERROR(options.on_records(records));
    if (options.live_subject_models && replan_subject && !subject_models_replaced) {
      if (const auto files = options.live_subject_models(tick)) {
        DS_ASSIGN_OR_RETURN(auto analyzers, replan_subject(*files));
        DS_RETURN_IF_ERROR((*pipeline)->replace_analyzers(std::move(analyzers)));
        subject_models_replaced = true;
        log::info("live: the child's face model and gaze constants are used from {} on ({})",
                  tick.stamp.to_string(), files->face_model.string());
      }
    }
    if (!write) return ok_status();
    DS_RETURN_IF_ERROR(jsonl.write(records));
    DS_RETURN_IF_ERROR(events.write(records));
    report.add(records);
    if (report.wants_key_frame(tick.stamp))
      add_key_frame(report, tick, view, records, plan_cameras, options.blur_faces);
    dream_export.add(view, tick.stamp, options.evaluator.freshness);
    return ok_status();
  };
  auto on_progress = [&](Timestamp t) {
    if (progress && t0.is_set() && t1.is_set() && t1 > t0)
      progress(std::clamp((t - t0).seconds() / (t1 - t0).seconds(), 0.0, 1.0));
  };
  if (auto s = (*pipeline)->run(source, on_tick, on_progress); !s)
    return tl::unexpected(in_session(s.error(), error_dir));
  summary.pipeline = (*pipeline)->stats();
  close_minute();
  if (damage_of) summary.damage = damage_of();
  if (options.markers) summary.markers = options.markers();

  if (write) {
    DS_RETURN_IF_ERROR(jsonl.commit());
    DS_RETURN_IF_ERROR(events.commit());
    if (want_overlay) DS_RETURN_IF_ERROR(overlay.commit());
    DS_RETURN_IF_ERROR(dream_export.write(out("dream.json"), shown));
    const auto& ps = (*pipeline)->stats();
    exporters::ReportContext rc;
    rc.input = summary.input;
    rc.plan = summary.plan;
    rc.analyzers = summary.analyzers;
    rc.ticks = ps.ticks;
    rc.dropped_frames = ps.sync.dropped_frames();
    rc.wall_seconds = ps.wall_seconds;
    rc.calibration_lines = options.report_calibration
                               ? options.report_calibration()
                               : calibration_lines(plan_subject, options.plan.include_names);
    // A correction the gaze applied to its rays is part of how the gaze numbers were made.
    if (summary.gaze_fixation_yaw_deg && *summary.gaze_fixation_yaw_deg != 0)
      rc.calibration_lines.push_back(fmt::format(
          "gaze: a sideways correction of {:+.1f} deg at the end (the eyes' bias, learnt from "
          "the child's looks at the robot's head; summary.json gaze_fixation_yaw_deg)",
          *summary.gaze_fixation_yaw_deg));
    for (const auto& d : summary.damage)
      if (d.any())
        rc.summary_lines.push_back(fmt::format(
            "Damaged recording: {}: {} of {} records skipped, {} torn at the end, {} empty lines{}",
            d.file, d.damaged, d.records, d.torn_tail, d.empty_lines,
            d.first.empty() ? "" : " (first: " + d.first.front().what + ")"));
    DS_RETURN_IF_ERROR(report.write(out("report.html"), shown, rc));
    if (options.csv.value_or(summary.input.value("kind", "") == "video")) {
      exporters::CsvTablesOptions co;
      co.approximate_calibration = summary.input.value("approximate_calibration", false);
      if (summary.input.value("kind", "") == "video") co.mutual_gaze_target = "the camera";
      for (const auto& m : summary.markers)
        co.markers.push_back({m.stamp_ns, m.label, m.source, fmt::format("marker {}", m.n)});
      auto tables = exporters::write_csv_tables(out("primitives.jsonl"), out("tables"), co);
      if (!tables) return tl::unexpected(tables.error());
    }
    for (const auto& e : fs::directory_iterator(staging.staged("")))
      summary.outputs.push_back(options.out_dir / e.path().filename());
    summary.outputs.push_back(options.out_dir / "summary.json");
    OutputFile f;
    DS_RETURN_IF_ERROR(f.open(out("summary.json")));
    nlohmann::json sj = summary.to_json();
    sj["session"] = session_name;
    sj["names"] = options.plan.include_names ? "included" : "ids only";
    DS_RETURN_IF_ERROR(f.write(sj.dump(2) + "\n"));
    DS_RETURN_IF_ERROR(f.commit());
    DS_RETURN_IF_ERROR(staging.publish(analysis_output_names(), "summary.json"));
  }
  return summary;
}

// An output folder that already holds an analysis is replaced only when asked (--force), so a
// re-run never silently mixes with, or destroys, an earlier result.
Status check_output_folder(const AnalysisOptions& options) {
  if (options.out_dir.empty() || options.replace_existing) return ok_status();
  std::error_code ec;
  for (const auto& name : analysis_output_names())
    if (fs::exists(options.out_dir / name, ec))
      return make_error(ErrorCode::kFailedPrecondition,
                        "{}: the output folder already holds an analysis ({}); add --force to "
                        "replace it",
                        options.out_dir.string(), name);
  return ok_status();
}

PipelineOptions pipeline_options(const sources::SessionManifest& manifest,
                                 const AnalysisOptions& options) {
  PipelineOptions po;
  po.threads = options.threads;
  po.sync.tick_period = period_from_rate(manifest.frame_rate > 0 ? manifest.frame_rate : 25.0);
  po.sync.tolerance = po.sync.tick_period / 2;
  return po;
}

// A plain video: its one-camera session, and the plan options with its assumed intrinsics.
struct VideoPlan {
  std::unique_ptr<sources::VideoFileSource> source;
  PlanOptions plan;
};

// The plan options of this analysis: a live policy makes it a live plan (PlanContext::live).
PlanOptions plan_options_of(const AnalysisOptions& options) {
  PlanOptions p = options.plan;
  p.live = p.live || options.policy == SyncPolicy::kLatestWithinTolerance;
  return p;
}

Result<VideoPlan> open_video(const AnalysisOptions& options) {
  sources::VideoFileOptions vo;
  vo.calibration = options.calibration;
  VideoPlan v;
  DS_ASSIGN_OR_RETURN(v.source, sources::VideoFileSource::open(options.session_dir, vo));
  const sources::VideoFileInfo& info = v.source->video();
  v.plan = plan_options_of(options);
  v.plan.absolute_paths_allowed = true;  // the stream's file is the video's absolute path
  if (info.approximate_calibration) v.plan.assumed_cameras[sources::kVideoStreamId] = info.camera;
  return v;
}

nlohmann::json video_input_json(const sources::VideoFileInfo& v) {
  return {{"kind", "video"},
          {"path", v.path.filename().string()},  // the name only: paths may name people
          {"width", v.width},
          {"height", v.height},
          {"nominal_fps", v.nominal_fps},
          {"container_frames", v.frame_count},
          {"codec", v.codec},
          {"calibration", v.manifest.metadata.at("calibration")},
          {"approximate_calibration", v.approximate_calibration},
          {"fx_px", v.camera.K(0, 0)},
          {"audio", v.audio}};
}

Result<AnalysisSummary> analyze_video(const AnalysisOptions& options,
                                      const AnalysisProgress& progress) {
  DS_ASSIGN_OR_RETURN(VideoPlan v, open_video(options));
  const sources::VideoFileInfo& info = v.source->video();
  auto plan = plan_pipeline(v.plan, info.manifest, info.path.parent_path());
  if (!plan) return tl::unexpected(plan.error());
  DS_RETURN_IF_ERROR(check_output_folder(options));
  PipelineOptions po = pipeline_options(info.manifest, options);
  po.sync.policy = options.policy;
  po.sync.start = Timestamp::from_ns(0);
  po.pace_source = options.pace_source;
  const SourceInfo si = v.source->info();
  return run_plan(options, std::move(*plan), info.manifest, *v.source, po, progress, si.start,
                  si.end, fs::path(), info.path.filename().string(), video_input_json(info),
                  nullptr);
}

}  // namespace

const std::vector<std::string>& analysis_output_names() {
  static const std::vector<std::string> names = {"primitives.jsonl", "events.log",  "dream.json",
                                                 "report.html",      "overlay.mp4", "tables",
                                                 "summary.json"};
  return names;
}

Result<PipelinePlan> plan_session(const AnalysisOptions& options) {
  DS_RETURN_IF_ERROR(options.check());
  if (is_video_input(options.session_dir)) {
    DS_ASSIGN_OR_RETURN(VideoPlan v, open_video(options));
    return plan_pipeline(v.plan, v.source->video().manifest, v.source->video().path.parent_path());
  }
  auto manifest = sources::read_manifest(options.session_dir);
  if (!manifest) return tl::unexpected(in_session(manifest.error(), options.session_dir));
  auto plan = plan_pipeline(plan_options_of(options), *manifest, options.session_dir);
  if (!plan) return tl::unexpected(in_session(plan.error(), options.session_dir));
  return plan;
}

Result<AnalysisSummary> analyze_session(const AnalysisOptions& options,
                                        const AnalysisProgress& progress) {
  DS_RETURN_IF_ERROR(options.check());
  if (is_video_input(options.session_dir)) return analyze_video(options, progress);
  if (std::error_code ec; fs::is_directory(options.session_dir, ec) &&
                          !fs::exists(options.session_dir / sources::kManifestName, ec)) {
    // A folder of recordings is batch's job; say so instead of "session.yaml missing".
    int videos = 0;
    for (const auto& e : fs::directory_iterator(options.session_dir, ec))
      videos += e.is_regular_file(ec) && sources::has_video_extension(e.path());
    if (videos > 0)
      return make_error(ErrorCode::kInvalidArgument,
                        "{}: a folder of {} videos, not a session (no {}): analyse each with "
                        "`dreamsense batch {} --out DIR`",
                        options.session_dir.string(), videos, sources::kManifestName,
                        options.session_dir.string());
  }
  if (!options.calibration.empty())
    return make_error(ErrorCode::kInvalidArgument,
                      "--calibration applies to a video input; {} is a session (its calibrations "
                      "are in session.yaml)",
                      options.session_dir.string());

  // Validate the whole session first (every stream, even those no analyser reads yet), so a
  // damaged recording is reported before any output is written.
  sources::SessionReaderOptions full_options;
  full_options.allow_damaged = options.allow_damaged;
  full_options.follow_links_outside = options.follow_links_outside;
  auto full = sources::SessionReader::open(options.session_dir, full_options);
  if (!full) return tl::unexpected(in_session(full.error(), options.session_dir));
  DS_RETURN_IF_ERROR(check_output_folder(options));
  const sources::SessionManifest manifest = (*full)->manifest();
  const SourceInfo full_info = (*full)->info();
  std::vector<sources::StreamDamage> open_damage = (*full)->damage();

  auto plan = plan_pipeline(plan_options_of(options), manifest, (*full)->dir());
  if (!plan) return tl::unexpected(plan.error());
  const std::vector<SensorId> used = plan->used;

  sources::SessionReaderOptions ro = full_options;
  ro.only = used;
  ro.log_damage = false;  // the full reader has said it
  auto reader =
      used.empty() ? std::move(full) : sources::SessionReader::open(options.session_dir, ro);
  if (!reader) return tl::unexpected(in_session(reader.error(), options.session_dir));
  full = {};

  PipelineOptions po = pipeline_options(manifest, options);
  po.sync.policy = options.policy;
  po.sync.start = full_info.start;  // ticks on the session clock, whatever streams are read
  po.pace_source = options.pace_source;
  // Damage of every stream: found when opening (all streams), and while reading (those analysed).
  const sources::SessionReader* used_reader = reader->get();
  auto damage_of = [open_damage, used_reader] {
    std::vector<sources::StreamDamage> all = open_damage;
    for (const auto& d : used_reader->damage())
      for (auto& a : all)
        if (a.stream == d.stream) a = d;
    return all;
  };
  // The folder's name, not its absolute path (which may name people or machines).
  fs::path session_path = fs::absolute(options.session_dir).lexically_normal();
  if (session_path.filename().empty()) session_path = session_path.parent_path();  // "dir/"
  const std::string session_name = session_path.filename().string();
  // The operator's markers recorded with the session (markers.jsonl) go into the event table.
  AnalysisOptions with_markers = options;
  if (!with_markers.markers) {
    auto markers = sources::read_markers(options.session_dir);
    if (!markers) return tl::unexpected(markers.error());
    with_markers.markers = [m = std::move(*markers)] { return m; };
  }
  auto summary = run_plan(with_markers, std::move(*plan), manifest, **reader, po, progress,
                          full_info.start, full_info.end, options.session_dir, session_name,
                          {{"kind", "session"}, {"name", session_name}}, damage_of);
  // A recording's capture report (capture.json: a device lost, frames dropped while recording)
  // travels with its analysis. A bad report costs the report, not the analysis.
  if (summary && !options.out_dir.empty()) {
    if (auto report = sources::read_capture_report(options.session_dir); !report)
      log::warn("{}", report.error().message);
    else if (*report)
      DS_RETURN_IF_ERROR(add_to_summary(options.out_dir, "recording_capture", **report));
  }
  return summary;
}

Result<AnalysisSummary> analyze_live(const AnalysisOptions& options,
                                     sources::LiveCapture& capture) {
  DS_RETURN_IF_ERROR(options.plan.check());
  DS_RETURN_IF_ERROR(options.evaluator.check());
  DS_RETURN_IF_ERROR(check_output_folder(options));
  const sources::SessionManifest& manifest = capture.manifest();
  // The live manifest's file references are the operator's absolute paths.
  PlanOptions plan_options = options.plan;
  plan_options.absolute_paths_allowed = true;
  plan_options.live = true;
  auto plan = plan_pipeline(plan_options, manifest, fs::current_path());
  if (!plan) return tl::unexpected(plan.error());
  PipelineOptions po = pipeline_options(manifest, options);
  po.sync.policy = SyncPolicy::kLatestWithinTolerance;
  po.pace_source = false;  // the devices deliver in real time
  // The live configuration's session name may name the participant: "live" unless names are in.
  const std::string session_name =
      options.plan.include_names && !manifest.name.empty() ? manifest.name : std::string("live");
  if (options.on_ready) options.on_ready();
  auto replan = [&](const SubjectFiles& files) {
    return replan_subject_analyzers(plan_options, manifest, fs::current_path(), files.face_model,
                                    files.gaze_model);
  };
  return run_plan(options, std::move(*plan), manifest, capture, po, nullptr, Timestamp::unset(),
                  Timestamp::unset(), fs::path("live"), session_name, {{"kind", "live"}}, nullptr,
                  replan);
}

Status add_to_summary(const fs::path& out_dir, const std::string& key,
                      const nlohmann::json& value) {
  const fs::path path = out_dir / "summary.json";
  nlohmann::json summary;
  {
    std::ifstream in(path);
    if (!in) return make_error(ErrorCode::kNotFound, "{}: not written", path.string());
    try {
      in >> summary;
    } catch (const nlohmann::json::exception& e) {
      return make_error(ErrorCode::kCorruptData, "{}: {}", path.string(), e.what());
    }
  }
  summary[key] = value;
  const fs::path partial = path.string() + ".partial";
  {
    std::ofstream f(partial);
    f << summary.dump(2) << "\n";
    if (!f) return make_error(ErrorCode::kIoError, "{}: cannot write", partial.string());
  }
  std::error_code ec;
  fs::rename(partial, path, ec);
  if (ec) return make_error(ErrorCode::kIoError, "{}: {}", path.string(), ec.message());
  return ok_status();
}

}  // namespace dreamsense::runner
