// Toys on the table:
//   dreamsense eval tracking --dataset otb|mil DIR [--tracker NAME|all] [--start-frame N]
//                            [--max-frames N] [--json FILE|-]
//   dreamsense enroll objects ... (see add_enroll_objects)

#include <cstdio>

#include "commands.hpp"
#include "dreamsense/eval/tracking_eval.hpp"
#include "dreamsense/objects/tracker.hpp"
#include "progress.hpp"

namespace dreamsense::app {
namespace {
struct EvalTrackingFlags {
  std::vector<std::string> dataset;  // NAME DIR
  std::vector<std::string> trackers = {"all"};
  int start_frame = 0;
  int max_frames = 0;
  std::string json;
};
}  // namespace

void add_eval_tracking(CLI::App& eval, const GlobalFlags& g, int& exit_code) {
  auto flags = std::make_shared<EvalTrackingFlags>();
  CLI::App* cmd = eval.add_subcommand(
      "tracking",
      "Single-object tracking, one-pass evaluation from the first labelled box: per tracker auc, "
      "precision20, mean_iou, mean_center_error_px, fps (all trackers on the same frames)");
  cmd->add_option("--dataset", flags->dataset,
                  "NAME DIR; NAME: otb (img/ + groundtruth_rect.txt, 1-based x,y,w,h) or mil "
                  "(imgs/ + NAME_gt.txt with 0,0,0,0 on unlabelled frames + NAME_frames.txt); DIR "
                  "is one sequence or a folder of sequences")
      ->expected(2)
      ->required();
  std::string known = "all";
  for (const auto& n : objects::tracker_names()) known += ", " + n;
  cmd->add_option("--tracker", flags->trackers,
                  "Tracker(s) to run, repeatable or comma-separated: " + known)
      ->delimiter(',')
      ->default_str("all");
  cmd->add_option("--start-frame", flags->start_frame,
                  "otb: frame number of the first ground-truth line when the file has fewer "
                  "lines than there are images (default: automatic)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--max-frames", flags->max_frames,
                  "Evaluate only the first N frames of each sequence (0 = all)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--json", flags->json, "Write the evaluation JSON to FILE (- for stdout)");
  cmd->callback([flags, &g, &exit_code] {
    eval::TrackingEvalOptions o;
    o.dataset = flags->dataset[0];
    o.dir = flags->dataset[1];
    o.trackers = flags->trackers;
    o.start_frame = flags->start_frame;
    o.max_frames = flags->max_frames;
    auto r = with_progress("eval tracking", g.quiet, [&](const auto& progress) {
      return eval::run_tracking_eval(o, progress);
    });
    if (!r) {
      exit_code = fail(r.error());
      return;
    }
    if (!g.quiet) {
      const auto& x = r->extra;
      std::fprintf(stderr, "tracking: %s, %zu sequence(s), %zu scored frames\n", o.dataset.c_str(),
                   x["sequences"].size(), r->items);
      for (const auto& w : x.value("warnings", nlohmann::json::array()))
        std::fprintf(stderr, "  warning: %s\n", w.get<std::string>().c_str());
      std::fprintf(stderr, "  %-12s %7s %8s %8s %10s %9s\n", "tracker", "auc", "prec@20",
                   "meanIoU", "centre_px", "fps");
      for (const auto& name : x["trackers"]) {
        const auto& m = r->metrics[name.get<std::string>()];
        std::fprintf(stderr, "  %-12s %7.3f %8.3f %8.3f %10.1f %9.1f\n",
                     name.get<std::string>().c_str(), m["auc"].get<double>(),
                     m["precision20"].get<double>(), m["mean_iou"].get<double>(),
                     m["mean_center_error_px"].get<double>(), m["fps"].get<double>());
      }
    }
    if (auto s = eval::write_report(*r, flags->json); !s) exit_code = fail(s.error());
  });
}

}  // namespace dreamsense::app
