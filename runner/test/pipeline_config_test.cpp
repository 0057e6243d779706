// pipeline.yaml (runner/pipeline_config.hpp): what it reads, and that a damaged file is one error
// naming the file and the key, never an exception out of the reader.
#include "dreamsense/runner/pipeline_config.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <string>
#include <unistd.h>

namespace dreamsense::runner {
namespace {

namespace fs = std::filesystem;

class PipelineConfigFile : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string pattern = (fs::temp_directory_path() / "ds_pipeline_config_XXXXXX").string();
    ASSERT_NE(mkdtemp(pattern.data()), nullptr);
    dir_ = pattern;
  }
  void TearDown() override { fs::remove_all(dir_); }

  fs::path write(const std::string& text) const {
    const fs::path file = dir_ / "pipeline.yaml";
    std::ofstream(file, std::ios::binary) << text;
    return file;
  }

  fs::path dir_;
};

TEST_F(PipelineConfigFile, ReadsAnalyzersOptionsAndRoles) {
  auto c =
      PipelineConfig::read(write("version: 1\n"
                                 "analyzers:\n"
                                 "  speech: false\n"
                                 "  gaze:\n"
                                 "    enabled: true\n"
                                 "    options: {mutual_gaze_deg: 12}\n"
                                 "roles:\n"
                                 "  cam_mid: [face, body]\n"
                                 "  mic: audio\n"));
  ASSERT_TRUE(c) << c.error().message;
  ASSERT_EQ(c->analyzers.count("speech"), 1u);
  EXPECT_EQ(c->analyzers.at("speech").enabled, std::optional<bool>(false));
  ASSERT_EQ(c->analyzers.count("gaze"), 1u);
  EXPECT_EQ(c->analyzers.at("gaze").enabled, std::optional<bool>(true));
  EXPECT_EQ(c->analyzers.at("gaze").options["mutual_gaze_deg"].as<int>(), 12);
  EXPECT_EQ(c->roles.at("cam_mid"), (std::vector<std::string>{"face", "body"}));
  EXPECT_EQ(c->roles.at("mic"), (std::vector<std::string>{"audio"}));
}

TEST_F(PipelineConfigFile, EmptyFileMeansDefaults) {
  auto c = PipelineConfig::read(write(""));
  ASSERT_TRUE(c) << c.error().message;
  EXPECT_TRUE(c->analyzers.empty());
  EXPECT_TRUE(c->roles.empty());
}

TEST_F(PipelineConfigFile, UnknownKeysAndWrongTypesNameTheKey) {
  auto typo = PipelineConfig::read(write("analyzer:\n  speech: false\n"));
  ASSERT_FALSE(typo);
  EXPECT_NE(typo.error().message.find("analyzer: unknown key"), std::string::npos)
      << typo.error().message;
  auto enabled = PipelineConfig::read(write("analyzers:\n  gaze: {enabled: maybe}\n"));
  ASSERT_FALSE(enabled);
  EXPECT_NE(enabled.error().message.find("analyzers.gaze.enabled"), std::string::npos)
      << enabled.error().message;
}

// Fuzz finding 6 (fuzz/README.md): a list or map used as a key (`? [a, b]: 1`) made
// as<std::string>() throw YAML::BadConversion out of the reader, and the program ended.
TEST_F(PipelineConfigFile, ListOrMapAsKeyIsAnErrorNotACrash) {
  for (const std::string text :
       {"? [a, b]\n: 1\n", "analyzers:\n  ? {a: 1}\n  : true\n",
        "analyzers:\n  gaze:\n    ? [enabled]\n    : true\n", "roles:\n  ? [cam]\n  : face\n"}) {
    Result<PipelineConfig> c = tl::unexpected(Error{ErrorCode::kInternal, "not read"});
    EXPECT_NO_THROW(c = PipelineConfig::read(write(text))) << text;
    ASSERT_FALSE(c) << text;
    EXPECT_EQ(c.error().code, ErrorCode::kInvalidArgument) << text;
    EXPECT_NE(c.error().message.find("a key must be a name"), std::string::npos)
        << c.error().message;
    EXPECT_NE(c.error().message.find("pipeline.yaml"), std::string::npos) << c.error().message;
  }
}

}  // namespace
}  // namespace dreamsense::runner
