// `dreamsense bench pipeline SESSION [--json FILE] [--no-live] [--pipeline FILE] [--set A.K=V]
// [--enable A] [--disable A]`

#include "dreamsense/runner/analysis.hpp"

#include <algorithm>
#include <cstdio>

#include "commands.hpp"

namespace dreamsense::app {
namespace {

struct BenchFlags {
  std::string session, json;
  bool no_live = false;
  PipelineFlags pipeline;  // the configuration measured (A/B of an option in one build)
};

double p95(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, v.size() * 95 / 100)];
}

}  // namespace

void add_bench(CLI::App& app, const GlobalFlags& g, int& exit_code) {
  CLI::App* bench = app.add_subcommand("bench", "Throughput and latency measurements");
  bench->require_subcommand(1);
  auto flags = std::make_shared<BenchFlags>();
  CLI::App* cmd = bench->add_subcommand(
      "pipeline",
      "Whole-pipeline speed on a session: a replay as fast as possible (fps, realtime factor, "
      "latency) and a real-time paced run with the live policy (dropped frames)");
  cmd->add_option("session", flags->session, "Session folder")->required();
  cmd->add_option("--json", flags->json, "Write the result JSON to FILE (- for stdout)");
  cmd->add_flag("--no-live", flags->no_live, "Skip the real-time paced run");
  add_pipeline_flags(*cmd, flags->pipeline);
  cmd->callback([flags, &g, &exit_code] {
    (void)g;
    runner::AnalysisOptions o;
    o.session_dir = flags->session;  // no out_dir: primitives are evaluated, nothing is written
    o.threads = flags->pipeline.threads;
    if (auto s = apply_pipeline_flags(flags->pipeline, o.plan); !s) {
      exit_code = fail(s.error());
      return;
    }
    auto replay = runner::analyze_session(o);
    if (!replay) {
      exit_code = fail(replay.error());
      return;
    }
    const auto& p = replay->pipeline;
    const double fps = p.wall_seconds > 0 ? p.ticks / p.wall_seconds : 0;
    nlohmann::json metrics = {
        {"fps", fps},
        {"realtime_factor", p.wall_seconds > 0 ? p.media_seconds / p.wall_seconds : 0},
        {"latency_p95_ms", p95(p.tick_latency_ms)},
        {"dropped_frames", nullptr},
        {"ticks", p.ticks},
        {"frames", p.frames}};
    nlohmann::json live_json = nullptr;
    if (!flags->no_live) {
      runner::AnalysisOptions lo = o;
      lo.policy = SyncPolicy::kLatestWithinTolerance;
      lo.pace_source = true;
      auto live = runner::analyze_session(lo);
      if (!live) {
        exit_code = fail(live.error());
        return;
      }
      const auto& l = live->pipeline;
      metrics["dropped_frames"] = l.sync.dropped_frames();
      live_json = {{"ticks", l.ticks},
                   {"ticks_dropped", l.sync.ticks_dropped},
                   {"dropped_frames", l.sync.dropped_frames()},
                   {"latency_p95_ms", p95(l.tick_latency_ms)}};
    }
    nlohmann::json out = {
        {"task", "pipeline"},
        {"dataset", {{"name", flags->session}, {"items", p.ticks}}},
        {"protocol",
         "replay (settled policy, as fast as possible) for fps, "
         "realtime_factor and latency; real-time paced replay with "
         "the live policy for dropped_frames"},
        {"metrics", metrics},
        {"timing", {{"replay_wall_seconds", p.wall_seconds}, {"threads", p.threads}}},
        {"per_class", nlohmann::json::object()},
        {"stages", replay->to_json()["stages"]},
        {"live", live_json}};
    std::fprintf(
        stderr, "fps %.1f, realtime factor %.1f, latency p95 %.2f ms, dropped %s, threads %d\n",
        fps, metrics["realtime_factor"].get<double>(), metrics["latency_p95_ms"].get<double>(),
        metrics["dropped_frames"].dump().c_str(), p.threads);
    if (auto s = write_json(flags->json, out); !s) exit_code = fail(s.error());
  });
}

}  // namespace dreamsense::app
