#include "dreamsense/perception/analyzer_registry.hpp"
#include "dreamsense/perception/options_node.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>

namespace dreamsense {
namespace {
namespace fs = std::filesystem;

TEST(OptionsNode, ReadsTypedValuesKeepsDefaultsAndRecordsEffectiveValues) {
  OptionsNode n("pipeline.yaml: analyzers.gaze.options",
                YAML::Load("{radius: 0.3, mode: camera_plane, robot: [0, -0.05, 0.15], "
                           "filter: {enabled: false}}"));
  double radius = 0.2;
  std::string mode = "3d";
  cv::Vec3d robot{1, 1, 1};
  int unused_default = 7;
  bool enabled = true;
  ASSERT_TRUE(n.get("radius", radius));
  ASSERT_TRUE(n.get("mode", mode));
  ASSERT_TRUE(n.get("robot", robot));
  ASSERT_TRUE(n.get("count", unused_default));
  ASSERT_TRUE(n.child("filter").get("enabled", enabled));
  EXPECT_DOUBLE_EQ(radius, 0.3);
  EXPECT_EQ(mode, "camera_plane");
  EXPECT_DOUBLE_EQ(robot[1], -0.05);
  EXPECT_EQ(unused_default, 7) << "absent keys keep the default";
  EXPECT_FALSE(enabled);
  EXPECT_TRUE(n.unread_keys().empty());
  bool found = false;
  for (const auto& [k, v] : n.effective())
    if (k == "count") found = v == "7";
  EXPECT_TRUE(found) << "defaults are listed as effective values";
}

TEST(OptionsNode, WrongTypesAndUnknownKeysNameTheKey) {
  OptionsNode n("pipeline.yaml: analyzers.speech.options",
                YAML::Load("{beam: yes please, typo: 1}"));
  bool beam = true;
  auto s = n.get("beam", beam);
  ASSERT_FALSE(s);
  EXPECT_NE(s.error().message.find("analyzers.speech.options.beam"), std::string::npos)
      << s.error().message;
  const auto unread = n.unread_keys();
  EXPECT_NE(std::find(unread.begin(), unread.end(), "typo"), unread.end())
      << "a key nobody reads is an unknown option";
  // Fuzz finding 6: a list as a key names no option; it is reported, not thrown.
  OptionsNode list_key("x", YAML::Load("{? [a, b] : 1}"));
  std::vector<std::string> list_unread;
  EXPECT_NO_THROW(list_unread = list_key.unread_keys());
  EXPECT_EQ(list_unread, std::vector<std::string>{"[a, b]"});
  cv::Vec3d v;
  OptionsNode bad("x", YAML::Load("{v: [1, 2]}"));
  EXPECT_FALSE(bad.get("v", v)) << "a vector needs three numbers";
}

TEST(OptionsNode, SetCreatesNestedOverrides) {
  OptionsNode n("cli", YAML::Node());
  ASSERT_TRUE(n.set("mutual.mode", "camera_plane"));
  ASSERT_TRUE(n.set("mutual.robot_head_m", "[0.1, 0.2, 0.3]"));
  ASSERT_TRUE(n.set("grammar", "cards.gram"));
  std::string mode, grammar;
  cv::Vec3d head;
  ASSERT_TRUE(n.child("mutual").get("mode", mode));
  ASSERT_TRUE(n.child("mutual").get("robot_head_m", head));
  ASSERT_TRUE(n.get("grammar", grammar));
  EXPECT_EQ(mode, "camera_plane");
  EXPECT_DOUBLE_EQ(head[2], 0.3);
  EXPECT_EQ(grammar, "cards.gram");
  EXPECT_FALSE(n.set("", "1"));
}

TEST(PlanContext, MetadataFilesStayInsideTheSession) {
  const fs::path dir = fs::temp_directory_path() / "ds_plan_context_test/session";
  fs::create_directories(dir / "grammars");
  std::ofstream(dir / "grammars/g.gram") << "#JSGF V1.0;\n";
  PlanContext c;
  c.session_dir = dir;
  c.manifest_path = dir / "session.yaml";
  c.metadata = {{"speech_grammar", "grammars/g.gram"},
                {"escape", "../../../etc/passwd"},
                {"absolute", "/etc/passwd"}};
  auto ok = c.metadata_file("speech_grammar");
  ASSERT_TRUE(ok);
  ASSERT_TRUE(ok->has_value());
  EXPECT_EQ(**ok, dir / "grammars/g.gram");
  auto none = c.metadata_file("voice_enroll");
  ASSERT_TRUE(none);
  EXPECT_FALSE(none->has_value());
  auto out = c.metadata_file("escape");
  ASSERT_FALSE(out);
  EXPECT_NE(out.error().message.find("outside the session"), std::string::npos);
  EXPECT_FALSE(c.metadata_file("absolute"));
  fs::remove_all(dir.parent_path());
}

TEST(AnalyzerRegistry, FindsByNameAndRefusesDuplicates) {
  AnalyzerRegistry r;
  AnalyzerFactory f;
  f.name = "x";
  f.plan = [](const PlanContext&, OptionsNode&) -> Result<PlannedAnalyzers> {
    return PlannedAnalyzers::skip("nothing");
  };
  r.add(f);
  EXPECT_NE(r.find("x"), nullptr);
  EXPECT_EQ(r.find("y"), nullptr);
  EXPECT_THROW(r.add(f), CheckFailure);
  StreamDescription s;
  s.roles = {"child_camera"};
  PlanContext c;
  c.streams = {s};
  EXPECT_EQ(c.with_role("child_camera").size(), 1u);
  EXPECT_EQ(c.first_with_role("mic_array"), nullptr);
}

}  // namespace
}  // namespace dreamsense
