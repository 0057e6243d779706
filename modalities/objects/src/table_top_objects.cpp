// Toys on the table: detection + identification + tracks + 3-D (see the header).

#include "dreamsense/objects/table_top_objects.hpp"

#include "dreamsense/objects/dcf_tracker.hpp"
#include "dreamsense/objects/table_geometry.hpp"

#include <algorithm>
#include <cmath>

namespace dreamsense::objects {
namespace {

constexpr double kNsPerS = 1e9;

cv::Point2d centre_of(const cv::Rect2d& b) { return {b.x + 0.5 * b.width, b.y + 0.5 * b.height}; }

}  // namespace

struct TableTopObjects::Track {
  int track_id = -1;
  std::map<int, double> votes;
  int identifications = 0;
  uint64_t last_identified = 0;
  int hits = 0;
  bool confirmed = false;
  cv::Rect2d box;
  double area_px = 0;
  cv::Point2d velocity_px{0, 0};  // px/s
  double angle_deg = 0;
  int missing = 0;
  bool updated = false;
  std::unique_ptr<Tracker> visual;
  ObjectState state;

  int best_id() const {
    int id = kUnknownObject;
    double w = -1;
    for (const auto& [k, v] : votes)
      if (v > w) w = v, id = k;
    return id;
  }
  double agreement() const {
    double sum = 0, best = 0;
    for (const auto& [k, v] : votes) sum += v, best = std::max(best, v);
    return sum > 0 ? best / sum : 0;
  }
  void vote(const Identification& idn) {
    for (auto& [k, v] : votes) v *= 0.97;  // old evidence fades: a relabelled toy gets through
    votes[idn.id] += 1.0;
    ++identifications;
  }
};

Status TableTopObjectsOptions::check() const {
  if (auto s = detector.check(); !s) return s;
  std::string bad;
  auto need = [&bad](bool ok, const char* what) {
    if (!ok) bad += bad.empty() ? what : std::string("; ") + what;
  };
  need(identifier == "gallery" || identifier == "hog_svm", "identifier must be gallery or hog_svm");
  need(reidentify_every >= 1, "reidentify_every must be >= 1");
  need(match_iou > 0 && match_iou < 1, "match_iou must be in (0, 1)");
  need(max_missing_frames >= 0, "max_missing_frames must be >= 0");
  need(confirm_frames >= 1, "confirm_frames must be >= 1");
  need(history >= 2, "history must be >= 2");
  need(velocity_window_s > 0, "velocity_window_s must be > 0");
  need(min_side_m > 0 && max_side_m > min_side_m, "need 0 < min_side_m < max_side_m");
  if (!bad.empty()) return make_error(ErrorCode::kInvalidArgument, "table-top objects: {}", bad);
  return ok_status();
}

Result<std::unique_ptr<TableTopObjects>> TableTopObjects::create(
    const TableTopObjectsOptions& options, std::shared_ptr<const ObjectGallery> gallery,
    std::optional<CameraModel> camera, std::optional<geometry::Plane> table) {
  if (auto s = options.check(); !s) return tl::unexpected(s.error());
  if (options.identifier == "hog_svm" && gallery && !gallery->has_baseline())
    return make_error(ErrorCode::kInvalidArgument,
                      "table-top objects: the gallery has no HOG + SVM baseline to identify with");
  std::unique_ptr<TableTopObjects> t(new TableTopObjects());
  t->o_ = options;
  t->gallery_ = std::move(gallery);
  t->camera_ = std::move(camera);
  t->table_ = table;
  if (t->camera_ && t->table_) {
    // Plausible blob areas from the calibration: a top face seen at the table's distance.
    const double d = t->table_->distance(t->camera_->centre_world());
    const double f = 0.5 * (t->camera_->K(0, 0) + t->camera_->K(1, 1));
    if (d > 0.05) {
      const double px = f / d;
      t->o_.detector.min_area_px = std::max(16.0, std::pow(options.min_side_m * px, 2) * 0.5);
      t->o_.detector.max_area_px = std::pow(options.max_side_m * px, 2) * 1.5;
    }
  }
  t->detector_ = TableTopDetector(t->o_.detector);
  return t;
}

TableTopObjects::~TableTopObjects() = default;

void TableTopObjects::reset() {
  detector_.reset();
  tracks_.clear();
  histories_.clear();
  previous_.release();
  frame_ = 0;
}

const std::deque<ObjectState>& TableTopObjects::history(int track_id) const {
  static const std::deque<ObjectState> empty;
  const auto it = histories_.find(track_id);
  return it == histories_.end() ? empty : it->second;
}

void TableTopObjects::finish_state(Track& t, int64_t stamp_ns) {
  ObjectState& s = t.state;
  s.stamp_ns = stamp_ns;
  s.track_id = t.track_id;
  s.id = t.best_id();
  s.id_score = t.agreement();
  s.label = "unknown";
  s.size_m = cv::Vec3d(0.10, 0.075, 0.0);
  if (gallery_) {
    if (const ObjectClass* c = gallery_->find(s.id)) s.label = c->label, s.size_m = c->size_m;
  }
  s.box = t.box;
  s.image_angle_deg = t.angle_deg;
  s.detected = t.missing == 0;
  s.missing_frames = t.missing;
  s.position_m.reset();
  s.axis_m.reset();
  if (camera_ && table_) {
    const double h = s.size_m[2];
    const cv::Point2d c = centre_of(t.box);
    if (auto mid = pixel_on_plane(*camera_, c, *table_, 0.5 * h)) {
      s.position_m = *mid + 0.5 * h * table_->normal;
      const double a = t.angle_deg * CV_PI / 180.0;
      const cv::Point2d d(10 * std::cos(a), 10 * std::sin(a));
      const auto p1 = pixel_on_plane(*camera_, c - d, *table_, h);
      const auto p2 = pixel_on_plane(*camera_, c + d, *table_, h);
      if (p1 && p2 && cv::norm(*p2 - *p1) > 1e-9) s.axis_m = cv::normalize(*p2 - *p1);
    }
  }
  auto& h = histories_[t.track_id];
  if (s.position_m) {
    std::deque<ObjectState> tmp = h;
    tmp.push_back(s);
    s.velocity_mps = estimate_velocity(tmp, o_.velocity_window_s);
  }
  h.push_back(s);
  while (h.size() > o_.history) h.pop_front();
}

Result<std::vector<ObjectState>> TableTopObjects::process(const cv::Mat& bgr, int64_t stamp_ns) {
  if (bgr.empty() || bgr.type() != CV_8UC3)
    return make_error(ErrorCode::kInvalidArgument, "table-top objects: need a BGR frame");
  ++frame_;
  const double dt = previous_.empty() ? 0.0 : (stamp_ns - previous_stamp_) / kNsPerS;
  std::vector<cv::Rect> occupied;
  for (const auto& t : tracks_) occupied.push_back(cv::Rect(t->box));
  auto cands = detector_.detect(bgr, occupied);
  if (!cands) return tl::unexpected(cands.error());

  // Match candidates to the tracks' predicted boxes by overlap, greedily.
  std::vector<cv::Rect2d> predicted;
  for (auto& t : tracks_) {
    t->updated = false;
    cv::Rect2d p = t->box;
    p.x += t->velocity_px.x * dt;
    p.y += t->velocity_px.y * dt;
    predicted.push_back(p);
  }
  struct Pair {
    double iou;
    size_t c, t;
  };
  std::vector<Pair> pairs;
  for (size_t c = 0; c < cands->size(); ++c)
    for (size_t k = 0; k < tracks_.size(); ++k) {
      const double v = iou(cv::Rect2d((*cands)[c].box), predicted[k]);
      if (v >= o_.match_iou) pairs.push_back({v, c, k});
    }
  std::sort(pairs.begin(), pairs.end(), [](const Pair& a, const Pair& b) { return a.iou > b.iou; });
  std::vector<int> cand_track(cands->size(), -1);
  std::vector<char> track_taken(tracks_.size(), 0);
  for (const auto& p : pairs)
    if (cand_track[p.c] < 0 && !track_taken[p.t])
      cand_track[p.c] = static_cast<int>(p.t), track_taken[p.t] = 1;

  // Pieces of a toy: a small blob touching the box of a bigger blob that a known toy's track
  // claims (a picture with table-coloured parts falls apart) is merged into it.
  std::vector<char> absorbed(cands->size(), 0);
  for (size_t c = 0; c < cands->size(); ++c) {
    if (cand_track[c] < 0 ||
        tracks_[static_cast<size_t>(cand_track[c])]->best_id() == kUnknownObject)
      continue;
    ObjectCandidate& main = (*cands)[c];
    for (size_t k = 0; k < cands->size(); ++k) {
      if (k == c || absorbed[k] || cand_track[k] >= 0) continue;
      const ObjectCandidate& piece = (*cands)[k];
      const cv::Rect grown(main.box.x - 4, main.box.y - 4, main.box.width + 8, main.box.height + 8);
      if (piece.area_px >= main.area_px || (grown & piece.box).empty()) continue;
      const cv::Rect u = main.box | piece.box;
      cv::Mat mask = cv::Mat::zeros(u.size(), CV_8U);
      main.mask.copyTo(mask(main.box - u.tl()));
      cv::Mat part = mask(piece.box - u.tl());
      cv::bitwise_or(part, piece.mask, part);
      main.box = u;
      main.mask = mask;
      main.area_px += piece.area_px;
      absorbed[k] = 1;
    }
  }

  auto identify = [&](const ObjectCandidate& c) -> std::optional<Identification> {
    if (!gallery_) return Identification{};
    auto view = make_view(bgr, c.box, c.mask, c.footprint);
    if (!view) return std::nullopt;
    return o_.identifier == "hog_svm" ? gallery_->identify_baseline(*view)
                                      : gallery_->identify(*view);
  };
  auto accept = [&](Track& t, const ObjectCandidate& c, const std::optional<Identification>& idn) {
    const cv::Point2d prev = centre_of(t.box), now = centre_of(cv::Rect2d(c.box));
    if (t.hits > 0 && dt > 0) {
      const cv::Point2d v = (now - prev) * (1.0 / dt);
      t.velocity_px = t.missing == 0 ? 0.5 * t.velocity_px + 0.5 * v : v;
    }
    t.box = cv::Rect2d(c.box);
    t.area_px = c.area_px;
    t.angle_deg = c.footprint.size.width >= c.footprint.size.height ? c.footprint.angle
                                                                    : c.footprint.angle + 90.0;
    t.missing = 0;
    t.visual.reset();
    t.updated = true;
    ++t.hits;
    if (idn) {
      t.vote(*idn);
      t.last_identified = frame_;
    }
    // A toy the gallery knows is reported at once; an unknown blob after confirm_frames.
    if (t.hits >= o_.confirm_frames || t.best_id() != kUnknownObject) t.confirmed = true;
  };

  for (size_t c = 0; c < cands->size(); ++c) {
    if (absorbed[c]) continue;
    const ObjectCandidate& cand = (*cands)[c];
    Track* t = cand_track[c] >= 0 ? tracks_[static_cast<size_t>(cand_track[c])].get() : nullptr;
    // Identify new blobs, young tracks, and every reidentify_every frames; a blob at the edge
    // that no track claims (a resting hand, most often) only every reidentify_every frames.
    const bool periodic = frame_ % static_cast<uint64_t>(o_.reidentify_every) == 0;
    const bool need_id =
        t ? t->identifications < 3 ||
                frame_ - t->last_identified >= static_cast<uint64_t>(o_.reidentify_every)
          : !cand.touches_edge || periodic;
    std::optional<Identification> idn;
    if (need_id) idn = identify(cand);
    if (t) {
      // A blob that reaches the table's edge and grew is a hand holding the toy: not its box.
      if (cand.touches_edge &&
          (cand.area_px > 1.5 * t->area_px || (idn && idn->id != t->best_id()))) {
        track_taken[static_cast<size_t>(cand_track[c])] = 0;
        continue;
      }
      accept(*t, cand, idn);
      continue;
    }
    if (!idn) continue;
    if (idn->id != kUnknownObject) {
      // A known toy that nobody claimed: the track it had before (re-detection), if any.
      for (size_t k = 0; k < tracks_.size() && !t; ++k)
        if (!track_taken[k] && tracks_[k]->best_id() == idn->id)
          t = tracks_[k].get(), track_taken[k] = 1;
    } else if (cand.touches_edge) {
      continue;  // an arm or hand coming in over the edge
    }
    if (!t) {
      tracks_.push_back(std::make_unique<Track>());
      t = tracks_.back().get();
      t->track_id = next_track_++;
      track_taken.push_back(1);
    }
    accept(*t, cand, idn);
  }

  // Tracks without a detection: the visual tracker (started on the last frame they were seen
  // in) or the constant-velocity prediction; dropped after max_missing_frames.
  for (size_t k = 0; k < tracks_.size(); ++k) {
    Track& t = *tracks_[k];
    if (t.updated) continue;
    ++t.missing;
    if (t.best_id() == kUnknownObject) continue;  // unknown blobs are not carried
    cv::Rect2d next = k < predicted.size() ? predicted[k] : t.box;
    if (o_.visual_tracker && t.confirmed && !previous_.empty()) {
      if (!t.visual) {
        auto v = std::make_unique<DcfTracker>();
        if (v->init(previous_, t.box)) t.visual = std::move(v);
      }
      if (t.visual) {
        auto u = t.visual->update(bgr);
        if (u && u->found) next = u->box;
      }
    }
    t.box = next;
  }
  const cv::Rect2d image(0, 0, bgr.cols, bgr.rows);
  tracks_.erase(std::remove_if(tracks_.begin(), tracks_.end(),
                               [&](const auto& t) {
                                 const bool unknown = t->best_id() == kUnknownObject;
                                 const bool gone = (t->box & image).area() < 0.5 * t->box.area();
                                 const int limit =
                                     unknown ? o_.confirm_frames : o_.max_missing_frames;
                                 if (t->missing <= limit && !gone) return false;
                                 histories_.erase(t->track_id);
                                 return true;
                               }),
                tracks_.end());

  std::vector<ObjectState> out;
  for (auto& t : tracks_) {
    finish_state(*t, stamp_ns);
    // Known toys are reported while occluded (detected = false); unknown blobs only when seen.
    if (t->confirmed && (t->missing == 0 || t->best_id() != kUnknownObject))
      out.push_back(t->state);
  }
  bgr.copyTo(previous_);
  previous_stamp_ = stamp_ns;
  return out;
}

// ---- geometry ----

std::optional<TableDistance> table_distance(const ObjectState& o, const geometry::Plane& table,
                                            bool measured) {
  if (!o.position_m) return std::nullopt;
  TableDistance d;
  d.top_m = table.signed_distance(*o.position_m);
  d.lift_m = std::max(0.0, d.top_m - o.size_m[2]);
  d.measured = measured;
  return d;
}

Status GripOptions::check() const {
  if (!(max_opening_m > 0) || !(clearance_m >= 0))
    return make_error(ErrorCode::kInvalidArgument,
                      "grip: need max_opening_m > 0, clearance_m >= 0");
  return ok_status();
}

std::optional<Grip> grip_location(const ObjectState& o, const geometry::Plane& table,
                                  const GripOptions& opt) {
  if (!o.position_m) return std::nullopt;
  const cv::Vec3d up = table.normal;
  cv::Vec3d along = o.axis_m ? *o.axis_m : cv::Vec3d(1, 0, 0);
  along -= along.dot(up) * up;  // horizontal
  if (cv::norm(along) < 1e-9) return std::nullopt;
  along = cv::normalize(along);
  const cv::Vec3d across = cv::normalize(up.cross(along));
  const double len = o.size_m[0], wid = o.size_m[1], h = o.size_m[2];
  Grip g;
  g.point_m = *o.position_m - 0.5 * h * up;
  g.approach = -up;
  if (wid + opt.clearance_m <= opt.max_opening_m) {
    g.closing_axis = across;
    g.opening_m = wid + opt.clearance_m;
  } else if (len + opt.clearance_m <= opt.max_opening_m) {
    g.closing_axis = along;
    g.opening_m = len + opt.clearance_m;
  } else {
    return std::nullopt;
  }
  return g;
}

cv::Vec3d estimate_velocity(const std::deque<ObjectState>& h, double window_s) {
  if (h.size() < 2) return {0, 0, 0};
  const int64_t t_last = h.back().stamp_ns;
  double st = 0, stt = 0, n = 0;
  cv::Vec3d sp(0, 0, 0), stp(0, 0, 0);
  for (auto it = h.rbegin(); it != h.rend(); ++it) {
    const double t = (it->stamp_ns - t_last) / kNsPerS;
    if (-t > window_s) break;
    if (!it->position_m) continue;
    st += t, stt += t * t, n += 1;
    sp += *it->position_m;
    stp += t * *it->position_m;
  }
  const double den = n * stt - st * st;
  if (n < 2 || den <= 1e-12) return {0, 0, 0};
  return (n * stp - st * sp) * (1.0 / den);
}

std::optional<cv::Vec3d> predict_position(const std::deque<ObjectState>& h, double dt_s,
                                          double window_s,
                                          const std::optional<geometry::Plane>& table) {
  const ObjectState* last = nullptr;
  for (auto it = h.rbegin(); it != h.rend() && !last; ++it)
    if (it->position_m) last = &*it;
  if (!last) return std::nullopt;
  const cv::Vec3d v = estimate_velocity(h, window_s);
  const double gap = (h.back().stamp_ns - last->stamp_ns) / kNsPerS;
  cv::Vec3d p = *last->position_m + v * (gap + dt_s);
  if (table) {  // stays at the same height above the table
    const double keep = table->signed_distance(*last->position_m);
    p -= (table->signed_distance(p) - keep) * table->normal;
  }
  return p;
}

std::vector<ObjectState> objects_in_circle(const std::vector<ObjectState>& objects,
                                           const cv::Vec3d& centre, double radius,
                                           const geometry::Plane& table) {
  std::vector<std::pair<double, ObjectState>> in;
  const cv::Vec3d c = table.project(centre);
  for (const auto& o : objects) {
    if (!o.position_m) continue;
    const double d = cv::norm(table.project(*o.position_m) - c);
    if (d <= radius) in.emplace_back(d, o);
  }
  std::stable_sort(in.begin(), in.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<ObjectState> out;
  for (auto& p : in) out.push_back(std::move(p.second));
  return out;
}

}  // namespace dreamsense::objects
