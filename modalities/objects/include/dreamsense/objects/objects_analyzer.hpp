#pragma once
// Thin Analyzer adapter over TableTopObjects: reads the table camera's colour frames (and, until
// the table plane is known, one frame of a depth stream to fit it), writes the toys on the table
// to the blackboard (perception/objects.hpp: `objects.table`) with what the primitives need per
// toy: 3-D position, table distance, grip, velocity and a short trajectory (V26). Planned by
// src/register.cpp from the session's streams (roles table_camera / table_depth) and calibration.

#include "dreamsense/core/analyzer.hpp"
#include "dreamsense/objects/table_geometry.hpp"
#include "dreamsense/objects/table_top_objects.hpp"
#include "dreamsense/perception/analyzer_registry.hpp"
#include "dreamsense/perception/objects.hpp"

#include <memory>
#include <optional>

namespace dreamsense::objects {

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
  GripOptions grip;           // F8's rule (README)
  double trajectory_s = 2.0;  // V26: each toy's trajectory covers this much of its history
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

// The blackboard value of one frame's toys: positions, table distances and grips from `table`,
// trajectories from the tracks' histories (the last `trajectory_s`).
TableObjects to_table_objects(const std::vector<ObjectState>& states,
                              const std::optional<geometry::Plane>& table,
                              const TableTopObjects& tracks, const ObjectsAnalyzerOptions& options);

// The declared pipeline's factory "objects" (src/register.cpp). Plan: the stream with role
// table_camera (skipped when there is none or it has no calibration); the table plane from the
// option `table` or the session's metadata `table_calibration` (a `calibrate desk` file), else
// fitted to the first frame of the table_depth stream or of another calibrated depth stream
// (option `plane_depth`; a recording: at planning, skipped when no table is found in it; live: at
// the first frame); the gallery from the option `gallery` (default: the shipped demo toys).
void register_analyzers(AnalyzerRegistry& registry);

}  // namespace dreamsense::objects
