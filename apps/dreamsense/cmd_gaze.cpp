// `dreamsense train gaze --session DIR [--analysis DIR] [--session ...] --out gaze.yaml`:
// fits D4.2 eq. (4)'s gaze constants from analysed sessions with known gaze targets (the demo).

#include "dreamsense/eval/gaze_fit.hpp"

#include <cstdio>

#include "commands.hpp"

namespace dreamsense::app {
namespace {
struct TrainGazeFlags {
  std::vector<std::string> sessions;
  std::vector<std::string> analyses;
  std::string out;
};
}  // namespace

void add_train_gaze(CLI::App& train, const GlobalFlags& g, int& exit_code) {
  auto flags = std::make_shared<TrainGazeFlags>();
  CLI::App* cmd = train.add_subcommand(
      "gaze",
      "Fit the eye-gaze constants (D4.2 eq. 4: gamma, epsilon, pupil rest offsets per eye) on "
      "sessions with truth gaze, e.g. demo seeds that you do not evaluate on");
  cmd->add_option("--session", flags->sessions, "Session folder with truth.jsonl (repeatable)")
      ->required();
  cmd->add_option("--analysis", flags->analyses,
                  "Its analysis folder, one per --session (default: analyse it now, with the "
                  "built-in gaze constants, into <session>/analysis-for-gaze-fit)");
  cmd->add_option("--out", flags->out, "Gaze model file to write (YAML)")->required();
  cmd->callback([flags, &g, &exit_code] {
    if (!flags->analyses.empty() && flags->analyses.size() != flags->sessions.size()) {
      exit_code = fail("train gaze: give one --analysis per --session, or none");
      return;
    }
    std::vector<eval::GazeFitInput> inputs;
    for (size_t i = 0; i < flags->sessions.size(); ++i) {
      eval::GazeFitInput in{flags->sessions[i], {}};
      if (!flags->analyses.empty()) {
        in.analysis_dir = flags->analyses[i];
      } else {
        runner::AnalysisOptions o;
        o.session_dir = in.session_dir;
        o.out_dir = in.session_dir / "analysis-for-gaze-fit";
        if (auto r = run_analysis_with_progress(o, g.quiet); !r) {
          exit_code = fail(r.error());
          return;
        }
        in.analysis_dir = o.out_dir;
      }
      inputs.push_back(in);
    }
    auto model = eval::fit_gaze_model(inputs);
    if (!model) {
      exit_code = fail(model.error());
      return;
    }
    if (auto s = gaze::write_gaze_model(flags->out, *model); !s) {
      exit_code = fail(s.error());
      return;
    }
    if (!g.quiet)
      std::fprintf(stderr,
                   "gaze model (%d eye samples) written to %s\n"
                   "  right eye: gamma %.3f epsilon %.3f rest (%.4f, %.4f)\n"
                   "  left eye:  gamma %.3f epsilon %.3f rest (%.4f, %.4f)\n",
                   model->samples, flags->out.c_str(), model->right_eye.gamma,
                   model->right_eye.epsilon, model->right_eye.rest_x, model->right_eye.rest_y,
                   model->left_eye.gamma, model->left_eye.epsilon, model->left_eye.rest_x,
                   model->left_eye.rest_y);
  });
}

}  // namespace dreamsense::app
