#include "dreamsense/vision/image_io.hpp"

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include <filesystem>
#include <fstream>

namespace dreamsense::vision {
namespace {

TEST(ImageIo, GifRoundTripIsExactAndFoundByContent) {
  const auto dir = std::filesystem::temp_directory_path() / "ds_image_io";
  std::filesystem::create_directories(dir);
  cv::Mat g(37, 53, CV_8UC1);
  cv::randu(g, 0, 256);
  const auto yale = dir / "subject07.happy";  // Yale naming: no extension
  ASSERT_TRUE(write_gif_grey(yale, g).has_value());
  auto back = read_grey_image(yale);
  ASSERT_TRUE(back.has_value()) << back.error().message;
  EXPECT_EQ(cv::norm(*back, g, cv::NORM_INF), 0.0);
  // A PNG under a name without extension is decoded by content too.
  cv::imwrite((dir / "x.png").string(), g);
  std::filesystem::rename(dir / "x.png", dir / "subject07.sad");
  auto png = read_grey_image(dir / "subject07.sad");
  ASSERT_TRUE(png.has_value());
  EXPECT_EQ(cv::norm(*png, g, cv::NORM_INF), 0.0);
  std::filesystem::remove_all(dir);
}

TEST(ImageIo, MissingTruncatedAndGarbageFilesAreErrorsNamingThem) {
  const auto dir = std::filesystem::temp_directory_path() / "ds_image_io_bad";
  std::filesystem::create_directories(dir);
  auto missing = read_grey_image(dir / "nope.png");
  ASSERT_FALSE(missing.has_value());
  EXPECT_NE(missing.error().message.find("nope.png"), std::string::npos);
  std::ofstream(dir / "garbage.jpg") << "not an image at all";
  EXPECT_EQ(read_grey_image(dir / "garbage.jpg").error().code, ErrorCode::kCorruptData);
  std::ofstream(dir / "cut.gif") << "GIF89a\x10";
  auto cut = read_grey_image(dir / "cut.gif");
  ASSERT_FALSE(cut.has_value());
  EXPECT_NE(cut.error().message.find("cut.gif"), std::string::npos);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace dreamsense::vision
