// `dreamsense eval landmarks --dataset 300w DIR [--detectors union+tta,haar,...] [--stride K]
//                            [--max-items N] [--json FILE|-]` (issue 20): face detection + 68
// landmarks on real faces, per detector chain and from the annotated box. Thin: flags -> options
// -> eval_landmarks -> report.

#include "dreamsense/eval/landmarks/landmarks_eval.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <cstdio>

#include "commands.hpp"
#include "progress.hpp"

namespace dreamsense::app {
namespace {

struct EvalLandmarksFlags {
  std::vector<std::string> dataset;
  std::string json;
  eval::landmarks::LandmarksEvalOptions options;
};

double number_or(const nlohmann::json& j, const char* key) {
  return j.contains(key) && j[key].is_number() ? j[key].get<double>() : -1.0;
}

}  // namespace

void add_eval_landmarks(CLI::App& eval, const GlobalFlags& g, int& exit_code) {
  auto flags = std::make_shared<EvalLandmarksFlags>();
  auto& o = flags->options;
  CLI::App* cmd = eval.add_subcommand(
      "landmarks",
      "Face detection + 68 landmarks on annotated faces: detection rate, NME (outer eye corners)");
  cmd->add_option("--dataset", flags->dataset,
                  "NAME DIR; NAME: 300w (DIR/NAME.jpg + DIR/NAME.pts, 68 points, iBUG order)")
      ->expected(2)
      ->required();
  cmd->add_option("--detectors", o.detectors,
                  "Detector chains compared on the same images, the first one reported at the "
                  "top level: haar (the pipeline's, baseline), hog (dlib HOG), hog_haar (HOG, a "
                  "wider Haar search when HOG finds no face), union (HOG and the wider Haar "
                  "search), tiny (face-api's tiny face detector), union_tiny (union + tiny), "
                  "ssd (face-api's SSD MobileNet v1), union_ssd (union + ssd), union_tiny_ssd "
                  "(union_tiny + ssd), ssd_union (the boxes of union_ssd, SSD's kept where "
                  "boxes overlap), ssd_hybrid (ssd_union's boxes, landmarks started from the "
                  "overlapping union box), ssd_paired (ssd_hybrid, face-api's CNN started from "
                  "the SSD box); a "
                  "suffix: +tta landmarks with test-time augmentation, +cnn face-api's 68-point "
                  "CNN, +mean the mean of +tta and +cnn, +cnn_dlib +tta from the CNN's points, "
                  "+switch +tta where the dlib passes agree (confident), else +cnn, "
                  "+cnn_switch +switch with dlib started from the box of the CNN's points on "
                  "face-api's (tiny, ssd) boxes")
      ->delimiter(',')
      ->default_str(fmt::format("{}", fmt::join(o.detectors, ",")));
  cmd->add_option("--hog-min-face", o.hog_min_face_px,
                  "Smallest face the HOG detector searches (px)")
      ->default_val(o.hog_min_face_px);
  cmd->add_option("--hog-max-side", o.hog_max_work_side_px,
                  "Longest side of the image the HOG detector searches (px, after enlarging)")
      ->default_val(o.hog_max_work_side_px);
  cmd->add_option("--refit-passes", o.landmark_refit_passes,
                  "Landmarker box re-derivations after the first fit (all chains)")
      ->default_val(o.landmark_refit_passes);
  cmd->add_flag("--quantized-leaves,!--float-leaves", o.landmark_quantized_leaves,
                "dlib landmarker leaves as int16 (the pipeline's default) or dlib's floats "
                "(bit-identical to dlib, the baseline)")
      ->default_val(o.landmark_quantized_leaves);
  cmd->add_option("--ssd-min-score", o.ssd_min_score,
                  "Minimum confidence of the SSD detector (the package's default 0.5)")
      ->default_val(o.ssd_min_score);
  cmd->add_flag("--ssd-tiles,!--no-ssd-tiles", o.ssd_tiles,
                "Also run the SSD detector on 2 x 2 overlapping tiles of images over 768 px, for "
                "small faces (default on; --no-ssd-tiles: the whole image only)");
  cmd->add_option("--stride", o.stride, "Every K-th face (by name) only")->default_val(o.stride);
  cmd->add_option("--max-items", o.max_items, "At most N faces (0 = all)")
      ->default_val(o.max_items);
  cmd->add_option("--json", flags->json, "Write the evaluation JSON to FILE (- for stdout)");
  cmd->callback([flags, &g, &exit_code] {
    auto& o = flags->options;
    o.dataset = flags->dataset[0];
    o.dir = flags->dataset[1];
    auto r = with_progress("eval landmarks", g.quiet, [&](const auto& progress) {
      return eval::landmarks::run_landmarks_eval(o, progress);
    });
    if (!r) {
      exit_code = fail(r.error());
      return;
    }
    if (!g.quiet) {
      std::fprintf(stderr, "landmarks: %zu faces\n", r->items);
      auto line = [&](const std::string& name, const nlohmann::json& m, const nlohmann::json& t) {
        std::fprintf(stderr,
                     "  %-9s detection %.4f  NME mean %.4f median %.4f  failures(>0.08) %.4f  "
                     "eye %.4f  ms/face %.1f\n",
                     name.c_str(), number_or(m, "detection_rate"),
                     number_or(m, "nme_outer_corners"), number_or(m, "nme_outer_corners_median"),
                     number_or(m, "failure_rate_08"), number_or(m, "eye_center_error"),
                     number_or(t, "ms_per_face_median"));
      };
      for (const auto& c : r->extra.at("detectors")) {
        const std::string name = c.get<std::string>();
        line(name, r->metrics[name], r->timing[name]);
      }
      line("from_box", r->metrics["from_box"], r->timing["from_box"]);
      line("from_box_plain", r->metrics["from_box_plain"], r->timing["from_box_plain"]);
      if (r->metrics.contains("from_box_cnn"))
        line("from_box_cnn", r->metrics["from_box_cnn"], r->timing["from_box_cnn"]);
    }
    if (auto s = eval::write_report(*r, flags->json); !s) exit_code = fail(s.error());
  });
}

}  // namespace dreamsense::app
