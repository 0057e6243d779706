#pragma once
// A camera of a demo session as a video file, the "device" of live dry runs (tests only).

#include "dreamsense/sources/session.hpp"

#include <gtest/gtest.h>
#include <opencv2/videoio.hpp>

#include <filesystem>
#include <string>
#include <variant>
#include <vector>

namespace dreamsense::cli_support {

// The demo's camera `id` as an MJPG video of `repeats` x its frames (25 fps).
inline void write_video(const std::filesystem::path& demo, const std::string& id, int repeats,
                        const std::filesystem::path& out) {
  dreamsense::sources::SessionReaderOptions ro;
  ro.only = {id};
  auto reader = dreamsense::sources::SessionReader::open(demo, ro);
  ASSERT_TRUE(reader) << reader.error().message;
  std::vector<cv::Mat> frames;
  for (auto f = (*reader)->next(); f; f = (*reader)->next())
    frames.push_back(std::get<dreamsense::ColorImage>((*f)->payload).image);
  ASSERT_FALSE(frames.empty());
  cv::VideoWriter w(out.string(), cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 25,
                    frames.front().size());
  ASSERT_TRUE(w.isOpened());
  for (int k = 0; k < repeats; ++k)
    for (const auto& f : frames) w.write(f);
}

}  // namespace dreamsense::cli_support
