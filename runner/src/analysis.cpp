#include "dreamsense/runner/analysis.hpp"

#include "dreamsense/core/log.hpp"
#include "dreamsense/core/output_file.hpp"
#include "dreamsense/dream/writers.hpp"
#include "dreamsense/export/csv_tables.hpp"
#include "dreamsense/export/overlay.hpp"
#include "dreamsense/export/report.hpp"
#include "dreamsense/export/writers.hpp"
#include "dreamsense/sources/recorder.hpp"
#include "dreamsense/sources/session.hpp"
#include "dreamsense/sources/video_file.hpp"

#include <algorithm>

namespace dreamsense::runner {
namespace fs = std::filesystem;

Status AnalysisOptions::check() const {
  if (session_dir.empty())
    return make_error(ErrorCode::kInvalidArgument, "analysis: no session folder given");
  DS_RETURN_IF_ERROR(plan.check());
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
          {"pipeline", plan},
          {"stages", stages},
          {"dropped_frames", pipeline.sync.dropped_frames()},
          {"status_counts", status_counts},
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

// A key frame for the report: the selected camera (getFaces' source, else the first child camera
// in the tick) with the analysis overlay, 480 pixels wide.
void add_key_frame(exporters::HtmlReport& report, const MultiFrame& tick,
                   const BlackboardView& view,
                   const std::vector<primitives::PrimitiveRecord>& records,
                   const std::map<SensorId, CameraModel>& cameras) {
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
  const int w = 480;
  const int h = std::max(2, image->image.rows * w / std::max(1, image->image.cols)) & ~1;
  report.add_key_frame(tick.stamp, camera,
                       exporters::draw_overlay(image->image, camera, tick, view, oo, {w, h}));
}

// Runs the planned analysers over `source` and writes the outputs (options.out_dir).
// [t0, t1] is the media span for progress (unset for live sources).
Result<AnalysisSummary> run_plan(const AnalysisOptions& options, PipelinePlan plan,
                                 const sources::SessionManifest& manifest, Source& source,
                                 const PipelineOptions& po, const AnalysisProgress& progress,
                                 Timestamp t0, Timestamp t1, const fs::path& error_dir,
                                 const std::string& session_name, nlohmann::json input) {
  AnalysisSummary summary;
  summary.input = std::move(input);
  for (const auto& a : plan.analyzers) summary.analyzers.emplace_back(a->name());
  summary.plan = plan.to_json();
  const auto overlay_cameras = child_cameras(plan);
  const auto& plan_cameras = overlay_cameras;
  primitives::Evaluator evaluator(options.evaluator, plan.key_sensors, plan.cameras);
  auto pipeline = Pipeline::build(po, source.info(), std::move(plan.analyzers));
  if (!pipeline) return tl::unexpected(pipeline.error());

  const bool write = !options.out_dir.empty();
  exporters::PrimitivesJsonlWriter jsonl;
  dream::EventLogWriter events;
  dream::DreamExport dream_export;
  exporters::HtmlReport report;
  report.set_span(t0, t1);
  if (write) {
    DS_RETURN_IF_ERROR(jsonl.open(options.out_dir / "primitives.jsonl"));
    DS_RETURN_IF_ERROR(events.open(options.out_dir / "events.log", manifest.clock_origin_unix_ns));
  }

  exporters::OverlayWriter overlay;
  const bool want_overlay = write && options.overlay && !overlay_cameras.empty();
  if (want_overlay) {
    exporters::OverlayOptions oo;
    oo.cameras = overlay_cameras;
    oo.fps = manifest.frame_rate > 0 ? manifest.frame_rate : 25.0;
    DS_RETURN_IF_ERROR(overlay.open(options.out_dir / "overlay.mp4", oo));
  }
  auto on_tick = [&](const MultiFrame& tick, const BlackboardView& view) -> Status {
    if (want_overlay) DS_RETURN_IF_ERROR(overlay.add(tick, view));
    if (options.on_tick_frames) options.on_tick_frames(tick);
    const auto records = evaluator.evaluate(tick, view);
    for (const auto& r : records)
      summary.status_counts[primitives::info(r.id).name][primitives::to_string(r.status)]++;
    if (options.on_records) DS_RETURN_IF_ERROR(options.on_records(records));
    if (!write) return ok_status();
    DS_RETURN_IF_ERROR(jsonl.write(records));
    DS_RETURN_IF_ERROR(events.write(records));
    report.add(records);
    if (report.wants_key_frame(tick.stamp))
      add_key_frame(report, tick, view, records, plan_cameras);
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

  if (write) {
    DS_RETURN_IF_ERROR(jsonl.commit());
    DS_RETURN_IF_ERROR(events.commit());
    if (want_overlay) DS_RETURN_IF_ERROR(overlay.commit());
    DS_RETURN_IF_ERROR(dream_export.write(options.out_dir / "dream.json", manifest));
    const auto& ps = (*pipeline)->stats();
    exporters::ReportContext rc;
    rc.input = summary.input;
    rc.plan = summary.plan;
    rc.analyzers = summary.analyzers;
    rc.ticks = ps.ticks;
    rc.dropped_frames = ps.sync.dropped_frames();
    rc.wall_seconds = ps.wall_seconds;
    DS_RETURN_IF_ERROR(report.write(options.out_dir / "report.html", manifest, rc));
    summary.outputs = {options.out_dir / "primitives.jsonl", options.out_dir / "events.log",
                       options.out_dir / "dream.json", options.out_dir / "report.html",
                       options.out_dir / "summary.json"};
    if (want_overlay) summary.outputs.push_back(options.out_dir / "overlay.mp4");
    if (options.csv.value_or(summary.input.value("kind", "") == "video")) {
      exporters::CsvTablesOptions co;
      co.approximate_calibration = summary.input.value("approximate_calibration", false);
      if (summary.input.value("kind", "") == "video") co.mutual_gaze_target = "the camera";
      auto tables = exporters::write_csv_tables(options.out_dir / "primitives.jsonl",
                                                options.out_dir / "tables", co);
      if (!tables) return tl::unexpected(tables.error());
      for (const auto& t : *tables) summary.outputs.push_back(t);
    }
    OutputFile f;
    DS_RETURN_IF_ERROR(f.open(options.out_dir / "summary.json"));
    nlohmann::json sj = summary.to_json();
    sj["session"] = session_name;
    DS_RETURN_IF_ERROR(f.write(sj.dump(2) + "\n"));
    DS_RETURN_IF_ERROR(f.commit());
  }
  return summary;
}

PipelineOptions pipeline_options(const sources::SessionManifest& manifest) {
  PipelineOptions po;
  po.sync.tick_period = period_from_rate(manifest.frame_rate > 0 ? manifest.frame_rate : 25.0);
  po.sync.tolerance = po.sync.tick_period / 2;
  return po;
}

// A plain video: its one-camera session, and the plan options with its assumed intrinsics.
struct VideoPlan {
  std::unique_ptr<sources::VideoFileSource> source;
  PlanOptions plan;
};

Result<VideoPlan> open_video(const AnalysisOptions& options) {
  sources::VideoFileOptions vo;
  vo.calibration = options.calibration;
  VideoPlan v;
  DS_ASSIGN_OR_RETURN(v.source, sources::VideoFileSource::open(options.session_dir, vo));
  const sources::VideoFileInfo& info = v.source->video();
  v.plan = options.plan;
  v.plan.absolute_paths_allowed = true;  // the stream's file is the video's absolute path
  if (info.approximate_calibration) v.plan.assumed_cameras[sources::kVideoStreamId] = info.camera;
  return v;
}

nlohmann::json video_input_json(const sources::VideoFileInfo& v) {
  return {{"kind", "video"},
          {"path", v.path.string()},
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
  if (!options.out_dir.empty()) DS_RETURN_IF_ERROR(ensure_writable_dir(options.out_dir));
  PipelineOptions po = pipeline_options(info.manifest);
  po.sync.policy = options.policy;
  po.sync.start = Timestamp::from_ns(0);
  po.pace_source = options.pace_source;
  const SourceInfo si = v.source->info();
  return run_plan(options, std::move(*plan), info.manifest, *v.source, po, progress, si.start,
                  si.end, fs::path(), info.path.string(), video_input_json(info));
}

}  // namespace

Result<PipelinePlan> plan_session(const AnalysisOptions& options) {
  DS_RETURN_IF_ERROR(options.check());
  if (is_video_input(options.session_dir)) {
    DS_ASSIGN_OR_RETURN(VideoPlan v, open_video(options));
    return plan_pipeline(v.plan, v.source->video().manifest, v.source->video().path.parent_path());
  }
  auto manifest = sources::read_manifest(options.session_dir);
  if (!manifest) return tl::unexpected(in_session(manifest.error(), options.session_dir));
  auto plan = plan_pipeline(options.plan, *manifest, options.session_dir);
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
  auto full = sources::SessionReader::open(options.session_dir);
  if (!full) return tl::unexpected(in_session(full.error(), options.session_dir));
  if (!options.out_dir.empty()) DS_RETURN_IF_ERROR(ensure_writable_dir(options.out_dir));
  const sources::SessionManifest manifest = (*full)->manifest();
  const SourceInfo full_info = (*full)->info();

  auto plan = plan_pipeline(options.plan, manifest, (*full)->dir());
  if (!plan) return tl::unexpected(plan.error());
  const std::vector<SensorId> used = plan->used;

  sources::SessionReaderOptions ro;
  ro.only = used;
  auto reader =
      used.empty() ? std::move(full) : sources::SessionReader::open(options.session_dir, ro);
  if (!reader) return tl::unexpected(in_session(reader.error(), options.session_dir));
  full = {};

  PipelineOptions po = pipeline_options(manifest);
  po.sync.policy = options.policy;
  po.sync.start = full_info.start;  // ticks on the session clock, whatever streams are read
  po.pace_source = options.pace_source;
  return run_plan(options, std::move(*plan), manifest, **reader, po, progress, full_info.start,
                  full_info.end, options.session_dir, fs::absolute(options.session_dir).string(),
                  {{"kind", "session"}, {"path", fs::absolute(options.session_dir).string()}});
}

Result<AnalysisSummary> analyze_live(const AnalysisOptions& options,
                                     sources::LiveCapture& capture) {
  DS_RETURN_IF_ERROR(options.plan.check());
  DS_RETURN_IF_ERROR(options.evaluator.check());
  if (!options.out_dir.empty()) DS_RETURN_IF_ERROR(ensure_writable_dir(options.out_dir));
  const sources::SessionManifest& manifest = capture.manifest();
  // The live manifest's file references are the operator's absolute paths.
  PlanOptions plan_options = options.plan;
  plan_options.absolute_paths_allowed = true;
  auto plan = plan_pipeline(plan_options, manifest, fs::current_path());
  if (!plan) return tl::unexpected(plan.error());
  PipelineOptions po = pipeline_options(manifest);
  po.sync.policy = SyncPolicy::kLatestWithinTolerance;
  po.pace_source = false;  // the devices deliver in real time
  return run_plan(options, std::move(*plan), manifest, capture, po, nullptr, Timestamp::unset(),
                  Timestamp::unset(), fs::path("live"), manifest.name, {{"kind", "live"}});
}

}  // namespace dreamsense::runner
