// `dreamsense eval landmarks` from outside (issue 20): the cli.md report of a faceless grey image,
// and bad input (malformed .pts, missing .pts, unknown dataset) as one-line errors, exit 1.

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include <filesystem>
#include <fstream>
#include <unistd.h>

#include "cli_support.hpp"

namespace fs = std::filesystem;
using dreamsense::cli_support::run;
using dreamsense::cli_support::slurp;

namespace {
struct TempDir {
  fs::path path = fs::temp_directory_path() / ("ds-lm-cli-" + std::to_string(::getpid()));
  TempDir() { fs::create_directories(path); }
  ~TempDir() { fs::remove_all(path); }
};

void write_pts(const fs::path& f, int n) {
  std::ofstream out(f);
  out << "version: 1\nn_points: " << n << "\n{\n";
  for (int i = 0; i < n; ++i) out << 100 + (i % 10) * 10 << " " << 100 + (i / 10) * 10 << "\n";
  out << "}\n";
}

bool one_line_naming(const std::string& err, const std::string& name) {
  return err.find(name) != std::string::npos && err.find('\n') == err.size() - 1;
}
}  // namespace

TEST(LandmarksCli, ReportAndBadInput) {
  TempDir t;
  const fs::path data = t.path / "data";
  fs::create_directories(data);
  cv::imwrite((data / "grey.jpg").string(), cv::Mat(240, 320, CV_8UC1, cv::Scalar(100)));
  write_pts(data / "grey.pts", 68);
  const fs::path json = t.path / "lm.json";
  auto ok = run("eval landmarks --dataset 300w " + data.string() + " --detectors hog,haar --json " +
                json.string());
  ASSERT_EQ(ok.exit_code, 0) << ok.err;
  const auto j = nlohmann::json::parse(slurp(json));
  EXPECT_EQ(j["task"], "landmarks");
  EXPECT_EQ(j["dataset"]["name"], "300w");
  EXPECT_EQ(j["dataset"]["items"], 1);
  EXPECT_EQ(j["metrics"]["detection_rate"], 0.0);  // a grey image: the face is not detected
  EXPECT_TRUE(j["metrics"].contains("from_box"));
  EXPECT_TRUE(j["timing"].contains("ms_per_face_median"));

  write_pts(data / "grey.pts", 67);
  auto bad = run("eval landmarks --dataset 300w " + data.string());
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_TRUE(one_line_naming(bad.err, "grey.pts")) << bad.err;

  fs::remove(data / "grey.pts");
  auto missing = run("eval landmarks --dataset 300w " + data.string());
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_TRUE(one_line_naming(missing.err, "grey.jpg")) << missing.err;

  auto unknown = run("eval landmarks --dataset helen " + data.string());
  EXPECT_EQ(unknown.exit_code, 1);
  EXPECT_NE(unknown.err.find("helen"), std::string::npos) << unknown.err;
}
