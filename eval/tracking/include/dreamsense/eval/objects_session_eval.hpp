#pragma once
// `dreamsense eval objects SESSION`: the table-top toys of a session that has ground truth
// (truth.jsonl `object` records, e.g. any demo seed) against what modalities/objects finds in its
// top camera alone, at every top frame (`eval session` reports the same measurement of a whole
// analysis as object_position_median_m, object_track_mean_iou, object_identification_accuracy).
//
// Per top-camera frame and truth toy, the output toy whose box overlaps the truth box most
// (IoU > 0) is its match. object_track_mean_iou = mean IoU over all (frame, toy) pairs (0 when
// nothing matches); object_position_median_m = median 3-D distance between the matched toy's
// position and the truth position (matched pairs); object_identification_accuracy = fraction of
// all pairs whose match carries the true id (no match = wrong); detection_recall = fraction of
// pairs with a match. With `unknown` = a toy id, that toy is removed from the gallery and
// unknown_reject_rate = fraction of its pairs not reported as any known toy (unknown or not at
// all); the accuracy then covers the other toys. Timing: milliseconds per top frame in
// TableTopObjects::process (decoding excluded), median and mean.
//
// The table plane: a table calibration file when given (`calibrate desk`), else fitted to the
// first frame of the session's depth stream (top.depth if present, else front.depth) with its
// calibration.

#include "dreamsense/core/status.hpp"
#include "dreamsense/eval/report.hpp"
#include "dreamsense/objects/table_top_objects.hpp"

#include <filesystem>
#include <functional>
#include <optional>

namespace dreamsense::eval {

struct ObjectsSessionEvalOptions {
  std::filesystem::path session;
  std::filesystem::path gallery;       // object gallery (enroll objects); required
  std::string identifier = "gallery";  // or "hog_svm" (the seed's baseline, same gallery file)
  std::optional<std::filesystem::path> table;  // table calibration (geometry::TableFrame YAML)
  std::string camera = "top.color";
  int max_frames = 0;  // > 0: only the first N top frames
  // A toy id left out of the gallery: the session's copies of it must come out `unknown`
  // (unknown_reject_rate); the other toys are scored as usual.
  std::optional<int> unknown;
  objects::TableTopObjectsOptions objects;
  Status check() const;
};

// The table plane of a session: the calibration file if given, else a depth stream's first frame.
Result<geometry::Plane> session_table_plane(const std::filesystem::path& session,
                                            const std::optional<std::filesystem::path>& table);

Result<EvalReport> run_objects_session_eval(const ObjectsSessionEvalOptions& options,
                                            const std::function<void(double)>& progress = {});

}  // namespace dreamsense::eval
