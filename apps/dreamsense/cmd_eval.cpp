// `dreamsense eval session SESSION [--analysis DIR] [--json FILE]`

#include "dreamsense/eval/session_eval.hpp"
#include "dreamsense/runner/analysis.hpp"

#include <cstdio>
#include <unistd.h>

#include "commands.hpp"

namespace dreamsense::app {

namespace {
struct EvalSessionFlags {
  std::string session, analysis, json;
};

void print_metrics(const nlohmann::json& j) {
  for (const auto& [k, v] : j["metrics"].items())
    if (!v.is_null()) std::fprintf(stderr, "  %-28s %s\n", k.c_str(), v.dump().c_str());
  std::fprintf(stderr, "  (%zu metrics not evaluated: see \"not_evaluated\")\n",
               j["not_evaluated"].size());
}
}  // namespace

void add_eval(CLI::App& app, const GlobalFlags& g, int& exit_code) {
  CLI::App* eval = app.add_subcommand("eval", "Standard-protocol evaluations (JSON of cli.md)");
  eval->require_subcommand(1);
  add_eval_calibration(*eval, g, exit_code);
  add_eval_doa(*eval, g, exit_code);
  add_eval_speech(*eval, g, exit_code);
  add_eval_eyes(*eval, g, exit_code);
  add_eval_voices(*eval, g, exit_code);
  add_eval_tracking(*eval, g, exit_code);  // cmd_objects.cpp
  add_eval_objects(*eval, g, exit_code);   // cmd_objects.cpp
  add_eval_actions(*eval, g, exit_code);   // cmd_actions.cpp

  add_eval_expression(*eval, g, exit_code);  // cmd_faces.cpp
  add_eval_faces(*eval, g, exit_code);       // cmd_faces.cpp

  auto flags = std::make_shared<EvalSessionFlags>();
  CLI::App* cmd = eval->add_subcommand(
      "session", "Compare an analysis of a session that has truth.jsonl with its truth");
  cmd->add_option("session", flags->session, "Session folder")->required();
  cmd->add_option("--analysis", flags->analysis,
                  "Folder with primitives.jsonl (default: analyse the session first)");
  cmd->add_option("--json", flags->json, "Write the evaluation JSON to FILE (- for stdout)");
  cmd->callback([flags, &g, &exit_code] {
    std::filesystem::path analysis = flags->analysis;
    std::filesystem::path temp;
    if (analysis.empty()) {
      temp = std::filesystem::temp_directory_path() /
             fmt::format("dreamsense-eval-{}", static_cast<long>(::getpid()));
      runner::AnalysisOptions a;
      a.session_dir = flags->session;
      a.out_dir = temp;
      auto r = run_analysis_with_progress(a, g.quiet);
      if (!r) {
        std::filesystem::remove_all(temp);
        exit_code = fail(r.error());
        return;
      }
      analysis = temp;
    }
    eval::SessionEvalOptions o{flags->session, analysis};
    auto r = eval::evaluate_session(o);
    if (!temp.empty()) std::filesystem::remove_all(temp);
    if (!r) {
      exit_code = fail(r.error());
      return;
    }
    if (!g.quiet) print_metrics(*r);
    if (auto s = write_json(flags->json, *r); !s) exit_code = fail(s.error());
  });
}

}  // namespace dreamsense::app
