#include "dreamsense/primitives/face_recognition.hpp"

#include "dreamsense/perception/expression.hpp"
#include "dreamsense/perception/face_identity.hpp"
#include "dreamsense/primitives/registry.hpp"

#include <array>

namespace dreamsense::primitives {

Answer<FaceIdentityValue> identify_face(const PrimitiveContext& ctx) {
  const auto o = ctx.observe(keys::kFaceIdentity);
  auto a = Answer<FaceIdentityValue>::from(o);
  if (a.status != PrimitiveStatus::kOk) return a;
  const FaceIdentity& f = o.value();
  a.confidence = o.entry->confidence;
  a.source = f.camera;
  a.value = FaceIdentityValue{f.id, f.name, f.score};
  return a;
}

Answer<ClassLabelValue> identify_face_expression(const PrimitiveContext& ctx) {
  const auto o = ctx.observe(keys::kFaceExpression);
  auto a = Answer<ClassLabelValue>::from(o);
  if (a.status != PrimitiveStatus::kOk) return a;
  const FaceExpression& e = o.value();
  a.confidence = o.entry->confidence;
  a.source = e.camera;
  a.value = ClassLabelValue{e.label, dream_expression_id(e.label), e.probabilities};
  return a;
}

int dream_expression_id(std::string_view label) {
  // spec/original-dream.md §2.2 #18 (code order); CK+ spells sad / angry as sadness / anger.
  constexpr std::array<std::array<std::string_view, 2>, 5> kIds = {{{"happy", "happy"},
                                                                    {"sad", "sadness"},
                                                                    {"angry", "anger"},
                                                                    {"fear", "fear"},
                                                                    {"neutral", "neutral"}}};
  for (size_t i = 0; i < kIds.size(); ++i)
    if (label == kIds[i][0] || label == kIds[i][1]) return static_cast<int>(i);
  return -1;
}

// The rows of the face recognition family.
void register_face_recognition_primitives(PrimitiveRegistry& r) {
  r.add(PrimitiveId::kIdentifyFace, {keys::kFaceIdentity.name}, identify_face);
  r.add(PrimitiveId::kIdentifyFaceExpression, {keys::kFaceExpression.name},
        identify_face_expression);
}

}  // namespace dreamsense::primitives
