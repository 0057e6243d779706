#include "dreamsense/geometry/correspondences.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <unistd.h>

namespace dreamsense::geometry {
namespace {
namespace fs = std::filesystem;

class CsvTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir = fs::temp_directory_path() / ("ds_corr_" + std::to_string(::getpid()));
    fs::create_directories(dir);
  }
  void TearDown() override { fs::remove_all(dir); }
  fs::path write(const std::string& name, const std::string& text) {
    std::ofstream(dir / name) << text;
    return dir / name;
  }
  fs::path dir;
};

CameraModel front_model() {
  CameraModel m;
  m.frame = "front.color";
  m.image_size = {64, 48};
  m.K = cv::Matx33d(50, 0, 31.5, 0, 50, 23.5, 0, 0, 1);
  return m;
}

TEST_F(CsvTest, HeaderCommentsAndLayouts) {
  auto t = read_numeric_csv(write("a.csv", "u,v,x,y,z\n# comment\n1,2,3,4,5\n 6, 7 ,8,9,10 # x\n"),
                            {4, 5});
  ASSERT_TRUE(t) << t.error().message;
  EXPECT_EQ(t->columns, 5);
  ASSERT_EQ(t->rows.size(), 2u);
  EXPECT_EQ(t->lines[1], 4);
  auto c = make_correspondences(*t, 0.001, nullptr, nullptr);
  ASSERT_TRUE(c);
  EXPECT_DOUBLE_EQ(c->world[1].z, 0.010);
  EXPECT_FALSE(read_numeric_csv(write("b.csv", "1,2,3,4,5\n1,2,3,4\n"), {4, 5}));
  EXPECT_FALSE(read_numeric_csv(write("c.csv", "1,2,3\n"), {4, 5}));
  EXPECT_FALSE(read_numeric_csv(write("d.csv", "1,2,3,4,5\n1,2,x,4,5\n"), {4, 5}));
  EXPECT_FALSE(read_numeric_csv(write("e.csv", "u,v\n"), {2}));
  EXPECT_FALSE(read_numeric_csv(dir / "missing.csv", {2}));
}

TEST_F(CsvTest, LiftThroughDepthAndNanDepthIsAnErrorNamingTheLine) {
  const CameraModel front = front_model();
  cv::Mat depth(48, 64, CV_16U, cv::Scalar(1500));
  depth.at<uint16_t>(10, 20) = 0;  // no reading
  auto X = lift_front_pixel(depth, front, {31.5, 23.5});
  ASSERT_TRUE(X);
  EXPECT_LT(cv::norm(*X - cv::Vec3d(0, 0, 1.5)), 1e-9);
  auto Y = lift_front_pixel(depth, front, {41.5, 23.5});
  ASSERT_TRUE(Y);
  EXPECT_NEAR((*Y)[0], 0.3, 1e-9) << "10 px at f = 50 px and 1.5 m";
  EXPECT_FALSE(lift_front_pixel(depth, front, {20, 10}));
  EXPECT_FALSE(lift_front_pixel(depth, front, {-3, 10}));
  EXPECT_FALSE(lift_front_pixel(cv::Mat(10, 10, CV_16U, cv::Scalar(1)), front, {1, 1}));

  cv::Mat fdepth(48, 64, CV_32F, cv::Scalar(2.0f));
  fdepth.at<float>(5, 5) = NAN;
  auto t = read_numeric_csv(write("p.csv", "100,200,31.5,23.5\n300,400,5,5\n"), {4, 5});
  ASSERT_TRUE(t);
  auto c = make_correspondences(*t, 1.0, &fdepth, &front);
  ASSERT_FALSE(c);
  EXPECT_NE(c.error().message.find("line 2"), std::string::npos) << c.error().message;
  EXPECT_NE(c.error().message.find("no depth"), std::string::npos) << c.error().message;
  EXPECT_FALSE(make_correspondences(*t, 1.0, nullptr, nullptr)) << "4 columns need depth";
}

}  // namespace
}  // namespace dreamsense::geometry
