// `dreamsense eval session SESSION [--analysis DIR] [--json FILE] [--subject X] [--uncalibrated]`

#include "dreamsense/eval/session_eval.hpp"
#include "dreamsense/runner/analysis.hpp"

#include <cstdio>
#include <fstream>
#include <unistd.h>

#include "commands.hpp"

namespace dreamsense::app {

namespace {
struct EvalSessionFlags {
  std::string session, analysis, json;
  std::string subject;        // self-calibration (issue 15): analysis with --subject X
  bool uncalibrated = false;  // also the self-calibrated path, metrics suffixed _uncalibrated
};

// Analyses `session` into a temporary folder with the subject choice `subject` ("" = the
// default: the session's subject folder, else self-calibration; "auto"; "none"; a folder).
Result<std::filesystem::path> analyse_for_eval(const std::string& session,
                                               const std::string& subject, const char* tag,
                                               bool quiet) {
  const auto temp = std::filesystem::temp_directory_path() /
                    fmt::format("dreamsense-eval-{}-{}", static_cast<long>(::getpid()), tag);
  runner::AnalysisOptions a;
  a.session_dir = session;
  a.out_dir = temp;
  // Identity metrics compare with the truth's names (face gallery names, enrolment folders): the
  // analysis is private to this process and removed after scoring.
  a.plan.include_names = true;
  SubjectFlags sf;
  sf.subject = subject;
  if (!subject.empty()) apply_subject_flags(sf, a);
  auto r = run_analysis_with_progress(a, quiet, self_calibration_mode(sf));
  if (!r) {
    std::filesystem::remove_all(temp);
    return tl::unexpected(r.error());
  }
  return temp;
}

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
  add_eval_landmarks(*eval, g, exit_code);   // cmd_landmarks.cpp

  auto flags = std::make_shared<EvalSessionFlags>();
  CLI::App* cmd = eval->add_subcommand(
      "session", "Compare an analysis of a session that has truth.jsonl with its truth");
  cmd->add_option("session", flags->session, "Session folder")->required();
  cmd->add_option("--analysis", flags->analysis,
                  "Folder with primitives.jsonl (default: analyse the session first)");
  cmd->add_option("--json", flags->json, "Write the evaluation JSON to FILE (- for stdout)");
  cmd->add_option("--subject", flags->subject,
                  "When analysing the session first: the child's calibration folder, 'none' or "
                  "'auto' (self-calibration), as analyze --subject")
      ->check(CLI::ExistingDirectory | CLI::IsMember({"none", "auto"}));
  cmd->add_flag("--uncalibrated", flags->uncalibrated,
                "Also analyse with --subject auto (self-calibration from the session, no "
                "calibration recording) and add its metrics with the suffix _uncalibrated");
  cmd->callback([flags, &g, &exit_code] {
    std::filesystem::path analysis = flags->analysis;
    std::filesystem::path temp;
    if (analysis.empty()) {
      auto a = analyse_for_eval(flags->session, flags->subject, "main", g.quiet);
      if (!a) {
        exit_code = fail(a.error());
        return;
      }
      temp = analysis = *a;
    }
    eval::SessionEvalOptions o{flags->session, analysis};
    auto r = eval::evaluate_session(o);
    if (!temp.empty()) std::filesystem::remove_all(temp);
    if (!r) {
      exit_code = fail(r.error());
      return;
    }
    if (flags->uncalibrated) {
      auto a = analyse_for_eval(flags->session, "auto", "auto", g.quiet);
      if (!a) {
        exit_code = fail(a.error());
        return;
      }
      auto u = eval::evaluate_session({flags->session, *a});
      std::ifstream summary(*a / "summary.json");
      nlohmann::json sj = nlohmann::json::parse(summary, nullptr, false);
      std::filesystem::remove_all(*a);
      if (!u) {
        exit_code = fail(u.error());
        return;
      }
      for (const auto& [k, v] : (*u)["metrics"].items()) (*r)["metrics"][k + "_uncalibrated"] = v;
      if (!sj.is_discarded() && sj.contains("self_calibration"))
        (*r)["self_calibration"] = sj["self_calibration"];
    }
    if (!g.quiet) print_metrics(*r);
    if (auto s = write_json(flags->json, *r); !s) exit_code = fail(s.error());
  });
}

}  // namespace dreamsense::app
