// `dreamsense analyze SESSION --out DIR`

#include "dreamsense/primitives/catalogue.hpp"
#include "dreamsense/runner/analysis.hpp"

#include <cstdio>

#include "commands.hpp"
#include "progress.hpp"

namespace dreamsense::app {
namespace {

struct AnalyzeFlags {
  std::string session, out;
  std::string policy = "settled";
  std::string grammar;
  bool overlay = false;
  SubjectFlags subject;
  std::string mutual_mode = "3d";
  std::vector<double> robot_head;
  std::string voice_method = "gmm_ubm", voice_model;
};

void print_summary(const runner::AnalysisSummary& s, const std::filesystem::path& out) {
  const auto& p = s.pipeline;
  std::fprintf(stderr, "analysed %.1f s of session time in %.2f s (%.1fx real time), %llu ticks\n",
               p.media_seconds, p.wall_seconds,
               p.wall_seconds > 0 ? p.media_seconds / p.wall_seconds : 0.0,
               static_cast<unsigned long long>(p.ticks));
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

}  // namespace

Result<runner::AnalysisSummary> run_analysis_with_progress(const runner::AnalysisOptions& o,
                                                           bool quiet) {
  return with_progress("analyse", quiet,
                       [&](const auto& progress) { return runner::analyze_session(o, progress); });
}

void add_subject_flags(CLI::App& cmd, SubjectFlags& flags) {
  cmd.add_option("--subject", flags.subject,
                 "The child's calibration folder (face_model.yaml, gaze.yaml), or 'none'; "
                 "default: data/subjects/<the session's metadata subject>, if it exists")
      ->check(CLI::ExistingDirectory | CLI::IsMember({"none"}));
  cmd.add_option("--face-model", flags.face_model,
                 "3-D face model from `dreamsense train face` (overrides the subject's)")
      ->check(CLI::ExistingFile);
  cmd.add_option("--gaze-model", flags.gaze_model,
                 "Gaze constants from `dreamsense train gaze` (overrides the subject's; "
                 "default: built in)")
      ->check(CLI::ExistingFile);
}

void apply_subject_flags(const SubjectFlags& flags, runner::AnalysisOptions& o) {
  if (flags.subject == "none")
    o.subject_from_session = false;
  else
    o.subject_dir = flags.subject;
  o.face_model = flags.face_model;
  o.gaze_model = flags.gaze_model;
}

void add_analyze(CLI::App& app, const GlobalFlags& g, int& exit_code) {
  auto flags = std::make_shared<AnalyzeFlags>();
  CLI::App* cmd = app.add_subcommand(
      "analyze",
      "Offline analysis of a recorded session: primitives.jsonl, events.log, dream.json");
  cmd->add_option("session", flags->session, "Session folder (with session.yaml)")->required();
  cmd->add_option("--out", flags->out, "Output folder (created if needed)")->required();
  cmd->add_option("--policy", flags->policy,
                  "Synchronisation: settled (deterministic replay) or live (real-time, drops)")
      ->check(CLI::IsMember({"settled", "live"}));
  cmd->add_option("--grammar", flags->grammar,
                  "Speech grammar (JSGF or SRGS .grxml); default: the session's own, if any")
      ->check(CLI::ExistingFile);
  cmd->add_flag("--overlay", flags->overlay,
                "Also write overlay.mp4: the selected camera with face boxes, landmarks, head "
                "axes, eye centres, gaze rays and mutual gaze");
  add_subject_flags(*cmd, flags->subject);
  cmd->add_option("--mutual-gaze", flags->mutual_mode,
                  "Mutual-gaze test: 3d (ray within 0.2 m of the robot head) or camera-plane "
                  "(DREAM's rectangle on the selected camera's plane)")
      ->check(CLI::IsMember({"3d", "camera-plane"}));
  cmd->add_option("--robot-head", flags->robot_head,
                  "Robot head position in world metres, X Y Z (default: the session's "
                  "robot_head_m metadata)")
      ->expected(3);
  cmd->add_option("--voice-method", flags->voice_method,
                  "identifyVoice: gmm_ubm (speaker models: --voice-model, or trained from the "
                  "session's enrolment audio), direction_rule (DREAM's sound-direction rule) "
                  "or off")
      ->check(CLI::IsMember({"gmm_ubm", "direction_rule", "off"}));
  cmd->add_option("--voice-model", flags->voice_model,
                  "Voice model from `dreamsense train voices` (gmm_ubm)")
      ->check(CLI::ExistingFile);
  cmd->callback([flags, &g, &exit_code] {
    runner::AnalysisOptions o;
    o.session_dir = flags->session;
    o.out_dir = flags->out;
    o.overlay = flags->overlay;
    apply_subject_flags(flags->subject, o);
    if (flags->mutual_mode == "camera-plane")
      o.mutual_gaze.mode = gaze::MutualGazeMode::kCameraPlane;
    if (flags->robot_head.size() == 3) {
      o.mutual_gaze.robot_head_m = {flags->robot_head[0], flags->robot_head[1],
                                    flags->robot_head[2]};
      o.robot_head_from_session = false;
    }
    o.policy = flags->policy == "live" ? SyncPolicy::kLatestWithinTolerance : SyncPolicy::kSettled;
    o.speech_grammar = flags->grammar;
    o.voice_method = flags->voice_method;
    o.voice_model = flags->voice_model;
    auto r = run_analysis_with_progress(o, g.quiet);
    if (!r) {
      exit_code = fail(r.error());
      return;
    }
    print_summary(*r, o.out_dir);
  });
}

}  // namespace dreamsense::app
