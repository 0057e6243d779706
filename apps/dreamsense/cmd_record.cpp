// `dreamsense record --config FILE --out DIR [--duration S]`: records a session from live
// cameras (OpenCV VideoCapture) and the microphone array (ALSA) until the duration has passed or
// Ctrl-C / SIGTERM (the session is then closed properly: complete: true).

#include "dreamsense/sources/recorder.hpp"

#include <csignal>
#include <cstdio>

#include "commands.hpp"

namespace dreamsense::app {
namespace {

std::atomic<bool> g_stop_recording{false};

extern "C" void on_stop_signal(int /*signal*/) { g_stop_recording = true; }

struct RecordFlags {
  std::string config, out;
  double duration_s = 0;
};

}  // namespace

void add_record(CLI::App& app, const GlobalFlags& g, int& exit_code) {
  auto flags = std::make_shared<RecordFlags>();
  CLI::App* cmd = app.add_subcommand(
      "record", "Record a session from live cameras and the microphone array (no analysis)");
  cmd->add_option("--config", flags->config,
                  "Recording configuration (YAML: session, cameras, audio; docs/recording.md)")
      ->required();
  cmd->add_option("--out", flags->out, "New session folder")->required();
  cmd->add_option("--duration", flags->duration_s,
                  "Stop after this many seconds (default: until Ctrl-C or SIGTERM)")
      ->check(CLI::NonNegativeNumber);
  cmd->callback([flags, &g, &exit_code] {
    auto config = sources::read_record_config(flags->config);
    if (!config) {
      exit_code = fail(config.error());
      return;
    }
    sources::RecordOptions o;
    if (flags->duration_s > 0) o.duration_s = flags->duration_s;
    o.stop = &g_stop_recording;
    std::signal(SIGINT, on_stop_signal);
    std::signal(SIGTERM, on_stop_signal);
    if (!g.quiet) {
      std::fprintf(stderr, "recording to %s (%s)\n", flags->out.c_str(),
                   flags->duration_s > 0 ? fmt::format("{} s", flags->duration_s).c_str()
                                         : "Ctrl-C to stop");
      o.progress = [](double elapsed) { std::fprintf(stderr, "\r%.0f s", elapsed); };
    }
    auto stats = sources::record_session(*config, flags->out, o);
    std::signal(SIGINT, SIG_DFL);
    std::signal(SIGTERM, SIG_DFL);
    if (!g.quiet) std::fprintf(stderr, "\n");
    if (!stats) {
      exit_code = fail(stats.error());
      return;
    }
    if (!g.quiet) {
      for (const auto& [id, s] : stats->streams)
        std::fprintf(stderr, "  %s: %llu frames written, %llu dropped, %llu overruns\n", id.c_str(),
                     static_cast<unsigned long long>(s.frames_written),
                     static_cast<unsigned long long>(s.frames_dropped),
                     static_cast<unsigned long long>(s.overruns));
      std::fprintf(stderr, "recorded %.1f s into %s\n", stats->duration_s, flags->out.c_str());
    }
    // A device lost mid-session: the recording is complete with what was captured, but a
    // script must not take it for a full one.
    if (auto lost = sources::lost_devices(*stats); !lost) exit_code = fail(lost.error());
  });
}

}  // namespace dreamsense::app
