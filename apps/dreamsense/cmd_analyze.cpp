// `dreamsense analyze SESSION --out DIR`

#include "dreamsense/core/log.hpp"
#include "dreamsense/live/live_analysis.hpp"
#include "dreamsense/primitives/catalogue.hpp"
#include "dreamsense/runner/analysis.hpp"

#include <cstdio>
#include <optional>

#include "commands.hpp"
#include "progress.hpp"

namespace dreamsense::app {
namespace {

struct AnalyzeFlags {
  std::string session, out;
  std::string config, record;             // live
  double duration_s = 0;                  // live
  std::string publish;                    // live: "dds"
  int dds_domain = 0;                     // live
  bool dds_json = false;                  // live: also the JSON-string topics
  std::vector<std::string> publish_only;  // live
  bool publish_all_statuses = false;      // live
  bool dds_network = false;               // live
  int ui_port = -1;                       // live: operator page (-1: none)
  std::string ui_host = "127.0.0.1";
  std::string policy = "settled";
  std::string grammar;
  bool overlay = false;
  bool overlay_mosaic = false;
  bool force = false;  // replace an earlier analysis in the output folder
  bool allow_damaged = false;
  bool follow_links = false;
  bool include_names = false;  // privacy: names of speakers, faces, the session (default: ids)
  bool blur_faces = false;     // privacy: faces pixelated in overlay.mp4 and the key frames
  SubjectFlags subject;
  std::string mutual_mode;
  std::vector<double> robot_head;
  std::string voice_method, voice_model;
  PipelineFlags pipeline;
  bool print_pipeline = false;       // analyze: show the graph and stop
  bool save_subject = false;         // analyze: keep a converged self-calibration as the subject's
  std::string calibration;           // analyze VIDEO: intrinsics instead of the approximate ones
  bool csv = false, no_csv = false;  // analyze: CSV tables (default: on for a video)
};

void print_summary(const runner::AnalysisSummary& s, const std::filesystem::path& out) {
  const auto& p = s.pipeline;
  std::fprintf(stderr, "analysed %.1f s of session time in %.2f s (%.1fx real time), %llu ticks\n",
               p.media_seconds, p.wall_seconds,
               p.wall_seconds > 0 ? p.media_seconds / p.wall_seconds : 0.0,
               static_cast<unsigned long long>(p.ticks));
  if (s.input.value("kind", "") == "video")
    std::fprintf(stderr, "video %dx%d: %s; audio %s\n", s.input.value("width", 0),
                 s.input.value("height", 0),
                 s.input.value("approximate_calibration", false)
                     ? fmt::format("APPROXIMATE intrinsics (fx = {:.0f} px from the image size; "
                                   "--calibration FILE for exact 3-D)",
                                   s.input.value("fx_px", 0.0))
                           .c_str()
                     : ("calibration " + s.input.value("calibration", std::string())).c_str(),
                 s.input.value("audio", std::string()).c_str());
  std::string names;
  for (const auto& a : s.analyzers) names += (names.empty() ? "" : ", ") + a;
  std::fprintf(stderr, "analysers: %s\n",
               names.empty() ? "(none for this session's streams)" : names.c_str());
  for (const auto& info : primitives::catalogue()) {
    auto it = s.status_counts.find(info.name);
    if (it == s.status_counts.end()) continue;
    std::string line;
    for (const auto& [status, n] : it->second) line += fmt::format(" {}={}", status, n);
    std::fprintf(stderr, "  %-4s %-24s%s\n", info.code, info.name, line.c_str());
  }
  if (!out.empty()) std::fprintf(stderr, "outputs in %s\n", out.string().c_str());
}

// Analysis flags shared by analyze and live. Each analyser option flag is a shorthand for one
// option of the declared pipeline (docs/pipeline.md), set over pipeline.yaml's value.
void add_analysis_flags(CLI::App& cmd, AnalyzeFlags& flags) {
  add_pipeline_flags(cmd, flags.pipeline);
  cmd.add_option("--grammar", flags.grammar,
                 "Speech grammar (JSGF or SRGS .grxml); default: the session's own, if any "
                 "(= --set speech.grammar=FILE)")
      ->check(CLI::ExistingFile);
  cmd.add_flag("--overlay", flags.overlay,
               "Also write overlay.mp4 (H.264): the selected camera with face boxes, landmarks, "
               "head axes, eye centres, gaze rays, mutual gaze, skeleton, sound direction, "
               "gesture, speech subtitles and a legend");
  cmd.add_flag("--overlay-mosaic", flags.overlay_mosaic,
               "overlay.mp4 shows every colour camera tiled, not only the selected one "
               "(implies --overlay)");
  cmd.add_flag("--force", flags.force,
               "Replace an earlier analysis in the output folder (all of its files; without "
               "this an output folder that holds one is an error)");
  cmd.add_flag("--allow-damaged", flags.allow_damaged,
               "Analyse streams even when more than 20 % of their records are damaged (the "
               "damage is reported in summary.json and the report either way)");
  cmd.add_flag("--follow-links", flags.follow_links,
               "Read session files that are symbolic links to files outside the session folder "
               "(refused by default)");
  cmd.add_flag("--include-names", flags.include_names,
               "Also write people's names: enrolment folder names of speakers (identifyVoice "
               "name), face gallery names (identifyFace name), the session's own name. Default: "
               "ids only (speaker_1, child, therapist, gallery ids; the session folder's name; "
               "session.yaml metadata is never written; docs/outputs.md)");
  cmd.add_flag("--blur-faces", flags.blur_faces,
               "Pixelate the faces (detections, landmarks, face tracks) in every picture "
               "written: overlay.mp4, the report's key frames (and live's operator page)");
  add_subject_flags(cmd, flags.subject);
  cmd.add_option("--mutual-gaze", flags.mutual_mode,
                 "Mutual-gaze test: 3d (ray within 0.2 m of the robot head) or camera-plane "
                 "(DREAM's rectangle on the selected camera's plane)")
      ->check(CLI::IsMember({"3d", "camera-plane"}));
  cmd.add_option("--robot-head", flags.robot_head,
                 "Robot head position in world metres, X Y Z (default: the session's "
                 "robot_head_m metadata)")
      ->expected(3);
  cmd.add_option("--voice-method", flags.voice_method,
                 "identifyVoice: gmm_ubm (speaker models: --voice-model, or trained from the "
                 "session's enrolment audio), direction_rule (DREAM's sound-direction rule) "
                 "or off")
      ->check(CLI::IsMember({"gmm_ubm", "direction_rule", "off"}));
  cmd.add_option("--voice-model", flags.voice_model,
                 "Voice model from `dreamsense train voices` (gmm_ubm)")
      ->check(CLI::ExistingFile);
}

Status apply_analysis_flags(const AnalyzeFlags& flags, runner::AnalysisOptions& o) {
  o.overlay = flags.overlay || flags.overlay_mosaic;
  o.overlay_mosaic = flags.overlay_mosaic;
  o.replace_existing = flags.force;
  o.allow_damaged = flags.allow_damaged;
  o.follow_links_outside = flags.follow_links;
  o.plan.include_names = flags.include_names;
  o.blur_faces = flags.blur_faces;
  apply_subject_flags(flags.subject, o);
  o.policy = flags.policy == "live" ? SyncPolicy::kLatestWithinTolerance : SyncPolicy::kSettled;
  o.threads = flags.pipeline.threads;
  runner::PlanOptions& plan = o.plan;
  auto set = [&plan](std::string analyzer, std::string key, std::string value) {
    plan.overrides.push_back({std::move(analyzer), std::move(key), std::move(value)});
  };
  auto quoted_path = [](const std::string& p) {
    return nlohmann::json(std::filesystem::absolute(p).string()).dump();  // YAML accepts JSON
  };
  if (!flags.mutual_mode.empty())
    set("gaze", "mutual.mode", flags.mutual_mode == "camera-plane" ? "camera_plane" : "3d");
  if (flags.robot_head.size() == 3)
    set("gaze", "mutual.robot_head_m",
        fmt::format("[{}, {}, {}]", flags.robot_head[0], flags.robot_head[1], flags.robot_head[2]));
  if (!flags.grammar.empty()) set("speech", "grammar", quoted_path(flags.grammar));
  if (flags.voice_method == "off")
    plan.enable["voice_id"] = false;
  else if (!flags.voice_method.empty())
    set("voice_id", "method", flags.voice_method);
  if (!flags.voice_model.empty()) set("voice_id", "model", quoted_path(flags.voice_model));
  return apply_pipeline_flags(flags.pipeline, plan);
}

}  // namespace

void add_pipeline_flags(CLI::App& cmd, PipelineFlags& flags) {
  cmd.add_option("--pipeline", flags.pipeline,
                 "pipeline.yaml: analysers on/off, their options, stream roles (docs/pipeline.md)")
      ->check(CLI::ExistingFile);
  cmd.add_option("--set", flags.set,
                 "Set an analyser option, ANALYSER.KEY=VALUE (YAML value; repeatable), e.g. "
                 "gaze.mutual.radius_m=0.25");
  cmd.add_option("--enable", flags.enable, "Run these analysers (names as --print-pipeline shows)");
  cmd.add_option("--disable", flags.disable, "Do not run these analysers");
  cmd.add_option("--threads", flags.threads,
                 "Threads that run each tick's analysers (those that share no blackboard key run "
                 "at the same time; the results do not depend on it); 0: 1 below 4 cores, else "
                 "the cores less one, at most 4")
      ->check(CLI::Range(0, PipelineOptions::kMaxThreads));
}

// After the verb's own shorthands (so that an explicit --set wins over them).
Status apply_pipeline_flags(const PipelineFlags& flags, runner::PlanOptions& plan) {
  plan.pipeline_file = flags.pipeline;
  for (const auto& kv : flags.set) {
    const auto eq = kv.find('=');
    const auto dot = kv.find('.');
    if (eq == std::string::npos || dot == std::string::npos || dot > eq || dot == 0 ||
        eq == dot + 1)
      return make_error(ErrorCode::kInvalidArgument,
                        "--set {}: expected ANALYSER.KEY=VALUE (e.g. gaze.mutual.radius_m=0.25)",
                        kv);
    plan.overrides.push_back(
        {kv.substr(0, dot), kv.substr(dot + 1, eq - dot - 1), kv.substr(eq + 1)});
  }
  for (const auto& n : flags.enable) plan.enable[n] = true;
  for (const auto& n : flags.disable) plan.enable[n] = false;
  return ok_status();
}

Result<runner::AnalysisSummary> run_analysis_with_progress(const runner::AnalysisOptions& o,
                                                           bool quiet) {
  return run_analysis_with_progress(o, quiet, SelfCalibrationMode::kWhenNoSubject);
}

namespace {

// The self-calibration of session `o` (writes OUT/self_calibration/, points `o` at its files),
// its progress lines on stderr unless quiet.
Result<nlohmann::json> self_calibrate_with_progress(runner::AnalysisOptions& o,
                                                    SelfCalibrationMode mode,
                                                    std::vector<runner::OptionOverride> overrides,
                                                    bool save_subject, bool quiet) {
  self_calibration::ForAnalysisOptions so;
  so.overrides = std::move(overrides);
  so.mode = mode;
  so.save_subject = save_subject;
  if (!quiet)
    so.progress = [](const std::string& line) { std::fprintf(stderr, "%s\n", line.c_str()); };
  return self_calibration::self_calibrate_for_analysis(o, so);
}

}  // namespace

Result<runner::AnalysisSummary> run_analysis_with_progress(const runner::AnalysisOptions& o_in,
                                                           bool quiet, SelfCalibrationMode mode,
                                                           bool save_subject) {
  runner::AnalysisOptions o = o_in;
  std::optional<nlohmann::json> calibration_status;
  auto self_calibration_overrides =
      self_calibration::take_self_calibration_overrides(o.plan.overrides);
  if (!o.out_dir.empty() && self_calibration::needs_self_calibration(o, mode)) {
    DS_ASSIGN_OR_RETURN(calibration_status,
                        self_calibrate_with_progress(o, mode, std::move(self_calibration_overrides),
                                                     save_subject, quiet));
  } else {
    if (!self_calibration_overrides.empty())
      log::info(
          "--set self_calibration.{}: no self-calibration in this analysis (a subject "
          "folder or model files are given), the option is not used",
          self_calibration_overrides.front().key);
    if (save_subject && !quiet)
      std::fprintf(stderr,
                   "--save-subject: nothing saved (no self-calibration in this analysis: the "
                   "subject has a calibration folder, model files or --subject none were given, "
                   "or the session has no calibrated camera)\n");
  }
  if (calibration_status)
    o.report_calibration = [status = *calibration_status] {
      return self_calibration::report_lines(status);
    };
  auto r = with_progress(
      "analyse", quiet, [&](const auto& progress) { return runner::analyze_session(o, progress); });
  if (r && calibration_status) {
    DS_RETURN_IF_ERROR(self_calibration::save_learnt_fixation_yaw(*calibration_status, *r));
    DS_RETURN_IF_ERROR(runner::add_to_summary(o.out_dir, "self_calibration", *calibration_status));
  }
  return r;
}

void add_subject_flags(CLI::App& cmd, SubjectFlags& flags) {
  cmd.add_option("--subject", flags.subject,
                 "The child's calibration folder (face_model.yaml, gaze.yaml, speech_model/), "
                 "'none' (generic face model, built-in gaze constants) or 'auto' (self-calibrate "
                 "from the session itself; live: during the session, generic models until it "
                 "converges); default: data/subjects/<the session's metadata subject> if it "
                 "exists, else auto")
      ->check(CLI::ExistingDirectory | CLI::IsMember({"none", "auto"}));
  cmd.add_option("--face-model", flags.face_model,
                 "3-D face model from `dreamsense train face` (overrides the subject's)")
      ->check(CLI::ExistingFile);
  cmd.add_option("--gaze-model", flags.gaze_model,
                 "Gaze constants from `dreamsense train gaze` (overrides the subject's; "
                 "default: built in)")
      ->check(CLI::ExistingFile);
  cmd.add_option("--speech-model", flags.speech_model,
                 "Acoustic model folder for recognizeSpeech, e.g. adapted to the child by "
                 "`dreamsense train speech` (overrides the subject's; default: en-us)")
      ->check(CLI::ExistingDirectory);
  cmd.add_option("--subjects-dir", flags.subjects_dir,
                 "Where the children's calibration folders are found (<dir>/<metadata subject>) "
                 "and --save-subject writes them (default: data/subjects of this installation)")
      ->check(CLI::ExistingDirectory);
}

void apply_subject_flags(const SubjectFlags& flags, runner::AnalysisOptions& o) {
  if (flags.subject == "none" || flags.subject == "auto")
    o.plan.subject_from_session = false;
  else
    o.plan.subject_dir = flags.subject;
  o.plan.face_model = flags.face_model;
  o.plan.gaze_model = flags.gaze_model;
  o.plan.speech_model = flags.speech_model;
  if (!flags.subjects_dir.empty()) o.plan.subjects_dir = flags.subjects_dir;
}

void add_analyze(CLI::App& app, const GlobalFlags& g, int& exit_code) {
  auto flags = std::make_shared<AnalyzeFlags>();
  CLI::App* cmd = app.add_subcommand(
      "analyze",
      "Offline analysis of a recorded session or of a plain video (a one-camera session made on "
      "the fly): primitives.jsonl, events.log, dream.json, report.html, summary.json, CSV tables");
  cmd->add_option("session", flags->session,
                  "Session folder (with session.yaml), or a video file (.mp4, .avi, ... anything "
                  "OpenCV/FFmpeg reads; docs/video_input.md)")
      ->required();
  cmd->add_option("--calibration", flags->calibration,
                  "Video input: camera intrinsics (CameraModel YAML from `dreamsense calibrate "
                  "intrinsics`) instead of the approximate ones (fx = 500 * width / 640)")
      ->check(CLI::ExistingFile);
  cmd->add_flag("--csv", flags->csv,
                "Also write OUT/tables/: one CSV per primitive, events.csv (docs/outputs.md); "
                "default: on for a video, off for a session");
  cmd->add_flag("--no-csv", flags->no_csv, "Do not write the CSV tables")->excludes("--csv");
  cmd->add_option("--out", flags->out,
                  "Output folder (created if needed; required unless --print-pipeline)");
  cmd->add_option("--policy", flags->policy,
                  "Synchronisation: settled (deterministic replay) or live (real-time, drops)")
      ->check(CLI::IsMember({"settled", "live"}));
  cmd->add_flag("--print-pipeline", flags->print_pipeline,
                "Print the analysis graph this session gets (streams and roles, analysers in "
                "order with their inputs, reads, writes and options) and stop");
  add_analysis_flags(*cmd, *flags);
  cmd->add_flag("--save-subject", flags->save_subject,
                "When the self-calibration converges, also save it as the session's subject "
                "folder (data/subjects/<metadata subject>, must not exist) for the next session, "
                "with the gaze's sideways correction learnt in this one");
  cmd->callback([flags, &g, &exit_code] {
    runner::AnalysisOptions o;
    o.session_dir = flags->session;
    o.out_dir = flags->out;
    o.calibration = flags->calibration;
    if (flags->csv) o.csv = true;
    if (flags->no_csv) o.csv = false;
    if (auto s = apply_analysis_flags(*flags, o); !s) {
      exit_code = fail(s.error());
      return;
    }
    if (flags->print_pipeline) {
      auto plan = runner::plan_session(o);
      if (!plan) {
        exit_code = fail(plan.error());
        return;
      }
      std::fputs(plan->describe().c_str(), stdout);
      return;
    }
    if (flags->out.empty()) {
      exit_code = fail("analyze: --out DIR is required");
      return;
    }
    auto r = run_analysis_with_progress(o, g.quiet, self_calibration_mode(flags->subject),
                                        flags->save_subject);
    if (!r) {
      exit_code = fail(r.error());
      return;
    }
    if (!g.quiet) print_summary(*r, o.out_dir);
  });
}

namespace {

// `live --record R --save-subject`: after the session the recording is self-calibrated (every
// searched tick, none skipped for lack of CPU as during the session) and saved as the subject's
// folder for the next session, and its status added to the live summary.json.
Status save_subject_from_recording(const runner::AnalysisOptions& live,
                                   const std::filesystem::path& recording, SelfCalibrationMode mode,
                                   std::vector<runner::OptionOverride> overrides, bool quiet) {
  runner::AnalysisOptions o = live;
  o.session_dir = recording;
  // The live self-calibration's own keys (live_nice, live_attempts) do not apply here.
  std::erase_if(overrides,
                [](const runner::OptionOverride& k) { return k.key.rfind("live_", 0) == 0; });
  if (!self_calibration::needs_self_calibration(o, mode)) {
    if (!quiet)
      std::fprintf(stderr,
                   "--save-subject: nothing saved (the subject has a calibration folder or model "
                   "files were given, or the recording has no calibrated camera)\n");
    return ok_status();
  }
  DS_ASSIGN_OR_RETURN(const nlohmann::json status,
                      self_calibrate_with_progress(o, mode, std::move(overrides), true, quiet));
  if (!quiet && status.contains("saved_to"))
    std::fprintf(stderr, "subject saved to %s\n", status["saved_to"].get<std::string>().c_str());
  return runner::add_to_summary(live.out_dir, "self_calibration", status);
}

}  // namespace

void add_live(CLI::App& app, const GlobalFlags& g, int& exit_code) {
  auto flags = std::make_shared<AnalyzeFlags>();
  CLI::App* cmd = app.add_subcommand(
      "live",
      "Live analysis of cameras and the microphone array (docs/recording.md): the outputs of "
      "analyze, written as the session runs; --record also records it");
  cmd->add_option("--config", flags->config,
                  "Device configuration (YAML: session, cameras, audio; docs/recording.md)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--out", flags->out, "Output folder (created if needed)")->required();
  cmd->add_option("--record", flags->record, "Also record the session into this new folder");
  cmd->add_option(
         "--duration", flags->duration_s,
         "Stop after this many seconds of analysis, counted from when the analysers are ready "
         "(default: until Ctrl-C or SIGTERM)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--publish", flags->publish,
                  "Publish the primitives as they are produced: dds (typed ROS 2 messages on "
                  "ROS4HRI topics /humans/faces/..., /humans/voices/... and "
                  "/dreamsense/mutual_gaze; publish/README.md)")
      ->check(CLI::IsMember({"dds"}));
  cmd->add_flag("--dds-json", flags->dds_json,
                "Also publish every primitive as JSON on rt/dreamsense/<primitive> "
                "(std_msgs/String holding the primitives.jsonl line)");
  cmd->add_option("--publish-only", flags->publish_only,
                  "Publish only these primitives (names as in primitives.jsonl)")
      ->delimiter(',');
  cmd->add_flag("--publish-all-statuses", flags->publish_all_statuses,
                "JSON topics: also publish records that are not ok (no_data, disabled, ...)");
  cmd->add_option("--dds-domain", flags->dds_domain, "DDS domain (ROS_DOMAIN_ID)")
      ->default_val(0)
      ->check(CLI::Range(0, 232));
  cmd->add_flag("--dds-network", flags->dds_network,
                "Publish on every network interface (default: this machine only)");
  cmd->add_option("--ui", flags->ui_port,
                  "Serve the operator page on this port (0: any free port): cameras with face "
                  "boxes, mutual gaze, last utterance, gesture, status strip, Mark button (key M) "
                  "writing markers into the session (ui/README.md)")
      ->check(CLI::Range(0, 65535));
  cmd->add_option("--ui-host", flags->ui_host,
                  "Address the operator page listens on (default 127.0.0.1: this machine only; "
                  "any other address needs the access token printed with the URL)")
      ->default_val(flags->ui_host);
  add_analysis_flags(*cmd, *flags);
  cmd->add_flag("--save-subject", flags->save_subject,
                "Save the child's self-calibrated face and eyes as the subject folder (<subjects "
                "dir>/<metadata subject>, must not exist), so that the next session starts "
                "calibrated: with --record, self-calibrated from the recording after the "
                "session; without, the live self-calibration's result when it converged");
  cmd->callback([flags, &g, &exit_code] {
    live::LiveAnalysisOptions lo;
    lo.analysis.out_dir = flags->out;
    if (auto s = apply_analysis_flags(*flags, lo.analysis); !s) {
      exit_code = fail(s.error());
      return;
    }
    if (flags->save_subject && flags->record.empty() && flags->subject.subject == "none") {
      exit_code = fail(
          "live: --save-subject needs --record or the live self-calibration (not with --subject "
          "none)");
      return;
    }
    // Without a recording the live self-calibration's own result is what can be saved.
    lo.save_live_self_calibration = flags->save_subject && flags->record.empty();
    // The planner knows only analysers: `--set self_calibration.K=V` is for the live
    // self-calibration and --save-subject.
    auto self_calibration_overrides =
        self_calibration::take_self_calibration_overrides(lo.analysis.plan.overrides);
    lo.self_calibration = self_calibration_mode(flags->subject);
    lo.self_calibration_overrides = self_calibration_overrides;
    lo.config = flags->config;
    if (!flags->record.empty()) lo.record = flags->record;
    lo.duration_s = flags->duration_s;
    if (flags->publish == "dds") {
      publish::DdsPublisherOptions po;
      po.domain_id = flags->dds_domain;
      po.network = flags->dds_network;
      po.json_topics = flags->dds_json;
      po.only = {flags->publish_only.begin(), flags->publish_only.end()};
      po.all_statuses = flags->publish_all_statuses;
      if (auto s = po.check(); !s) {
        exit_code = fail(s.error());
        return;
      }
      lo.dds = po;
    }
    if (flags->ui_port >= 0) {
      ui::OperatorPageOptions uo;
      uo.port = flags->ui_port;
      uo.host = flags->ui_host;
      uo.blur_faces = flags->blur_faces;
      lo.ui = uo;
    }
    lo.on_ui_started = [](const std::string& url) {
      std::fprintf(stderr, "operator page: %s\n", url.c_str());
    };
    lo.on_capture_started = [&] {
      if (!g.quiet)
        std::fprintf(stderr, "live analysis into %s%s (%s)\n", flags->out.c_str(),
                     lo.record ? (" recording into " + lo.record->string()).c_str() : "",
                     flags->duration_s > 0 ? fmt::format("{} s", flags->duration_s).c_str()
                                           : "Ctrl-C to stop");
    };
    auto r = live::run_live_analysis(lo);
    if (!r) {
      exit_code = fail(r.error());
      return;
    }
    if (!g.quiet) {
      print_summary(r->analysis, lo.analysis.out_dir);
      if (r->self_calibration) {
        const nlohmann::json& c = *r->self_calibration;
        std::fprintf(stderr, "  self-calibration during the session: %s%s\n",
                     c.value("state", "").c_str(),
                     c.value("used_from_ns", nlohmann::json()).is_number()
                         ? fmt::format(" ({:.1f} s of the session searched); the child's "
                                       "models used from then on",
                                       c.value("seconds_searched", 0.0))
                               .c_str()
                         : "");
      }
      for (const auto& [id, st] : r->capture.streams)
        std::fprintf(stderr, "  %s: %llu frames captured, %llu dropped, %llu overruns\n",
                     id.c_str(), static_cast<unsigned long long>(st.frames_written),
                     static_cast<unsigned long long>(st.frames_dropped),
                     static_cast<unsigned long long>(st.overruns));
      if (r->dds)
        std::fprintf(stderr, "DDS: %llu messages published, %llu refused\n",
                     static_cast<unsigned long long>(r->dds->published),
                     static_cast<unsigned long long>(r->dds->failed));
    }
    // A device lost mid-session: the analysis went on without it (stream offline); the exit
    // status says so.
    if (auto lost = sources::lost_devices(r->capture); !lost) exit_code = fail(lost.error());
    if (lo.save_live_self_calibration && !g.quiet) {
      const nlohmann::json c = r->self_calibration.value_or(nlohmann::json::object());
      if (c.contains("saved_to"))
        std::fprintf(stderr, "subject saved to %s\n", c["saved_to"].get<std::string>().c_str());
      else
        std::fprintf(stderr, "--save-subject: nothing saved (%s)\n",
                     r->self_calibration ? "the live self-calibration did not converge"
                                         : "no live self-calibration: the subject has a "
                                           "calibration folder or model files were given");
    }
    if (flags->save_subject && !flags->record.empty()) {
      if (auto s = save_subject_from_recording(lo.analysis, flags->record,
                                               self_calibration_mode(flags->subject),
                                               std::move(self_calibration_overrides), g.quiet);
          !s)
        exit_code = fail(s.error());
    }
  });
}

}  // namespace dreamsense::app
