// F17 identifyFace and F18 identifyFaceExpression through the evaluator (faces, issue 12).
#include "dreamsense/primitives/face_recognition.hpp"

#include "dreamsense/perception/expression.hpp"
#include "dreamsense/perception/face_identity.hpp"
#include "dreamsense/primitives/evaluator.hpp"

#include <gtest/gtest.h>

#include "test_time.hpp"

namespace dreamsense::primitives {
namespace {

using test::ms;

MultiFrame tick(int64_t t) {
  MultiFrame mf;
  mf.stamp = ms(t);
  mf.frames["cam"] = make_frame("cam", ms(t), 0, ColorImage{});
  return mf;
}

const PrimitiveRecord& of(const std::vector<PrimitiveRecord>& r, PrimitiveId id) {
  return r[static_cast<size_t>(id) - 1];
}

TEST(FaceRecognitionPrimitives, DisabledWithoutWritersOkWithAFaceNoDataWithout) {
  const Evaluator none({}, {});
  EXPECT_FALSE(none.enabled(PrimitiveId::kIdentifyFace));
  EXPECT_FALSE(none.enabled(PrimitiveId::kIdentifyFaceExpression));

  Evaluator ev({}, {{"face.identity", {"cam"}}, {"face.expression", {"cam"}}});
  Blackboard bb;
  {
    BlackboardWriter w("faces");
    FaceIdentity id;
    id.id = 3;
    id.name = "child";
    id.score = -0.2;
    id.camera = "cam";
    w.set(keys::kFaceIdentity, id, ms(40), 0.9f);
    FaceExpression e;
    e.label = "sadness";
    e.probability = 0.7;
    e.probabilities = {{"sadness", 0.7}, {"happy", 0.3}};
    e.camera = "cam";
    w.set(keys::kFaceExpression, e, ms(40), 0.6f);
    bb.commit(w, ms(40));
  }
  auto r = ev.evaluate(tick(40), bb.snapshot());
  const auto& f17 = of(r, PrimitiveId::kIdentifyFace);
  ASSERT_EQ(f17.status, PrimitiveStatus::kOk);
  const auto* v = f17.value_as<FaceIdentityValue>();
  ASSERT_NE(v, nullptr);
  EXPECT_EQ(v->id, 3);
  EXPECT_EQ(v->name, "child");
  EXPECT_DOUBLE_EQ(v->score, -0.2);
  EXPECT_EQ(f17.source, "cam");
  const auto& f18 = of(r, PrimitiveId::kIdentifyFaceExpression);
  ASSERT_EQ(f18.status, PrimitiveStatus::kOk);
  const auto* e = f18.value_as<ClassLabelValue>();
  ASSERT_NE(e, nullptr);
  EXPECT_EQ(e->label, "sadness");
  EXPECT_EQ(e->id, 1) << "DREAM's legacy id of sad";
  EXPECT_DOUBLE_EQ(e->scores.at("happy"), 0.3);
  EXPECT_NEAR(*f18.confidence, 0.6, 1e-6);

  {  // the face is lost: no_data, never the last identity
    BlackboardWriter w("faces");
    w.set_absent(keys::kFaceIdentity, ms(80));
    w.set_absent(keys::kFaceExpression, ms(80));
    bb.commit(w, ms(80));
  }
  r = ev.evaluate(tick(80), bb.snapshot());
  EXPECT_EQ(of(r, PrimitiveId::kIdentifyFace).status, PrimitiveStatus::kNoData);
  EXPECT_EQ(of(r, PrimitiveId::kIdentifyFaceExpression).status, PrimitiveStatus::kNoData);

  {  // a stranger: ok with id -1
    BlackboardWriter w("faces");
    FaceIdentity id;
    id.id = -1;
    id.best_id = 3;
    id.camera = "cam";
    w.set(keys::kFaceIdentity, id, ms(120), 0.9f);
    bb.commit(w, ms(120));
  }
  r = ev.evaluate(tick(120), bb.snapshot());
  ASSERT_EQ(of(r, PrimitiveId::kIdentifyFace).status, PrimitiveStatus::kOk);
  EXPECT_EQ(of(r, PrimitiveId::kIdentifyFace).value_as<FaceIdentityValue>()->id, -1);
}

TEST(FaceRecognitionPrimitives, DreamExpressionIds) {
  EXPECT_EQ(dream_expression_id("happy"), 0);
  EXPECT_EQ(dream_expression_id("sadness"), 1);
  EXPECT_EQ(dream_expression_id("sad"), 1);
  EXPECT_EQ(dream_expression_id("anger"), 2);
  EXPECT_EQ(dream_expression_id("fear"), 3);
  EXPECT_EQ(dream_expression_id("neutral"), 4);
  EXPECT_EQ(dream_expression_id("surprise"), -1);
  EXPECT_EQ(dream_expression_id("contempt"), -1);
  EXPECT_EQ(dream_expression_id(""), -1);
}

}  // namespace
}  // namespace dreamsense::primitives
