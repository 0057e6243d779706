#include "dreamsense/primitives/objects.hpp"

#include "dreamsense/primitives/registry.hpp"

#include <algorithm>
#include <limits>

namespace dreamsense::primitives {

Status ObjectPrimitiveOptions::check() const {
  std::string bad;
  if (!(circle.radius_m > 0)) bad += " circle radius_m must be > 0;";
  if (!(query_radius_m > 0)) bad += " query_radius_m must be > 0;";
  if (!(track_dt_s >= 0)) bad += " track_dt_s must be >= 0;";
  if (!bad.empty()) return make_error(ErrorCode::kInvalidArgument, "ObjectPrimitiveOptions:" + bad);
  return ok_status();
}

namespace {

// The table camera, reported with every status.
template <typename V>
Answer<V> start(const PrimitiveContext& ctx, const Observation<TableObjects>& o) {
  auto a = Answer<V>::from(o);
  const auto& sensors = ctx.sensors_of(keys::kTableObjects.name);
  if (o.entry && o.entry->present())
    a.source = o.value().camera;
  else if (!sensors.empty())
    a.source = sensors.front();
  return a;
}

ObjectValue object_value(const TableObject& o) {
  ObjectValue v;
  v.id = o.id;
  v.label = o.label;
  v.position_m = *o.position_m;
  v.score = o.id_score;
  v.track_id = o.track_id;
  v.box_px = o.box_px;
  v.detected = o.detected;
  return v;
}

// The object a query names: nearest to its position (within the radius), else the first one
// with a position (or, when `need_position` is false, the first one at all).
const TableObject* pick(const PrimitiveContext& ctx, const TableObjects& objects,
                        const std::optional<cv::Vec3d>& position, bool need_position = true) {
  const TableObject* best = nullptr;
  if (position) {
    double best_d = ctx.family_options<ObjectPrimitiveOptions>().query_radius_m;
    for (const auto& o : objects.objects) {
      if (!o.position_m) continue;
      const double d = cv::norm(*o.position_m - *position);
      if (d <= best_d) best = &o, best_d = d;
    }
    return best;
  }
  for (const auto& o : objects.objects)
    if (o.position_m || !need_position) return &o;
  return nullptr;
}

}  // namespace

std::vector<const TableObject*> objects_in_circle(const TableObjects& objects,
                                                  const cv::Vec3d& centre_m, double radius_m) {
  std::vector<std::pair<double, const TableObject*>> in;
  for (const auto& o : objects.objects) {
    if (!o.position_m) continue;
    const cv::Vec3d d =
        objects.table ? objects.table->project(*o.position_m) - objects.table->project(centre_m)
                      : *o.position_m - centre_m;
    const double r = cv::norm(d);
    if (r <= radius_m) in.emplace_back(r, &o);
  }
  std::stable_sort(in.begin(), in.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<const TableObject*> out;
  for (const auto& p : in) out.push_back(p.second);
  return out;
}

cv::Vec3d predict_object_position(const TableObject& o, Timestamp at,
                                  const std::optional<TablePlane>& table) {
  const cv::Vec3d from = o.position_m ? *o.position_m : cv::Vec3d(0, 0, 0);
  cv::Vec3d p = from + (at - o.stamp).seconds() * o.velocity_mps;
  if (table) p -= (table->height(p) - table->height(from)) * table->normal;
  return p;
}

Answer<ObjectsValue> get_objects(const PrimitiveContext& ctx) {
  const auto o = ctx.observe(keys::kTableObjects);
  auto a = start<ObjectsValue>(ctx, o);
  if (a.status != PrimitiveStatus::kOk) return a;
  ObjectsValue v;
  for (const auto& obj : o.value().objects)
    if (obj.position_m) v.objects.push_back(object_value(obj));
  if (v.objects.empty()) {
    a.status = PrimitiveStatus::kNoData;
    return a;
  }
  a.confidence = o.entry->confidence;
  a.value = std::move(v);
  return a;
}

Answer<ObjectsValue> get_objects_in_circle(const PrimitiveContext& ctx, const CircleQuery& query) {
  const auto o = ctx.observe(keys::kTableObjects);
  auto a = start<ObjectsValue>(ctx, o);
  if (a.status == PrimitiveStatus::kDisabled) return a;
  a.query = query;
  if (a.status != PrimitiveStatus::kOk) return a;
  ObjectsValue v;
  for (const TableObject* obj : objects_in_circle(o.value(), query.centre_m, query.radius_m))
    v.objects.push_back(object_value(*obj));
  if (v.objects.empty()) {
    a.status = PrimitiveStatus::kNoData;
    return a;
  }
  a.confidence = o.entry->confidence;
  a.value = std::move(v);
  return a;
}

Answer<ObjectTableDistanceValue> get_object_table_distance(const PrimitiveContext& ctx,
                                                           const PositionQuery& query) {
  const auto o = ctx.observe(keys::kTableObjects);
  auto a = start<ObjectTableDistanceValue>(ctx, o);
  if (a.status == PrimitiveStatus::kDisabled) return a;
  a.query = query;
  if (a.status != PrimitiveStatus::kOk) return a;
  const TableObject* obj = pick(ctx, o.value(), query.position_m);
  if (obj == nullptr || !obj->height_m) {
    a.status = PrimitiveStatus::kNoData;
    return a;
  }
  a.confidence = o.entry->confidence;
  a.value = ObjectTableDistanceValue{*obj->height_m, obj->id, obj->lift_m, obj->height_measured,
                                     obj->track_id};
  return a;
}

Answer<GripLocationValue> get_grip_location(const PrimitiveContext& ctx,
                                            const PositionQuery& query) {
  const auto o = ctx.observe(keys::kTableObjects);
  auto a = start<GripLocationValue>(ctx, o);
  if (a.status == PrimitiveStatus::kDisabled) return a;
  a.query = query;
  if (a.status != PrimitiveStatus::kOk) return a;
  const TableObject* obj = pick(ctx, o.value(), query.position_m);
  if (obj == nullptr || !obj->grip) {
    a.status = PrimitiveStatus::kNoData;
    return a;
  }
  const ObjectGrip& g = *obj->grip;
  a.confidence = o.entry->confidence;
  a.value =
      GripLocationValue{g.point_m, g.approach, g.opening_m, obj->id, g.closing_axis, obj->track_id};
  return a;
}

Answer<ObjectIdentityValue> identify_object(const PrimitiveContext& ctx,
                                            const PositionQuery& query) {
  const auto o = ctx.observe(keys::kTableObjects);
  auto a = start<ObjectIdentityValue>(ctx, o);
  if (a.status == PrimitiveStatus::kDisabled) return a;
  a.query = query;
  if (a.status != PrimitiveStatus::kOk) return a;
  const TableObject* obj = pick(ctx, o.value(), query.position_m, /*need_position=*/false);
  if (obj == nullptr) {
    a.status = PrimitiveStatus::kNoData;
    return a;
  }
  a.confidence = obj->id_score;
  a.value = ObjectIdentityValue{obj->id, obj->label, obj->id_score, obj->track_id};
  return a;
}

Answer<TrackValue> track_object(const PrimitiveContext& ctx,
                                const std::optional<TrackQuery>& query) {
  const auto o = ctx.observe(keys::kTableObjects);
  auto a = start<TrackValue>(ctx, o);
  if (a.status == PrimitiveStatus::kDisabled) return a;
  if (query) a.query = *query;
  if (a.status != PrimitiveStatus::kOk) return a;
  const TableObjects& objects = o.value();
  const TableObject* obj = pick(ctx, objects, query ? std::optional(query->seed_m) : std::nullopt);
  if (obj == nullptr) {
    a.status = PrimitiveStatus::kNoData;
    return a;
  }
  const TrackQuery q =
      query ? *query
            : TrackQuery{*obj->position_m, ctx.family_options<ObjectPrimitiveOptions>().track_dt_s};
  a.query = q;
  TrackValue v;
  const Timestamp at = ctx.tick() + Duration::from_seconds(q.dt_s);
  v.position_m = predict_object_position(*obj, at, objects.table);
  v.velocity_mps = obj->velocity_mps;
  if (objects.table)
    v.velocity_mps -= v.velocity_mps.dot(objects.table->normal) * objects.table->normal;
  v.track_id = obj->track_id;
  v.samples = static_cast<int>(obj->trajectory.size());
  a.confidence = o.entry->confidence;
  a.value = v;
  return a;
}

std::vector<ObjectTrajectoryPoint> object_history(const PrimitiveContext& ctx, int track_id) {
  const auto e = ctx.view().get(keys::kTableObjects);
  if (!e || !e->present()) return {};
  for (const auto& o : e->value->objects)
    if (o.track_id == track_id) return o.trajectory;
  return {};
}

// The rows of the objects family: everything is answered from the toys on the table.
void register_objects_primitives(PrimitiveRegistry& r) {
  using P = PrimitiveId;
  const std::vector<std::string> table{keys::kTableObjects.name};
  r.add(P::kGetGripLocation, table, [](const PrimitiveContext& c) { return get_grip_location(c); });
  r.add(P::kGetObjects, table, get_objects);
  r.add(P::kGetObjectsCircle, table, [](const PrimitiveContext& c) {
    return get_objects_in_circle(c, c.family_options<ObjectPrimitiveOptions>().circle);
  });
  r.add(P::kGetObjectTableDistance, table,
        [](const PrimitiveContext& c) { return get_object_table_distance(c); });
  r.add(P::kIdentifyObject, table, [](const PrimitiveContext& c) { return identify_object(c); });
  r.add(P::kTrackObject, table, [](const PrimitiveContext& c) { return track_object(c); });
}

}  // namespace dreamsense::primitives
