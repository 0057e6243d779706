#pragma once
// Primitives answered from the toys on the table (perception/objects.hpp, `objects.table`):
// F8 getGripLocation, F13 getObjects, F14 getObjects (circle), F15 getObjectTableDistance,
// F19 identifyObject, F25 trackObject, and the object history (V26).
//
// Which object. A query position picks the object nearest to it (3-D distance) when it is within
// ObjectPrimitiveOptions::query_radius_m, otherwise the answer is no_data; without a query (batch
// analysis) the primitive answers for the first object of getObjects (the oldest track). Objects
// without a 3-D position (no table plane yet) are left out of every answer but identifyObject's
// default one. Nothing on the table is no_data.

#include "dreamsense/perception/objects.hpp"
#include "dreamsense/primitives/context.hpp"

#include <optional>
#include <vector>

namespace dreamsense::primitives {

// The objects family's options block (EvaluatorOptions::families).
struct ObjectPrimitiveOptions {
  // Default query of getObjects (circle), F14: a circle on the table (world, m).
  CircleQuery circle{cv::Vec3d(0, 0.3, 0.6), 0.15};
  // F8, F15, F19, F25 with a position: the object nearest to it, if within this distance.
  double query_radius_m = 0.15;
  // Default query of trackObject (F25): predict the first object this far ahead.
  double track_dt_s = 0.2;
  Status check() const;
};

// F13: every toy on the table with a position, by track id.
Answer<ObjectsValue> get_objects(const PrimitiveContext& ctx);
// F14: the toys whose position lies within the circle, measured in the table plane (the height
// above the table is ignored), nearest first; no_data when none.
Answer<ObjectsValue> get_objects_in_circle(const PrimitiveContext& ctx, const CircleQuery& query);
// F15: the object's position (top face centre) above the table plane, and its bottom's lift.
Answer<ObjectTableDistanceValue> get_object_table_distance(const PrimitiveContext& ctx,
                                                           const PositionQuery& query = {});
// F8: where to grip the object (analyser's rule; no_data when it is too big for the hand).
Answer<GripLocationValue> get_grip_location(const PrimitiveContext& ctx,
                                            const PositionQuery& query = {});
// F19: which toy it is (id -1 "unknown": a blob nobody enrolled).
Answer<ObjectIdentityValue> identify_object(const PrimitiveContext& ctx,
                                            const PositionQuery& query = {});
// F25: the track nearest to the seed, predicted dt ahead by a constant-velocity model (the
// velocity is the least-squares slope of the track's recent positions), from the object's last
// observation to tick + dt, kept at the same height above the table. Without a query: the first
// object, dt = ObjectPrimitiveOptions::track_dt_s.
Answer<TrackValue> track_object(const PrimitiveContext& ctx,
                                const std::optional<TrackQuery>& query = std::nullopt);

// V26: the recent positions of a track (oldest first); empty when the track is not on the table
// in this tick's snapshot.
std::vector<ObjectTrajectoryPoint> object_history(const PrimitiveContext& ctx, int track_id);

// Pure helpers (tested alone).
// Objects within `radius_m` of `centre_m` in the table plane, nearest first.
std::vector<const TableObject*> objects_in_circle(const TableObjects& objects,
                                                  const cv::Vec3d& centre_m, double radius_m);
// Constant-velocity prediction of `object` at `at` (kept at its height above `table` if any).
cv::Vec3d predict_object_position(const TableObject& object, Timestamp at,
                                  const std::optional<TablePlane>& table);

}  // namespace dreamsense::primitives
