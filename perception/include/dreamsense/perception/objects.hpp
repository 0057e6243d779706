#pragma once
// Toys on the table (modalities/objects): V10/V21 object location, V22 object id, V25/V26 object
// history, with the table plane (V19) they stand on. F8 getGripLocation, F13/F14 getObjects,
// F15 getObjectTableDistance, F19 identifyObject and F25 trackObject are answered from it.
// Blackboard types of one modality (perception layer: below the modalities, which never include
// each other's headers). docs/blackboard.md maps the keys onto DREAM's global buffer (V1-V29).

#include "dreamsense/core/blackboard.hpp"
#include "dreamsense/core/sensor_frame.hpp"

#include <opencv2/core.hpp>

#include <optional>
#include <string>
#include <vector>

namespace dreamsense {

// The table top (world, metres): points x with normal . x + offset = 0; the unit normal points
// up, away from the table top (towards the cameras).
struct TablePlane {
  cv::Vec3d normal{0, -1, 0};
  double offset = 0;
  double height(const cv::Vec3d& p) const { return normal.dot(p) + offset; }  // above the table
  cv::Vec3d project(const cv::Vec3d& p) const { return p - height(p) * normal; }
};

// Where a robot hand should take a toy (F8; the rule is in modalities/objects/README.md).
struct ObjectGrip {
  cv::Vec3d point_m{0, 0, 0};
  cv::Vec3d approach{0, 1, 0};      // unit, world: the direction the hand moves in
  cv::Vec3d closing_axis{1, 0, 0};  // unit, world: the direction the fingers close along
  double opening_m = 0;             // how wide the hand must open
};

// One past position of a track (V26).
struct ObjectTrajectoryPoint {
  Timestamp stamp;
  cv::Vec3d position_m{0, 0, 0};
  bool detected = true;  // false: carried by the visual tracker
};

// A toy on the table at one top-camera frame.
struct TableObject {
  int track_id = -1;              // stable while the toy is tracked (and when it comes back)
  int id = -1;                    // DREAM id (0 car, 1 cup, 2 flower, 3 plane) or enrolled; -1
  std::string label = "unknown";  //   unknown (a blob nobody enrolled)
  double id_score = 0;            // fraction of the track's identifications that agree
  Timestamp stamp;                // the top frame this state is from
  cv::Rect2d box_px;              // in the top camera's image
  std::optional<cv::Vec3d> position_m;  // top face centre (world); needs calibration and table
  std::optional<cv::Vec3d> axis_m;      // unit, along the top face's long side (world)
  cv::Vec3d velocity_mps{0, 0, 0};      // least squares over the track's recent positions
  cv::Vec3d size_m{0, 0, 0};            // length, width, height of the toy (its class's)
  bool detected = true;                 // false: carried by the visual tracker (occluded)
  int missing_frames = 0;               // frames since it was last detected
  // F15: height of the top face above the table and of its bottom (0 when resting);
  // `height_measured` = false when the position assumed the toy rests on the table (no depth).
  std::optional<double> height_m;
  double lift_m = 0;
  bool height_measured = false;
  std::optional<ObjectGrip> grip;                 // F8 (absent: no position, or too big to grip)
  std::vector<ObjectTrajectoryPoint> trajectory;  // V26: recent positions, oldest first
};

// The toys on the table at one top-camera frame. An empty `objects` = none on the table.
struct TableObjects {
  std::vector<TableObject> objects;  // by track id
  std::optional<TablePlane> table;   // absent: no 3-D positions
  SensorId camera;                   // the table camera
};

namespace keys {
// Written at every top-camera frame.
inline constexpr Key<TableObjects> kTableObjects{"objects.table"};
}  // namespace keys

}  // namespace dreamsense
