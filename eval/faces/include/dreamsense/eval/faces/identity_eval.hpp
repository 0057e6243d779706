#pragma once
// `dreamsense eval faces --dataset att|yale DIR --enroll K [--unknown U]` (spec/cli.md, task
// "faces"): subjects in natural order; the last U never enrol and all their images are probes
// that must be rejected; of every other subject the first K images (natural order of file
// names; Yale: of condition names) enrol and the rest are probes.
// Metrics (first method at the top level, every method under metrics.<method>): accuracy =
// rank-1 identification of known probes with a rejection counted as an error;
// false_accept_rate = unknown probes accepted as anyone; closed_set_accuracy (the best match,
// threshold ignored); false_reject_rate (known probes rejected); the threshold and whether the
// enrolment data could choose it. Faces are aligned as for expression (cascade + dlib
// landmarks, crop fallbacks); an image without a usable face is skipped at enrolment and
// answered "unknown" as a probe. Timing: ms_per_face_median = warp + descriptor + matching,
// single-threaded (the landmarks come from the pipeline); ms_alignment_median = the dataset
// crop path.

#include "dreamsense/core/status.hpp"
#include "dreamsense/eval/faces/expression_eval.hpp"
#include "dreamsense/eval/report.hpp"
#include "dreamsense/vision/face_crops.hpp"

#include <filesystem>
#include <string>
#include <vector>

namespace dreamsense::eval::faces {

struct FaceIdEvalOptions {
  std::string dataset;  // att | yale
  std::filesystem::path dir;
  int enroll = 5;
  int unknown = 0;
  std::vector<std::string> methods{"face_api", "lbp_tt", "lbp_svm"};
  vision::FaceCropOptions crop;
  Status check() const;
};

Result<EvalReport> run_face_id_eval(const FaceIdEvalOptions& options,
                                    const Progress& progress = {});

}  // namespace dreamsense::eval::faces
