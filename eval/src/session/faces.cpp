// Face identity (F17) and expression (F18) against the truth `face` records of the same tick
// (faces, issue 12). A tick counts when its truth face is visible in at least one camera.
//  - face_identity_ok_rate: such ticks with an ok identifyFace / such ticks.
//  - face_identity_accuracy: ok identifyFace answers naming the truth `person` (the gallery's
//    name of the enrolled child, i.e. the session's subject, or "unknown" for a face the gallery
//    does not enrol, which must be answered -1) / ok answers. Not evaluated when the truth has no
//    person. An analysis made without --include-names has ids only (privacy, docs/outputs.md):
//    an answer without a name is compared by id with the truth's `person_id` (the gallery id;
//    -1 for "unknown"), and cannot be judged when the truth has none.
//  - expression_ok_rate, expression_accuracy: the same for identifyFaceExpression's label
//    against the truth `expression` (the demo's portrait shows one expression throughout, so
//    this checks the chain and the absence of flicker, not the discrimination of expressions).

#include "dreamsense/eval/session_metrics.hpp"

#include <map>
#include <optional>

namespace dreamsense::eval {
using primitives::PrimitiveId;

namespace {

bool face_visible(const nlohmann::json& t) {
  if (!t.contains("cameras")) return false;
  for (const auto& [cam, c] : t["cameras"].items())
    if (c.value("visible", false)) return true;
  return false;
}

}  // namespace

MetricGroup face_recognition_metrics() {
  MetricGroup g;
  g.name = "face_recognition";
  g.metrics = {{"face_identity_ok_rate", PrimitiveId::kIdentifyFace},
               {"face_identity_accuracy", PrimitiveId::kIdentifyFace},
               {"expression_ok_rate", PrimitiveId::kIdentifyFaceExpression},
               {"expression_accuracy", PrimitiveId::kIdentifyFaceExpression}};
  g.compute = [](const SessionData& d, nlohmann::json& metrics, nlohmann::json& not_evaluated) {
    std::map<int64_t, const nlohmann::json*> truth;
    for (const auto* t : d.truth_of("face"))
      if (face_visible(*t)) truth[t->value("stamp_ns", int64_t{0})] = t;
    // right_of(record, truth face) -> nullopt when the truth cannot judge the answer.
    auto evaluate = [&](PrimitiveId id, const char* field, const char* ok_rate,
                        const char* accuracy, auto right_of) {
      if (!d.enabled(id)) return;
      int ticks = 0, answered = 0, right = 0;
      bool has_truth = false;
      for (const auto* r : d.of(id)) {
        const auto it = truth.find(r->stamp.ns());
        if (it == truth.end()) continue;
        ++ticks;
        if (!r->ok()) continue;
        ++answered;
        const std::optional<bool> verdict = right_of(*r, *it->second);
        if (!verdict) continue;
        has_truth = true;
        right += *verdict;
      }
      if (ticks == 0) {
        not_evaluated[ok_rate] = "no tick with a visible truth face";
        not_evaluated[accuracy] = "no tick with a visible truth face";
        return;
      }
      metrics[ok_rate] = static_cast<double>(answered) / ticks;
      if (!has_truth || answered == 0)
        not_evaluated[accuracy] =
            std::string("the truth faces have no ") + field + " (or nothing was answered)";
      else
        metrics[accuracy] = static_cast<double>(right) / answered;
    };
    evaluate(
        PrimitiveId::kIdentifyFace, "person", "face_identity_ok_rate", "face_identity_accuracy",
        [](const primitives::PrimitiveRecord& r, const nlohmann::json& t) -> std::optional<bool> {
          const nlohmann::json& person = t.value("person", nlohmann::json(nullptr));
          if (!person.is_string()) return std::nullopt;
          const auto* v = r.value_as<primitives::FaceIdentityValue>();
          if (v == nullptr) return false;
          if (v->id < 0) return person.get<std::string>() == "unknown";
          if (!v->name.empty()) return v->name == person.get<std::string>();
          // Ids only (an analysis without --include-names): by the gallery id.
          const nlohmann::json& id = t.value("person_id", nlohmann::json(nullptr));
          if (!id.is_number_integer()) return std::nullopt;
          return v->id == id.get<int>();
        });
    evaluate(
        PrimitiveId::kIdentifyFaceExpression, "expression", "expression_ok_rate",
        "expression_accuracy",
        [](const primitives::PrimitiveRecord& r, const nlohmann::json& t) -> std::optional<bool> {
          const nlohmann::json& want = t.value("expression", nlohmann::json(nullptr));
          if (!want.is_string()) return std::nullopt;
          const auto* v = r.value_as<primitives::ClassLabelValue>();
          return v != nullptr && v->label == want.get<std::string>();
        });
  };
  return g;
}

}  // namespace dreamsense::eval
