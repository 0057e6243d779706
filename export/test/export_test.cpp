#include "dreamsense/export/primitive_json.hpp"
#include "dreamsense/export/report.hpp"

#include <gtest/gtest.h>

#include <limits>

namespace dreamsense::exporters {
namespace {
using namespace primitives;

TEST(PrimitiveJson, RecordHasTheContractFields) {
  PrimitiveRecord r;
  r.stamp = Timestamp::from_ns(40'000'000);
  r.id = PrimitiveId::kGetHeadGazePlane;
  auto j = to_json(r);
  EXPECT_EQ(j["stamp_ns"], 40'000'000);
  EXPECT_EQ(j["primitive"], "getHeadGaze (plane)");
  EXPECT_EQ(j["id"], "F12");
  EXPECT_EQ(j["status"], "disabled");
  for (const char* k : {"confidence", "value", "legacy", "source"}) EXPECT_TRUE(j.contains(k)) << k;
  EXPECT_FALSE(j.contains("query")) << "no query unless one was answered";
}

TEST(PrimitiveJson, NonFiniteValuesAreFound) {
  PrimitiveRecord r;
  r.id = PrimitiveId::kGetHead;
  r.status = PrimitiveStatus::kOk;
  r.value = HeadValue{{0.1, 0.2, 1.0}, "camera_left"};
  EXPECT_TRUE(value_is_finite(r));
  r.value = HeadValue{{0.1, std::numeric_limits<double>::quiet_NaN(), 1.0}, "camera_left"};
  EXPECT_FALSE(value_is_finite(r));
  r.value = HeadValue{{0.1, 0.2, std::numeric_limits<double>::infinity()}, "camera_left"};
  EXPECT_FALSE(value_is_finite(r));
  r.value = HeadValue{{0.1, 0.2, 1.0}, "camera_left"};
  r.confidence = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(value_is_finite(r));
}

// Every typed value goes to JSON and back unchanged, with DREAM's legacy vector beside it.
TEST(PrimitiveJson, TypedRecordsRoundTrip) {
  std::vector<PrimitiveRecord> records;
  auto add = [&](PrimitiveId id, PrimitiveValue v, PrimitiveQuery q = {}) {
    PrimitiveRecord r;
    r.stamp = Timestamp::from_ns(80'000'000);
    r.id = id;
    r.status = PrimitiveStatus::kOk;
    r.confidence = 0.75;
    r.value = std::move(v);
    r.query = std::move(q);
    r.source = "camera_left";
    r.data_stamp = Timestamp::from_ns(40'000'000);
    records.push_back(r);
  };
  FacesValue faces;
  faces.faces.push_back({{0.1, -0.05, 1.1}, 0.9f, "camera_left", {{"camera_left", {1, 2, 3, 4}}}});
  faces.cameras["camera_left"] = {{{1, 2, 3, 4}, 0.9f, 0.8f}};
  faces.selected_camera = "camera_left";
  add(PrimitiveId::kGetFaces, faces);
  add(PrimitiveId::kGetHeadGazePlane, HeadGazePlaneValue{{0.1, 0.2, 0.0}, 1.1, "camera_left"},
      PlaneQuery{});
  add(PrimitiveId::kTrackHand, TrackValue{{0.1, 0.2, 0.3}, {0.5, 0, 0}, -1, "right", 7},
      TrackQuery{{0.1, 0.2, 0.3}, 0.2});
  add(PrimitiveId::kIdentifyTrajectory, ClassLabelValue{"wave", 1, {{"wave", 0.9}}},
      WindowQuery{1.5});
  add(PrimitiveId::kGetObjects,
      ObjectsValue{{{0, "car", {0.1, 0.3, 0.6}, 0.95, 2}, {3, "plane", {-0.1, 0.3, 0.6}, 0.9, 4}}});
  SoundDirectionValue sd;
  sd.azimuth_deg = 20;
  sd.confidence = 0.6;
  add(PrimitiveId::kGetSoundDirection, sd, ThresholdQuery{0.5});
  for (const auto& r : records) {
    const auto j = to_json(r);
    auto back = record_from_json(nlohmann::json::parse(j.dump()));
    ASSERT_TRUE(back) << back.error().message;
    EXPECT_EQ(to_json(*back), j) << j.dump();
    EXPECT_EQ(back->value.index(), r.value.index());
    EXPECT_EQ(back->query.index(), r.query.index());
  }
  EXPECT_EQ(to_json(records[0])["legacy"].size(), 16u) << "DREAM's getFaces layout";
  EXPECT_DOUBLE_EQ(to_json(records[4])["legacy"][4].get<double>(), 0) << "car = 0";
}

TEST(PrimitiveJson, MalformedRecordsAreErrorsNamingTheMember) {
  auto r = record_from_json(nlohmann::json::parse(
      R"({"primitive":"getHead","stamp_ns":0,"status":"ok","value":{"position_m":[1,2]}})"));
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("value"), std::string::npos) << r.error().message;
  EXPECT_FALSE(record_from_json(nlohmann::json::parse(R"({"primitive":"getNothing"})")));
  EXPECT_FALSE(record_from_json(
      nlohmann::json::parse(R"({"primitive":"getHead","stamp_ns":0,"status":"fine"})")));
}

}  // namespace
}  // namespace dreamsense::exporters

