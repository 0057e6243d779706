// Labelled toy views from crops or recordings, and the gallery built from them.

#include "dreamsense/eval/object_enrolment.hpp"

#include "dreamsense/objects/table_detector.hpp"
#include "dreamsense/objects/tracker.hpp"
#include "dreamsense/sources/session.hpp"
#include "dreamsense/sources/truth.hpp"

#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <fstream>
#include <map>
#include <sstream>

namespace dreamsense::eval {
namespace fs = std::filesystem;
namespace {

struct Box {
  int64_t key;  // frame index or stamp
  std::string label;
  cv::Rect2d box;
};

Result<std::vector<Box>> read_box_csv(const fs::path& file) {
  std::ifstream in(file);
  if (!in) return make_error(ErrorCode::kNotFound, "{}: cannot open", file.string());
  std::vector<Box> out;
  std::string line;
  for (int n = 1; std::getline(in, line); ++n) {
    if (line.empty() || line[0] == '#') continue;
    std::replace_if(
        line.begin(), line.end(), [](char c) { return c == ',' || c == '\t' || c == '\r'; }, ' ');
    std::istringstream ss(line);
    Box b;
    double x, y, w, h;
    std::string extra;
    if (!(ss >> b.key >> b.label >> x >> y >> w >> h) || (ss >> extra) || w <= 0 || h <= 0)
      return make_error(ErrorCode::kCorruptData,
                        "{}:{}: expected 'frame,label,x,y,w,h' with w, h > 0", file.string(), n);
    if (n == 1 && b.label == "label") continue;  // header
    b.box = cv::Rect2d(x, y, w, h);
    out.push_back(b);
  }
  if (out.empty()) return make_error(ErrorCode::kCorruptData, "{}: no boxes", file.string());
  return out;
}

}  // namespace

Result<objects::ObjectClass> parse_object_class(const std::string& text) {
  objects::ObjectClass c;
  const auto eq = text.find('=');
  if (eq == std::string::npos || eq == 0)
    return make_error(ErrorCode::kInvalidArgument, "--class '{}': expected label=id[:LxWxH]", text);
  c.label = text.substr(0, eq);
  std::string rest = text.substr(eq + 1);
  const auto colon = rest.find(':');
  try {
    size_t used = 0;
    c.id = std::stoi(rest.substr(0, colon), &used);
    if (used != (colon == std::string::npos ? rest.size() : colon) || c.id < 0)
      throw std::invalid_argument("id");
    if (colon != std::string::npos) {
      std::string s = rest.substr(colon + 1);
      std::replace(s.begin(), s.end(), 'x', ' ');
      std::istringstream ss(s);
      std::string extra;
      if (!(ss >> c.size_m[0] >> c.size_m[1] >> c.size_m[2]) || (ss >> extra) || c.size_m[0] <= 0 ||
          c.size_m[1] <= 0 || c.size_m[2] < 0)
        throw std::invalid_argument("size");
    }
  } catch (const std::exception&) {
    return make_error(ErrorCode::kInvalidArgument,
                      "--class '{}': expected label=id[:LxWxH] with id >= 0 and sizes in metres",
                      text);
  }
  return c;
}

Status ObjectEnrolmentOptions::check() const {
  if (!crops && sessions.empty())
    return make_error(ErrorCode::kInvalidArgument,
                      "enroll objects: give --crops DIR or --session DIR");
  if (boxes && sessions.size() != 1)
    return make_error(ErrorCode::kInvalidArgument,
                      "enroll objects: --boxes goes with exactly one --session");
  if (frame_step < 1)
    return make_error(ErrorCode::kInvalidArgument, "enroll objects: --frame-step must be >= 1");
  return gallery.check();
}

Result<ObjectEnrolmentResult> enrol_objects(const ObjectEnrolmentOptions& o) {
  if (auto s = o.check(); !s) return tl::unexpected(s.error());
  std::optional<objects::ObjectGallery> base;
  if (o.base) {
    auto g = objects::ObjectGallery::load(*o.base);
    if (!g) return tl::unexpected(g.error());
    base = std::move(*g);
  }
  // Label -> class: the base gallery's, the DREAM toys, then --class overrides; new labels get
  // the next free id.
  std::vector<objects::ObjectClass> known = base ? base->classes() : objects::dream_toy_classes();
  if (base)
    for (const auto& d : objects::dream_toy_classes())
      if (!base->find(d.id)) known.push_back(d);
  for (const auto& c : o.classes) {
    auto it =
        std::find_if(known.begin(), known.end(), [&](const auto& k) { return k.label == c.label; });
    if (it != known.end())
      *it = c;
    else
      known.push_back(c);
  }
  auto class_of = [&](const std::string& label) -> const objects::ObjectClass& {
    auto it =
        std::find_if(known.begin(), known.end(), [&](const auto& k) { return k.label == label; });
    if (it != known.end()) return *it;
    int next = 0;
    for (const auto& k : known) next = std::max(next, k.id + 1);
    known.push_back({next, label, {0.10, 0.075, 0.03}});
    return known.back();
  };
  auto class_of_id = [&](int id) -> const objects::ObjectClass* {
    for (const auto& k : known)
      if (k.id == id) return &k;
    return nullptr;
  };

  std::vector<objects::LabelledView> views;
  std::vector<cv::Mat> keep;  // the frames the views point into
  if (o.crops) {
    std::error_code ec;
    if (!fs::is_directory(*o.crops, ec))
      return make_error(ErrorCode::kNotFound, "{}: no such crops folder", o.crops->string());
    std::vector<fs::path> dirs;
    for (const auto& e : fs::directory_iterator(*o.crops, ec))
      if (e.is_directory()) dirs.push_back(e.path());
    std::sort(dirs.begin(), dirs.end());
    for (const auto& d : dirs) {
      const objects::ObjectClass& c = class_of(d.filename().string());
      std::vector<fs::path> files;
      for (const auto& e : fs::directory_iterator(d, ec)) {
        std::string ext = e.path().extension().string();
        std::transform(ext.begin(), ext.end(), ext.begin(), ::tolower);
        if (ext == ".png" || ext == ".jpg" || ext == ".jpeg" || ext == ".bmp")
          files.push_back(e.path());
      }
      std::sort(files.begin(), files.end());
      for (const auto& f : files) {
        cv::Mat img = cv::imread(f.string(), cv::IMREAD_COLOR);
        if (img.empty())
          return make_error(ErrorCode::kCorruptData, "{}: cannot decode image", f.string());
        auto v = objects::make_view(img, cv::Rect(0, 0, img.cols, img.rows));
        if (!v) return make_error(v.error().code, "{}: {}", f.string(), v.error().message);
        keep.push_back(img);
        views.push_back({c.id, *v});
      }
    }
  }
  for (const auto& session : o.sessions) {
    auto manifest = sources::read_manifest(session);
    if (!manifest) return tl::unexpected(manifest.error());
    if (!manifest->find(o.camera))
      return make_error(ErrorCode::kNotFound, "{}: no stream '{}'", session.string(), o.camera);
    // Boxes: key -> (label, box).
    std::multimap<int64_t, std::pair<std::string, cv::Rect2d>> boxes;
    bool by_stamp = o.boxes_by_stamp;
    if (o.boxes) {
      auto b = read_box_csv(*o.boxes);
      if (!b) return tl::unexpected(b.error());
      for (const auto& x : *b) boxes.emplace(x.key, std::make_pair(x.label, x.box));
    } else {
      if (manifest->truth.empty())
        return make_error(ErrorCode::kNotFound, "{}: no truth.jsonl; give --boxes FILE",
                          session.string());
      auto truth = sources::read_truth(session / manifest->truth);
      if (!truth) return tl::unexpected(truth.error());
      by_stamp = true;
      for (const auto& r : *truth) {
        if (r.value("type", "") != "object") continue;
        const int id = r.at("label").get<int>();
        const objects::ObjectClass* c = class_of_id(id);
        const std::string label = c ? c->label : r.value("label_name", std::to_string(id));
        if (!c) class_of(label);
        const auto& b = r.at("top_box");
        boxes.emplace(r.at("stamp_ns").get<int64_t>(),
                      std::make_pair(label, cv::Rect2d(b[0], b[1], b[2], b[3])));
      }
    }
    sources::SessionReaderOptions ro;
    ro.only = {o.camera};
    auto reader = sources::SessionReader::open(session, ro);
    if (!reader) return tl::unexpected(reader.error());
    objects::TableTopDetector detector;
    int64_t index = -1;
    for (;;) {
      auto f = (*reader)->next();
      if (!f) {
        if (f.error().code == ErrorCode::kEndOfStream) break;
        return tl::unexpected(f.error());
      }
      const ColorImage* img = (*f)->as<ColorImage>();
      if (!img) continue;
      ++index;
      // The detector learns its background from every frame; views from every n-th.
      auto cands = detector.detect(img->image);
      if (!cands) return tl::unexpected(cands.error());
      if (index % o.frame_step) continue;
      const int64_t key = by_stamp ? (*f)->stamp.ns() : index;
      const auto range = boxes.equal_range(key);
      for (auto it = range.first; it != range.second; ++it) {
        const objects::ObjectClass& c = class_of(it->second.first);
        const cv::Rect2d& want = it->second.second;
        const objects::ObjectCandidate* best = nullptr;
        double best_iou = 0.5;
        for (const auto& cand : *cands) {
          const double v = objects::iou(cv::Rect2d(cand.box), want);
          if (v >= best_iou) best_iou = v, best = &cand;
        }
        cv::Mat frame = img->image;
        Result<objects::ObjectView> v = best ? objects::make_view(frame, best->box, best->mask)
                                             : objects::make_view(frame, cv::Rect(want));
        if (!v) continue;  // a box outside the frame: skipped
        keep.push_back(frame);
        views.push_back({c.id, *v});
      }
    }
  }
  if (views.empty())
    return make_error(ErrorCode::kInvalidArgument, "enroll objects: no views found");
  // Only the classes that have views (or are already in the base gallery).
  std::vector<objects::ObjectClass> classes;
  for (const auto& k : known) {
    const bool has =
        std::any_of(views.begin(), views.end(), [&](const auto& v) { return v.id == k.id; });
    if (has || (base && base->find(k.id))) classes.push_back(k);
  }
  ObjectEnrolmentResult out{objects::ObjectGallery{}, {}};
  if (base) {
    if (auto s = base->add(classes, views); !s) return tl::unexpected(s.error());
    out.gallery = std::move(*base);
  } else {
    auto g = objects::ObjectGallery::enrol(classes, views, o.gallery);
    if (!g) return tl::unexpected(g.error());
    out.gallery = std::move(*g);
  }
  for (const auto& c : classes) {
    const int n = static_cast<int>(
        std::count_if(views.begin(), views.end(), [&](const auto& v) { return v.id == c.id; }));
    out.views_per_label.emplace_back(c.label, n);
  }
  return out;
}

}  // namespace dreamsense::eval
