#include "dreamsense/eval/faces/identity_eval.hpp"

#include "dreamsense/eval/classification.hpp"
#include "dreamsense/eval/faces/datasets.hpp"
#include "dreamsense/face_identity/face_gallery.hpp"
#include "dreamsense/vision/face_locator.hpp"
#include "dreamsense/vision/image_io.hpp"

#include <opencv2/core.hpp>

#include <algorithm>
#include <chrono>
#include <map>
#include <set>

namespace dreamsense::eval::faces {
namespace {}  // namespace

Status FaceIdEvalOptions::check() const {
  if (enroll < 1) return make_error(ErrorCode::kInvalidArgument, "--enroll must be >= 1");
  if (unknown < 0) return make_error(ErrorCode::kInvalidArgument, "--unknown must be >= 0");
  if (methods.empty()) return make_error(ErrorCode::kInvalidArgument, "no identity method");
  return crop.check();
}

Result<EvalReport> run_face_id_eval(const FaceIdEvalOptions& o, const Progress& progress) {
  if (auto s = o.check(); !s) return tl::unexpected(s.error());
  auto items = read_identity_dataset(o.dataset, o.dir);
  if (!items) return tl::unexpected(items.error());
  std::vector<face_identity::IdentityMethod> methods;
  for (const auto& n : o.methods) {
    auto m = face_identity::identity_method(n);
    if (!m) return tl::unexpected(m.error());
    methods.push_back(std::move(*m));
  }
  // Subjects (items are sorted by subject, then image).
  std::vector<std::string> subjects;
  for (const auto& it : *items)
    if (subjects.empty() || subjects.back() != it.subject) subjects.push_back(it.subject);
  if (o.unknown >= static_cast<int>(subjects.size()))
    return make_error(ErrorCode::kInvalidArgument,
                      "--unknown {} leaves no subject to enrol ({} subjects)", o.unknown,
                      subjects.size());
  const std::set<std::string> unknown(subjects.end() - o.unknown, subjects.end());
  std::map<std::string, int> ids;
  for (size_t s = 0; s < subjects.size(); ++s) ids[subjects[s]] = static_cast<int>(s);

  // Align every image once per distinct alignment geometry.
  auto landmarker = vision::load_landmarker();
  if (!landmarker) return tl::unexpected(landmarker.error());
  struct Prepared {
    cv::Mat grey;
    std::optional<vision::AlignedFace> face;
    bool enrol = false;
  };
  std::vector<std::pair<vision::AlignmentOptions, std::vector<Prepared>>> aligned;
  std::vector<double> align_ms;
  std::map<std::string, size_t> sources{
      {"landmarks", 0}, {"landmarks_from_crop", 0}, {"crop_geometry", 0}, {"no_face", 0}};
  for (const auto& m : methods) {
    if (std::any_of(aligned.begin(), aligned.end(),
                    [&](const auto& a) { return a.first == m.alignment; }))
      continue;
    vision::FaceCropOptions crop = o.crop;
    crop.alignment = m.alignment;
    auto aligner = vision::make_face_crop_aligner(crop, *landmarker);
    if (!aligner) return tl::unexpected(aligner.error());
    std::vector<Prepared> prepared(items->size());
    std::map<std::string, int> seen;
    const bool first = aligned.empty();
    for (size_t i = 0; i < items->size(); ++i) {
      const auto& it = (*items)[i];
      auto grey = vision::read_grey_image(it.path);
      if (!grey) return tl::unexpected(grey.error());
      prepared[i].grey = *grey;
      const auto t0 = std::chrono::steady_clock::now();
      auto face = aligner->align(*grey);
      if (first) align_ms.push_back(ms_since(t0));
      if (!face)
        return make_error(face.error().code, "{}: {}", it.path.string(), face.error().message);
      prepared[i].face = std::move(*face);
      if (first)
        ++sources[prepared[i].face ? vision::to_string(prepared[i].face->source) : "no_face"];
      prepared[i].enrol = !unknown.count(it.subject) && seen[it.subject]++ < o.enroll;
      if (progress && i % 8 == 0) progress(0.5 * (i + 1.0) / items->size());
    }
    aligned.emplace_back(m.alignment, std::move(prepared));
  }

  std::vector<std::string> known_labels;
  for (const auto& s : subjects)
    if (!unknown.count(s)) known_labels.push_back(s);
  EvalReport report;
  report.task = "faces";
  report.dataset = o.dataset;
  nlohmann::json method_names = nlohmann::json::array();
  size_t known_probes = 0, unknown_probes = 0;
  for (size_t mi = 0; mi < methods.size(); ++mi) {
    const auto& m = methods[mi];
    const std::vector<Prepared>& prepared =
        std::find_if(aligned.begin(), aligned.end(), [&](const auto& a) {
          return a.first == m.alignment;
        })->second;
    auto extractor = face_identity::IdentityFeatureExtractor::create(m);
    if (!extractor) return tl::unexpected(extractor.error());
    face_identity::FaceGallery gallery(m, extractor->weights_hash());
    std::vector<std::vector<float>> features(items->size());
    for (size_t i = 0; i < items->size(); ++i) {
      if (!prepared[i].face) continue;
      features[i] = extractor->extract(prepared[i].grey, *prepared[i].face);
      if (prepared[i].enrol)
        if (auto s = gallery.add(ids[(*items)[i].subject], features[i]); !s)
          return tl::unexpected(s.error());
    }
    auto identifier = face_identity::FaceIdentifier::create(std::move(gallery));
    if (!identifier) return tl::unexpected(identifier.error());
    ConfusionMatrix cm(known_labels, "unknown");
    size_t closed_correct = 0, rejected_known = 0, accepted_unknown = 0;
    known_probes = unknown_probes = 0;
    std::vector<double> ms;
    const int threads = cv::getNumThreads();
    cv::setNumThreads(1);
    for (size_t i = 0; i < items->size(); ++i) {
      if (prepared[i].enrol) continue;
      const auto& it = (*items)[i];
      face_identity::IdentityResult r;
      if (prepared[i].face) {
        const auto t0 = std::chrono::steady_clock::now();
        const vision::AlignedFace f =
            vision::warp_face(prepared[i].grey, prepared[i].face->crop_from_image, m.alignment,
                              prepared[i].face->source);
        r = identifier->identify(extractor->extract(prepared[i].grey, f));
        ms.push_back(ms_since(t0));
      }
      const std::string predicted = r.id >= 0 ? subjects[static_cast<size_t>(r.id)] : "unknown";
      if (unknown.count(it.subject)) {
        ++unknown_probes;
        if (r.id >= 0) ++accepted_unknown;
      } else {
        ++known_probes;
        cm.add(it.subject, predicted);
        if (r.best_id >= 0 && subjects[static_cast<size_t>(r.best_id)] == it.subject)
          ++closed_correct;
        if (r.id < 0) ++rejected_known;
      }
    }
    cv::setNumThreads(threads);
    const auto frac = [](size_t a, size_t b) {
      return b ? nlohmann::json(static_cast<double>(a) / b) : nlohmann::json(nullptr);
    };
    nlohmann::json mj = {{"accuracy", number_or_null(cm.accuracy())},
                         {"false_accept_rate", frac(accepted_unknown, unknown_probes)},
                         {"closed_set_accuracy", frac(closed_correct, known_probes)},
                         {"false_reject_rate", frac(rejected_known, known_probes)},
                         {"threshold", identifier->threshold()},
                         {"threshold_from_enrolment", identifier->threshold_from_enrolment()},
                         {"enrolled_images", identifier->gallery().images()}};
    if (mi == 0) {
      for (const auto& [k, v] : mj.items()) report.metrics[k] = v;
      report.per_class = cm.per_class_json();
      report.timing["ms_per_face_median"] = number_or_null(median(ms));
    }
    report.metrics[m.name] = mj;
    report.timing[m.name] = {{"ms_per_face_median", number_or_null(median(ms))}};
    method_names.push_back(m.name);
    if (progress) progress(0.5 + 0.5 * (mi + 1.0) / methods.size());
  }
  report.items = known_probes + unknown_probes;
  report.timing["ms_alignment_median"] = number_or_null(median(align_ms));
  std::string names;
  for (const auto& m : methods) names += (names.empty() ? "" : ", ") + m.name;
  report.protocol = fmt::format(
      "{} subjects in natural order; the last {} never enrol (all their images are probes to "
      "reject); the first {} images of every other subject enrol, the rest are probes; "
      "rejection threshold chosen on the enrolment data only (leave-one-out); methods {}",
      subjects.size(), o.unknown, o.enroll, names);
  report.extra = {{"alignment", sources},
                  {"methods", method_names},
                  {"known_probes", known_probes},
                  {"unknown_probes", unknown_probes},
                  {"enrolled_subjects", known_labels.size()}};
  return report;
}

}  // namespace dreamsense::eval::faces
