// Toys on the table:
//   dreamsense eval tracking --dataset otb|mil DIR [--tracker NAME|all] [--start-frame N]
//                            [--max-frames N] [--json FILE|-]
//   dreamsense eval objects SESSION [--gallery FILE] [--identifier gallery|hog_svm] [--json FILE|-]
//   dreamsense enroll objects (--crops DIR | --session DIR [--boxes CSV]) --out GALLERY

#include "dreamsense/eval/object_enrolment.hpp"
#include "dreamsense/eval/objects_session_eval.hpp"
#include "dreamsense/eval/tracking_eval.hpp"
#include "dreamsense/objects/identification.hpp"
#include "dreamsense/objects/tracker.hpp"

#include <cstdio>

#include "commands.hpp"
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
      std::fprintf(stderr, "  %-12s %7s %8s %8s %10s %9s\n", "tracker", "auc", "prec@20", "meanIoU",
                   "centre_px", "fps");
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

namespace dreamsense::app {
namespace {
struct EnrollObjectsFlags {
  std::string crops;
  std::vector<std::string> sessions;
  std::string boxes;
  bool boxes_by_stamp = false;
  std::string camera = "top.color";
  int frame_step = 10;
  std::vector<std::string> classes;
  std::string base;
  std::string out;
  int max_views = 40;
};
struct EvalObjectsFlags {
  std::string session;
  std::string gallery;
  std::string identifier = "gallery";
  std::string table;
  int max_frames = 0;
  int unknown = -1;
  std::string json;
};
}  // namespace

void add_enroll_objects(CLI::App& enroll, const GlobalFlags& g, int& exit_code) {
  auto flags = std::make_shared<EnrollObjectsFlags>();
  CLI::App* cmd = enroll.add_subcommand(
      "objects",
      "Enrol toys for identifyObject from labelled crops (DIR/<label>/*.png) or recordings with "
      "boxes; writes a versioned object gallery (our colour + fHOG gallery with rejection and "
      "the seed's HOG + SVM baseline)");
  cmd->add_option("--crops", flags->crops, "Folder of crops, one sub-folder per label");
  cmd->add_option("--session", flags->sessions,
                  "Recording(s) whose top camera shows the toys (repeatable); boxes from "
                  "--boxes or the session's truth.jsonl");
  cmd->add_option(
      "--boxes", flags->boxes,
      "CSV 'frame,label,x,y,w,h' (frame index of the camera, from 0) for one --session");
  cmd->add_flag("--boxes-by-stamp", flags->boxes_by_stamp,
                "The CSV's first column is the frame stamp in ns, not its index");
  cmd->add_option("--camera", flags->camera, "Stream of the recordings")->default_val("top.color");
  cmd->add_option("--frame-step", flags->frame_step, "Use every n-th frame of a recording")
      ->default_val(10)
      ->check(CLI::PositiveNumber);
  cmd->add_option("--class", flags->classes,
                  "label=id[:LxWxH] for a new toy or to override an id/size (metres), repeatable; "
                  "known: car=0, cup=1, flower=2, plane=3 (10 x 7.5 x 3 cm)");
  cmd->add_option("--add-to", flags->base, "Add to this gallery instead of starting a new one");
  cmd->add_option("--max-views", flags->max_views, "Views kept per toy (evenly thinned)")
      ->default_val(40)
      ->check(CLI::PositiveNumber);
  cmd->add_option("--out", flags->out, "Gallery file to write (YAML)")->required();
  cmd->callback([flags, &g, &exit_code] {
    eval::ObjectEnrolmentOptions o;
    if (!flags->crops.empty()) o.crops = flags->crops;
    for (const auto& s : flags->sessions) o.sessions.emplace_back(s);
    if (!flags->boxes.empty()) o.boxes = flags->boxes;
    o.boxes_by_stamp = flags->boxes_by_stamp;
    o.camera = flags->camera;
    o.frame_step = flags->frame_step;
    o.gallery.max_exemplars_per_class = flags->max_views;
    if (!flags->base.empty()) o.base = flags->base;
    for (const auto& c : flags->classes) {
      auto k = eval::parse_object_class(c);
      if (!k) {
        exit_code = fail(k.error());
        return;
      }
      o.classes.push_back(*k);
    }
    auto r = eval::enrol_objects(o);
    if (!r) {
      exit_code = fail(r.error());
      return;
    }
    if (auto s = r->gallery.save(flags->out); !s) {
      exit_code = fail(s.error());
      return;
    }
    if (!g.quiet) {
      std::fprintf(stderr,
                   "objects: %zu toys enrolled (%d exemplars, rejection threshold %.3f)%s\n",
                   r->gallery.classes().size(), r->gallery.exemplars(), r->gallery.threshold(),
                   r->gallery.has_baseline() ? ", HOG + SVM baseline trained" : "");
      for (const auto& [label, n] : r->views_per_label)
        std::fprintf(stderr, "  %-12s %d views\n", label.c_str(), n);
    }
  });
}

void add_eval_objects(CLI::App& eval, const GlobalFlags& g, int& exit_code) {
  auto flags = std::make_shared<EvalObjectsFlags>();
  CLI::App* cmd = eval.add_subcommand(
      "objects",
      "Toys on the table of a session with truth (e.g. a demo seed): object_track_mean_iou, "
      "object_position_median_m, object_identification_accuracy, ms per top frame");
  cmd->add_option("session", flags->session, "Session folder with truth.jsonl")->required();
  cmd->add_option("--gallery", flags->gallery,
                  "Object gallery (enroll objects); default: the demo toys' gallery shipped in "
                  "modalities/objects/models");
  cmd->add_option("--identifier", flags->identifier, "gallery (ours) or hog_svm (the seed's)")
      ->check(CLI::IsMember({"gallery", "hog_svm"}));
  cmd->add_option("--table", flags->table,
                  "Table calibration (calibrate desk); default: fitted to the session's depth");
  cmd->add_option("--max-frames", flags->max_frames, "Only the first N top frames (0 = all)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--unknown", flags->unknown,
                  "Leave this toy id out of the gallery: its copies must come out unknown "
                  "(unknown_reject_rate)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--json", flags->json, "Write the evaluation JSON to FILE (- for stdout)");
  cmd->callback([flags, &g, &exit_code] {
    eval::ObjectsSessionEvalOptions o;
    if (flags->unknown >= 0) o.unknown = flags->unknown;
    o.session = flags->session;
    o.gallery = flags->gallery.empty() ? objects::default_gallery_path()
                                       : std::filesystem::path(flags->gallery);
    o.identifier = flags->identifier;
    if (!flags->table.empty()) o.table = flags->table;
    o.max_frames = flags->max_frames;
    auto r = with_progress("eval objects", g.quiet, [&](const auto& progress) {
      return eval::run_objects_session_eval(o, progress);
    });
    if (!r) {
      exit_code = fail(r.error());
      return;
    }
    if (!g.quiet) {
      const auto& m = r->metrics;
      auto num = [](const nlohmann::json& v) { return v.is_null() ? -1.0 : v.get<double>(); };
      std::fprintf(stderr,
                   "objects (%s): mean IoU %.3f, position median %.4f m, identification %.3f, "
                   "recall %.3f, %.2f ms/frame (median; CPU %.2f ms)\n",
                   o.identifier.c_str(), num(m["object_track_mean_iou"]),
                   num(m["object_position_median_m"]), num(m["object_identification_accuracy"]),
                   num(m["detection_recall"]), num(r->timing["ms_per_frame_median"]),
                   num(r->timing["cpu_ms_per_frame_median"]));
      if (m.contains("unknown_reject_rate"))
        std::fprintf(
            stderr, "  toy %d left out of the gallery: rejected as unknown in %.3f of its frames\n",
            m["unknown_toy"].get<int>(), m["unknown_reject_rate"].get<double>());
    }
    if (auto s = eval::write_report(*r, flags->json); !s) exit_code = fail(s.error());
  });
}

}  // namespace dreamsense::app
