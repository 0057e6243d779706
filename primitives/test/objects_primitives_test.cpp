// The object primitives (F8, F13, F14, F15, F19, F25) and the object history (V26) from a
// synthetic `objects.table` entry: values, queries, statuses, JSON round trip and DREAM's legacy
// vectors.

#include "dreamsense/dream/legacy.hpp"
#include "dreamsense/export/primitive_json.hpp"
#include "dreamsense/primitives/evaluator.hpp"
#include "dreamsense/primitives/objects.hpp"

#include <gtest/gtest.h>

#include "test_time.hpp"

namespace dreamsense::primitives {
namespace {

using test::ms;

// The demo's table: horizontal at y = 0.30 in a y-down world (up = -y).
TablePlane table() { return TablePlane{{0, -1, 0}, 0.30}; }

TableObject toy(int track, int id, const std::string& label, cv::Vec3d position, cv::Vec3d v,
                Timestamp stamp) {
  TableObject o;
  o.track_id = track;
  o.id = id;
  o.label = label;
  o.id_score = 0.9;
  o.stamp = stamp;
  o.box_px = {100.0 + 100 * track, 200, 60, 50};
  o.position_m = position;
  o.velocity_mps = v;
  o.size_m = {0.10, 0.075, 0.03};
  o.height_m = table().height(position);
  o.grip = ObjectGrip{position + cv::Vec3d(0, 0.015, 0), {0, 1, 0}, {0, 0, 1}, 0.095};
  for (int k = 0; k < 5; ++k)
    o.trajectory.push_back(
        {stamp - Duration::from_ms(40 * (4 - k)), position - (0.04 * (4 - k)) * v, true});
  return o;
}

TableObjects scene(Timestamp stamp) {
  TableObjects s;
  s.camera = "top.color";
  s.table = table();
  s.objects = {toy(1, 0, "car", {-0.20, 0.27, 0.60}, {0.10, 0, 0}, stamp),
               toy(4, 2, "flower", {0.15, 0.27, 0.55}, {0, 0, 0}, stamp)};
  TableObject unseen;  // no position yet (left out of every answer but identifyObject's default)
  unseen.track_id = 0;
  unseen.label = "unknown";
  unseen.stamp = stamp;
  s.objects.insert(s.objects.begin(), unseen);
  return s;
}

struct Fixture {
  Blackboard board;
  EvaluatorOptions options;
  KeySensors sensors{{"objects.table", {"top.color"}}};
  std::map<SensorId, Timestamp> seen{{"top.color", ms(1000)}};
  std::map<SensorId, CameraModel> cameras;
  explicit Fixture(const std::optional<TableObjects>& value) {
    BlackboardWriter w("objects");
    if (value)
      w.set(keys::kTableObjects, *value, ms(1000), 1.f);
    else
      w.set_absent(keys::kTableObjects, ms(1000));
    board.commit(w, ms(1000));
  }
  PrimitiveContext context(Timestamp tick = ms(1000)) const {
    return PrimitiveContext(board.snapshot(), tick, options, sensors, seen, ms(0), cameras);
  }
};

TEST(ObjectPrimitives, GetObjectsListsToysWithPositionsByTrack) {
  Fixture f(scene(ms(1000)));
  auto a = get_objects(f.context());
  ASSERT_TRUE(a.ok());
  ASSERT_EQ(a.value->objects.size(), 2u);
  EXPECT_EQ(a.value->objects[0].label, "car");
  EXPECT_EQ(a.value->objects[0].track_id, 1);
  EXPECT_EQ(a.value->objects[1].id, 2);
  EXPECT_EQ(a.source, "top.color");
  EXPECT_EQ(a.value->objects[1].box_px, cv::Rect2d(500, 200, 60, 50));
}

TEST(ObjectPrimitives, CircleIsMeasuredInTheTablePlaneNearestFirst) {
  Fixture f(scene(ms(1000)));
  // Centre 0.5 m above the flower: inside (height ignored), the car is 0.35 m away.
  auto a = get_objects_in_circle(f.context(), CircleQuery{{0.14, -0.2, 0.55}, 0.10});
  ASSERT_TRUE(a.ok());
  ASSERT_EQ(a.value->objects.size(), 1u);
  EXPECT_EQ(a.value->objects[0].label, "flower");
  a = get_objects_in_circle(f.context(), CircleQuery{{0, 0.3, 0.6}, 0.4});
  ASSERT_TRUE(a.ok());
  ASSERT_EQ(a.value->objects.size(), 2u);
  EXPECT_EQ(a.value->objects[0].label, "flower");  // 0.158 m vs 0.2 m
  a = get_objects_in_circle(f.context(), CircleQuery{{0.6, 0.3, 1.2}, 0.1});
  EXPECT_EQ(a.status, PrimitiveStatus::kNoData);
  EXPECT_TRUE(std::holds_alternative<CircleQuery>(a.query));
}

TEST(ObjectPrimitives, QueriesPickTheNearestObjectWithinTheRadius) {
  Fixture f(scene(ms(1000)));
  const auto ctx = f.context();
  auto id = identify_object(ctx, PositionQuery{cv::Vec3d(0.16, 0.28, 0.56)});
  ASSERT_TRUE(id.ok());
  EXPECT_EQ(id.value->id, 2);
  EXPECT_EQ(id.value->label, "flower");
  EXPECT_EQ(id.value->track_id, 4);
  EXPECT_DOUBLE_EQ(*id.confidence, 0.9);
  EXPECT_EQ(identify_object(ctx, PositionQuery{cv::Vec3d(0.6, 0.27, 1.2)}).status,
            PrimitiveStatus::kNoData);
  // Default: the first object, even without a position (its identity is known from the image).
  id = identify_object(ctx);
  ASSERT_TRUE(id.ok());
  EXPECT_EQ(id.value->track_id, 0);
  EXPECT_EQ(id.value->id, -1);

  auto d = get_object_table_distance(ctx, PositionQuery{cv::Vec3d(-0.2, 0.27, 0.6)});
  ASSERT_TRUE(d.ok());
  EXPECT_NEAR(d.value->distance_m, 0.03, 1e-12);
  EXPECT_EQ(d.value->object_id, 0);
  EXPECT_FALSE(d.value->measured);
  d = get_object_table_distance(ctx);  // default: the first object with a position
  ASSERT_TRUE(d.ok());
  EXPECT_EQ(d.value->track_id, 1);

  auto g = get_grip_location(ctx, PositionQuery{cv::Vec3d(0.15, 0.27, 0.55)});
  ASSERT_TRUE(g.ok());
  EXPECT_NEAR(g.value->position_m[1], 0.285, 1e-12);
  EXPECT_EQ(g.value->approach_direction, cv::Vec3d(0, 1, 0));
  EXPECT_EQ(g.value->closing_axis, cv::Vec3d(0, 0, 1));
  EXPECT_DOUBLE_EQ(g.value->width_m, 0.095);
  EXPECT_EQ(g.value->object_id, 2);
}

TEST(ObjectPrimitives, TrackObjectPredictsWithConstantVelocityFromTheLastObservation) {
  TableObjects s = scene(ms(1000));
  s.objects[1].velocity_mps = {0.10, -0.05, 0};  // a vertical part is not followed
  Fixture f(s);
  // 40 ms after the observation, 0.5 s ahead: 0.54 s at 10 cm/s in x.
  auto t = track_object(f.context(ms(1040)), TrackQuery{{-0.19, 0.27, 0.61}, 0.5});
  ASSERT_EQ(t.status, PrimitiveStatus::kOk);
  EXPECT_NEAR(t.value->position_m[0], -0.20 + 0.054, 1e-9);
  EXPECT_NEAR(t.value->position_m[1], 0.27, 1e-9);  // same height above the table
  EXPECT_NEAR(t.value->position_m[2], 0.60, 1e-9);
  EXPECT_NEAR(t.value->velocity_mps[1], 0.0, 1e-12);
  EXPECT_EQ(t.value->track_id, 1);
  EXPECT_EQ(t.value->samples, 5);
  // A seed far from every toy: nothing to track.
  EXPECT_EQ(track_object(f.context(ms(1040)), TrackQuery{{1, 0, 2}, 0.5}).status,
            PrimitiveStatus::kNoData);
  // Default query: the first object with a position, dt = track_object_dt_s.
  t = track_object(f.context(ms(1000)));
  ASSERT_TRUE(t.ok());
  EXPECT_NEAR(t.value->position_m[0],
              -0.20 + 0.1 * f.options.families.get<ObjectPrimitiveOptions>().track_dt_s, 1e-9);
  ASSERT_TRUE(std::holds_alternative<TrackQuery>(t.query));

  const auto h = object_history(f.context(), 4);
  ASSERT_EQ(h.size(), 5u);
  EXPECT_EQ(h.back().stamp, ms(1000));
  EXPECT_TRUE(object_history(f.context(), 99).empty());
}

TEST(ObjectPrimitives, StatusesNoDataStaleOfflineDisabled) {
  Fixture empty_table(TableObjects{{}, table(), "top.color"});
  for (auto s :
       {get_objects(empty_table.context()).status, identify_object(empty_table.context()).status,
        track_object(empty_table.context()).status,
        get_grip_location(empty_table.context()).status})
    EXPECT_EQ(s, PrimitiveStatus::kNoData);
  // No table plane: boxes but no positions, so nothing to place.
  TableObjects flat = scene(ms(1000));
  flat.table.reset();
  for (auto& o : flat.objects) o.position_m.reset(), o.height_m.reset(), o.grip.reset();
  Fixture no_plane(flat);
  EXPECT_EQ(get_objects(no_plane.context()).status, PrimitiveStatus::kNoData);
  EXPECT_EQ(get_object_table_distance(no_plane.context()).status, PrimitiveStatus::kNoData);
  EXPECT_TRUE(identify_object(no_plane.context()).ok());

  Fixture f(scene(ms(1000)));
  EXPECT_EQ(get_objects(f.context(ms(1300))).status, PrimitiveStatus::kStale);
  EXPECT_EQ(get_objects(f.context(ms(2500))).status, PrimitiveStatus::kSensorOffline);
  f.sensors.clear();
  EXPECT_EQ(get_objects(f.context()).status, PrimitiveStatus::kDisabled);
}

TEST(ObjectPrimitives, EvaluatorAnswersAllSixAndJsonAndLegacyRoundTrip) {
  Fixture f(scene(ms(1000)));
  EvaluatorOptions o;
  ObjectPrimitiveOptions objects;  // the family's own options block
  objects.circle = CircleQuery{{0, 0.3, 0.6}, 0.4};
  o.families.set(objects);
  Evaluator ev(o, f.sensors);
  MultiFrame tick;
  tick.stamp = ms(1000);
  tick.frames["top.color"] = make_frame("top.color", ms(1000), 0, ColorImage{});
  const auto records = ev.evaluate(tick, f.board.snapshot());
  for (PrimitiveId id : {PrimitiveId::kGetGripLocation, PrimitiveId::kGetObjects,
                         PrimitiveId::kGetObjectsCircle, PrimitiveId::kGetObjectTableDistance,
                         PrimitiveId::kIdentifyObject, PrimitiveId::kTrackObject}) {
    const PrimitiveRecord& r = records[static_cast<size_t>(id) - 1];
    ASSERT_EQ(r.id, id);
    EXPECT_EQ(r.status, PrimitiveStatus::kOk) << info(id).name;
    const auto j = exporters::to_json(r);
    auto back = exporters::record_from_json(j);
    ASSERT_TRUE(back) << back.error().message;
    EXPECT_EQ(exporters::to_json(*back), j) << info(id).name;
  }
  auto legacy = [&](PrimitiveId id) {
    return *dream::legacy_vector(records[static_cast<size_t>(id) - 1]);
  };
  // [N, (x, y, z, id) x N] in mm.
  EXPECT_EQ(legacy(PrimitiveId::kGetObjects),
            (std::vector<double>{2, -200, 270, 600, 0, 150, 270, 550, 2}));
  EXPECT_EQ(legacy(PrimitiveId::kGetObjectsCircle)[0], 2);
  EXPECT_EQ(legacy(PrimitiveId::kIdentifyObject), std::vector<double>{-1});  // the unplaced one
  ASSERT_EQ(legacy(PrimitiveId::kGetObjectTableDistance).size(), 1u);
  EXPECT_NEAR(legacy(PrimitiveId::kGetObjectTableDistance)[0], 30, 1e-9);
  EXPECT_EQ(legacy(PrimitiveId::kGetGripLocation).size(), 3u);
  EXPECT_NEAR(legacy(PrimitiveId::kTrackObject)[0], -200 + 100 * objects.track_dt_s, 1e-9);
  EXPECT_STREQ(dream::port(PrimitiveId::kTrackObject), "trackObject:o");  // not trackHand's
  const auto& circle = records[static_cast<size_t>(PrimitiveId::kGetObjectsCircle) - 1];
  ASSERT_NE(std::get_if<CircleQuery>(&circle.query), nullptr);
  EXPECT_DOUBLE_EQ(std::get<CircleQuery>(circle.query).radius_m, 0.4) << "the family's option";
}

TEST(ObjectPrimitives, FamilyOptionsAreChecked) {
  EvaluatorOptions o;
  EXPECT_TRUE(o.check()) << "defaults of every family";
  ObjectPrimitiveOptions bad;
  bad.query_radius_m = 0;
  o.families.set(bad);
  const auto s = o.check();
  ASSERT_FALSE(s);
  EXPECT_NE(s.error().message.find("ObjectPrimitiveOptions: query_radius_m"), std::string::npos)
      << s.error().message;
}

}  // namespace
}  // namespace dreamsense::primitives
