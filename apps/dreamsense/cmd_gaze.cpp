// The child's calibration from sessions with truth (e.g. demo seeds not evaluated on):
// `dreamsense train face --session DIR [--session ...] --out face_model.yaml`: the 3-D landmark
//   shape for head pose (eval/face_model_fit.hpp);
// `dreamsense train gaze --session DIR [--analysis DIR] [--session ...] [--face-model F]
//   --out gaze.yaml`: D4.2 eq. (4)'s gaze constants from analysed sessions with known targets.

#include "dreamsense/eval/face_model_fit.hpp"
#include "dreamsense/eval/gaze_fit.hpp"

#include <algorithm>
#include <cstdio>
#include <numeric>

#include "commands.hpp"
#include "progress.hpp"

namespace dreamsense::app {
namespace {
struct TrainGazeFlags {
  std::vector<std::string> sessions;
  std::vector<std::string> analyses;
  std::string face_model;
  std::string out;
};
struct TrainFaceFlags {
  std::vector<std::string> sessions;
  int frame_step = 2;
  std::string out;
};
}  // namespace

void add_train_face(CLI::App& train, const GlobalFlags& g, int& exit_code) {
  auto flags = std::make_shared<TrainFaceFlags>();
  CLI::App* cmd = train.add_subcommand(
      "face",
      "Fit the child's 3-D face model (51 landmark positions in the head frame) for head pose, "
      "from sessions with truth head poses, e.g. demo seeds that you do not evaluate on");
  cmd->add_option("--session", flags->sessions, "Session folder with truth.jsonl (repeatable)")
      ->required();
  cmd->add_option("--frame-step", flags->frame_step, "Use every n-th frame of each camera")
      ->check(CLI::Range(1, 1000));
  cmd->add_option("--out", flags->out, "Face model file to write (YAML)")->required();
  cmd->callback([flags, &g, &exit_code] {
    eval::FaceModelFitOptions o;
    o.frame_step = flags->frame_step;
    std::vector<std::filesystem::path> sessions(flags->sessions.begin(), flags->sessions.end());
    auto r = with_progress("face views", g.quiet, [&](const auto& progress) {
      return eval::fit_subject_face_model(sessions, o, [&](int64_t done, int64_t total) {
        progress(total > 0 ? static_cast<double>(done) / static_cast<double>(total) : 0.0);
      });
    });
    if (!r) {
      exit_code = fail(r.error());
      return;
    }
    if (auto s = head_pose::write_face_model(flags->out, r->fit.model, r->provenance); !s) {
      exit_code = fail(s.error());
      return;
    }
    if (!g.quiet) {
      const auto& rms = r->fit.rms_ray_distance_m;
      const auto& views = r->fit.views_per_point;
      std::fprintf(
          stderr,
          "face model (%zu points) written to %s\n"
          "  %d camera frames searched, %d with landmarks, %d facing the camera\n"
          "  per point: %.0f views on average, mean ray distance %.2f mm (max %.2f)\n",
          r->fit.model.points_m.size(), flags->out.c_str(), r->frames_searched, r->views,
          r->fit.views_used,
          std::accumulate(views.begin(), views.end(), 0.0) / static_cast<double>(views.size()),
          1e3 * std::accumulate(rms.begin(), rms.end(), 0.0) / static_cast<double>(rms.size()),
          1e3 * *std::max_element(rms.begin(), rms.end()));
    }
  });
}

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
  cmd->add_option("--face-model", flags->face_model,
                  "The child's face model (`dreamsense train face`) for the analyses run here")
      ->check(CLI::ExistingFile);
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
        // Built-in gaze constants and no head-model offset: the fit measures both afresh.
        o.plan.subject_from_session = false;
        o.plan.face_model = flags->face_model;
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
