// `dreamsense demo [--out DIR] [--seed N] [--duration S] [--gestures dream|dream6|classic]
// [--no-analyze] [--snr DB] [--child-voice-shift F] [--no-robot-voice] [--audio-only]`

#include "dreamsense/runner/analysis.hpp"
#include "dreamsense/sim/demo_children.hpp"
#include "dreamsense/sim/demo_session.hpp"

#include <cstdio>

#include "commands.hpp"
#include "progress.hpp"

namespace dreamsense::app {

namespace {
struct DemoFlags {
  std::string out;
  uint64_t seed = 1;
  double duration_s = 20;
  int child = -1;  // -1: chosen by the seed
  bool no_analyze = false;
  std::string gestures = "dream";  // dream (face in view), dream6, classic
  double snr_db = 20;
  double child_voice_shift = 1.0;
  bool no_robot_voice = false, audio_only = false;
};
}  // namespace

void add_demo(CLI::App& app, const GlobalFlags& g, int& exit_code) {
  auto flags = std::make_shared<DemoFlags>();
  CLI::App* cmd = app.add_subcommand(
      "demo",
      "Build the deterministic demo session (real media from Debian packages, exact ground "
      "truth) and analyse it");
  cmd->add_option("--out", flags->out,
                  "Folder for the session and its analysis (default: out/demo-seed-N)");
  cmd->add_option("--seed", flags->seed, "Scene variation: poses, paths, actions, speech placement")
      ->capture_default_str();
  cmd->add_option("--duration", flags->duration_s, "Session length in seconds")
      ->capture_default_str()
      ->check(CLI::Range(1.0, 600.0));
  cmd->add_option(
         "--child", flags->child,
         "Which demo child (0 = the original, whose calibration ships; sim/demo_children.hpp); "
         "default: 0 on odd seeds, 1 and 2 alternately on even seeds; 3 is held out: no seed "
         "shows it")
      ->check(CLI::Range(0, static_cast<int>(sim::demo_children().size()) - 1));
  cmd->add_flag("--no-analyze", flags->no_analyze, "Only build the session");
  cmd->add_option("--child-voice-shift", flags->child_voice_shift,
                  "Child-like voice: the child's clips (session and enrolment) played this many "
                  "times faster, pitch and formants raised alike (1 = as recorded; e.g. 1.3)")
      ->check(CLI::Range(0.5, 2.0));
  cmd->add_option("--snr", flags->snr_db,
                  "Speech to pink-noise ratio of the microphone audio, dB (while speech is on)")
      ->capture_default_str()
      ->check(CLI::Range(-19.0, 99.0));
  cmd->add_flag("--no-robot-voice", flags->no_robot_voice,
                "No robot voice (no robot prompts in the audio, no robot_audio reference stream): "
                "the demo before issue 16");
  cmd->add_flag("--audio-only", flags->audio_only,
                "Write only the audio streams (and the full truth): the same audio, fast");
  cmd->add_option("--gestures", flags->gestures,
                  "The child's gestures (F20): dream (wave, fly, hands_on_head, drive_car: "
                  "DREAM's gestures that leave the face in view), dream6 (also cover_eyes and "
                  "drink: hands over the face) or classic (wave, fly, hands_on_head: the demo "
                  "before issue 13)")
      ->check(CLI::IsMember({"dream", "dream6", "classic"}))
      ->capture_default_str();
  cmd->callback([flags, &g, &exit_code] {
    const std::filesystem::path out =
        flags->out.empty() ? std::filesystem::path("out") / fmt::format("demo-seed-{}", flags->seed)
                           : std::filesystem::path(flags->out);
    sim::DemoOptions o;
    o.out_dir = out;
    o.seed = flags->seed;
    o.duration_s = flags->duration_s;
    o.child = flags->child >= 0 ? flags->child : sim::demo_child_for_seed(flags->seed);
    o.overwrite = true;
    o.snr_db = flags->snr_db;
    o.child_voice_shift = flags->child_voice_shift;
    o.robot_voice = !flags->no_robot_voice;
    o.audio_only = flags->audio_only;
    if (flags->gestures == "classic")
      o.script.gestures = sim::DemoScriptOptions::GestureSet::kClassic;
    else if (flags->gestures == "dream6")
      o.script.gestures = sim::DemoScriptOptions::GestureSet::kDream;
    Result<sim::DemoSummary> demo = with_progress("generate", g.quiet, [&](const auto& progress) {
      return sim::generate_demo_session(o, progress);
    });
    if (!demo) {
      exit_code = fail(demo.error());
      return;
    }
    if (!g.quiet)
      std::fprintf(stderr, "demo session (seed %llu, child %d, %.0f s) written to %s in %.1f s\n",
                   static_cast<unsigned long long>(flags->seed), o.child, flags->duration_s,
                   out.string().c_str(), demo->generation_s);
    if (flags->no_analyze) return;
    // The analysis goes beside the session, so the one folder holds everything.
    runner::AnalysisOptions a;
    a.session_dir = out;
    a.out_dir = out;
    a.replace_existing = true;  // the demo rebuilds its folder (session and analysis) every time
    auto r = run_analysis_with_progress(a, g.quiet);
    if (!r) {
      exit_code = fail(r.error());
      return;
    }
    if (g.quiet) return;
    std::fprintf(
        stderr,
        "analysis: %llu ticks in %.2f s; primitives.jsonl, events.log, dream.json, report.html, "
        "summary.json in %s\n",
        static_cast<unsigned long long>(r->pipeline.ticks), r->pipeline.wall_seconds,
        out.string().c_str());
    std::fprintf(stderr, "compare with the truth: dreamsense eval session %s --analysis %s\n",
                 out.string().c_str(), out.string().c_str());
  });
}

}  // namespace dreamsense::app
