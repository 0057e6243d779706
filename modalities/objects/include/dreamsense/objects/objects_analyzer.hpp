#pragma once
// Thin Analyzer adapter over TableTopObjects: reads the top camera's colour frames (and, until
// the table plane is known, one frame of a depth stream to fit it), writes the toys on the
// table to the blackboard. Not wired into the runner yet (issue 19 reshapes the pipeline); the
// blackboard type lives here until the perception/ layer exists.

#include "dreamsense/core/analyzer.hpp"
#include "dreamsense/objects/table_geometry.hpp"
#include "dreamsense/objects/table_top_objects.hpp"

#include <memory>
#include <optional>

namespace dreamsense::objects {

// The toys on the table at one top-camera frame (getObjects, identifyObject, trackObject,
// getObjectTableDistance, getGripLocation read it). Empty `objects` = none seen.
struct TableObjects {
  std::vector<ObjectState> objects;
  std::optional<geometry::Plane> table;  // world; absent: no 3-D positions yet
  SensorId camera;
};
inline constexpr Key<TableObjects> kTableObjectsKey{"objects.table"};

struct ObjectsAnalyzerOptions {
  SensorId camera = "top.color";
  std::optional<CameraModel> camera_model;  // the top camera's calibration (3-D needs it)
  std::optional<geometry::Plane> table;     // from the desk calibration, if there is one
  // Otherwise the plane is fitted to the first frame of this depth stream (e.g. front.depth),
  // whose calibration is `depth_model`; `depth_up` = the table normal's prior in world (for a
  // front sensor its -y axis); unset: the depth camera looks down on the table.
  std::optional<SensorId> depth;
  std::optional<CameraModel> depth_model;
  std::optional<cv::Vec3d> depth_up;
  TableTopObjectsOptions objects;
  Status check() const;
};

class ObjectsAnalyzer : public Analyzer {
 public:
  static Result<std::unique_ptr<ObjectsAnalyzer>> create(
      ObjectsAnalyzerOptions options, std::shared_ptr<const ObjectGallery> gallery);
  std::string_view name() const override { return "objects"; }
  AnalyzerContract contract() const override;
  Status process(const MultiFrame& in, const BlackboardView& prior, BlackboardWriter& out) override;
  void reset() override;

 private:
  ObjectsAnalyzer() = default;
  Status make_pipeline();

  ObjectsAnalyzerOptions o_;
  std::shared_ptr<const ObjectGallery> gallery_;
  std::optional<geometry::Plane> table_;
  std::unique_ptr<TableTopObjects> pipeline_;
  bool plane_failed_ = false;
};

}  // namespace dreamsense::objects
