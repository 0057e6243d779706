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
  cmd->callback([flags, &g, &exit_code] {
    runner::AnalysisOptions o;
    o.session_dir = flags->session;
    o.out_dir = flags->out;
    o.policy = flags->policy == "live" ? SyncPolicy::kLatestWithinTolerance : SyncPolicy::kSettled;
    o.speech_grammar = flags->grammar;
    auto r = run_analysis_with_progress(o, g.quiet);
    if (!r) {
      exit_code = fail(r.error());
      return;
    }
    print_summary(*r, o.out_dir);
  });
}

}  // namespace dreamsense::app