namespace dreamsense::exporters {
namespace {

TEST(HtmlReport, HasSummaryAvailabilityAndChartsOfEnabledPrimitivesOnly) {
  HtmlReport report;
  for (int t = 0; t < 10; ++t) {
    primitives::PrimitiveRecord ok, off;
    ok.stamp = off.stamp = Timestamp::from_ns(t * 40'000'000LL);
    ok.id = primitives::PrimitiveId::kGetBody;
    ok.status = t == 5 ? primitives::PrimitiveStatus::kNoData : primitives::PrimitiveStatus::kOk;
    ok.value = primitives::BodyValue{{0.001 * t, 0.002, 0.003}, 1};
    off.id = primitives::PrimitiveId::kGetFaces;
    off.status = primitives::PrimitiveStatus::kDisabled;
    report.add({ok, off});
  }
  sources::SessionManifest m;
  m.name = "a<b";
  ReportContext c;
  c.plan = {{"not_running", {{"face_detection", "no stream with role child_camera"}}}};
  const std::string html = report.build(m, c);
  EXPECT_NE(html.find("a&lt;b"), std::string::npos) << "escaped";
  EXPECT_NE(html.find("<td>F3</td><td class=\"l\">getBody</td><td>90.0&nbsp;%</td>"
                      "<td>10.0&nbsp;%</td>"),
            std::string::npos);
  EXPECT_NE(html.find("F3 getBody"), std::string::npos) << "a chart of getBody";
  EXPECT_NE(html.find("position_m.x"), std::string::npos) << "its quantities by name";
  EXPECT_NE(html.find("metres"), std::string::npos) << "with their unit";
  EXPECT_EQ(html.find("F7 getFaces"), std::string::npos) << "no chart for a disabled one";
  EXPECT_NE(html.find("time (s)"), std::string::npos);
  EXPECT_NE(html.find("no stream with role child_camera"), std::string::npos);
  EXPECT_EQ(html.find("http"), std::string::npos) << "self-contained";
  EXPECT_EQ(html.find("Approximate camera intrinsics"), std::string::npos);
  EXPECT_EQ(html.find("Child calibration"), std::string::npos) << "none given, none shown";
  c.calibration_lines = {"self-calibrated <here>", "residual 1.7 mm RMS"};
  EXPECT_NE(report.build(m, c).find("<p><b>Child calibration.</b> self-calibrated &lt;here&gt;. "
                                    "residual 1.7 mm RMS.</p>"),
            std::string::npos);
  c.calibration_lines.clear();
  c.input = {{"kind", "video"}, {"approximate_calibration", true}, {"fx_px", 500.0}};
  EXPECT_NE(report.build(m, c).find("Approximate camera intrinsics"), std::string::npos);
}

}  // namespace
}  // namespace dreamsense::exporters
