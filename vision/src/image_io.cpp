#include "dreamsense/vision/image_io.hpp"

#include <opencv2/imgcodecs.hpp>

#include <fstream>
#include <gif_lib.h>

namespace dreamsense::vision {
namespace {
const char* gif_error(int code) {
  const char* s = GifErrorString(code);
  return s ? s : "unknown GIF error";
}
}  // namespace

Result<cv::Mat> read_gif_grey(const std::filesystem::path& path) {
  int err = 0;
  GifFileType* gif = DGifOpenFileName(path.c_str(), &err);
  if (!gif)
    return make_error(ErrorCode::kCorruptData, "{}: not a readable GIF ({})", path.string(),
                      gif_error(err));
  struct Closer {
    GifFileType* g;
    ~Closer() {
      int e = 0;
      DGifCloseFile(g, &e);
    }
  } closer{gif};
  if (DGifSlurp(gif) != GIF_OK || gif->ImageCount < 1 || gif->SWidth <= 0 || gif->SHeight <= 0)
    return make_error(ErrorCode::kCorruptData, "{}: truncated or empty GIF ({})", path.string(),
                      gif_error(gif->Error));
  const SavedImage& frame = gif->SavedImages[0];
  const ColorMapObject* map = frame.ImageDesc.ColorMap ? frame.ImageDesc.ColorMap : gif->SColorMap;
  if (!map)
    return make_error(ErrorCode::kCorruptData, "{}: GIF without a colour map", path.string());
  std::vector<uint8_t> luma(256, 0);
  for (int i = 0; i < map->ColorCount && i < 256; ++i) {
    const GifColorType& c = map->Colors[i];
    luma[i] = cv::saturate_cast<uint8_t>(0.299 * c.Red + 0.587 * c.Green + 0.114 * c.Blue);
  }
  cv::Mat grey(gif->SHeight, gif->SWidth, CV_8UC1,
               cv::Scalar(luma[static_cast<size_t>(gif->SBackGroundColor) & 0xff]));
  const GifImageDesc& d = frame.ImageDesc;
  for (int y = 0; y < d.Height; ++y) {
    const int gy = d.Top + y;
    if (gy < 0 || gy >= grey.rows) continue;
    for (int x = 0; x < d.Width; ++x) {
      const int gx = d.Left + x;
      if (gx < 0 || gx >= grey.cols) continue;
      grey.at<uint8_t>(gy, gx) = luma[frame.RasterBits[static_cast<size_t>(y) * d.Width + x]];
    }
  }
  return grey;
}

Result<cv::Mat> read_grey_image(const std::filesystem::path& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec))
    return make_error(ErrorCode::kNotFound, "{}: no such image file", path.string());
  char magic[4] = {};
  {
    std::ifstream in(path, std::ios::binary);
    if (!in) return make_error(ErrorCode::kIoError, "{}: cannot open", path.string());
    in.read(magic, 4);
  }
  if (std::string(magic, 4) == "GIF8") return read_gif_grey(path);
  cv::Mat img = cv::imread(path.string(), cv::IMREAD_GRAYSCALE);
  if (img.empty())
    return make_error(ErrorCode::kCorruptData, "{}: not an image OpenCV can decode", path.string());
  return img;
}

Status write_gif_grey(const std::filesystem::path& path, const cv::Mat& grey) {
  if (grey.type() != CV_8UC1 || grey.empty())
    return make_error(ErrorCode::kInvalidArgument, "{}: write_gif_grey needs CV_8UC1",
                      path.string());
  int err = 0;
  GifFileType* gif = EGifOpenFileName(path.c_str(), false, &err);
  if (!gif) return make_error(ErrorCode::kIoError, "{}: cannot write GIF", path.string());
  ColorMapObject* map = GifMakeMapObject(256, nullptr);
  for (int i = 0; i < 256; ++i) {
    map->Colors[i].Red = map->Colors[i].Green = map->Colors[i].Blue = static_cast<GifByteType>(i);
  }
  bool ok = EGifPutScreenDesc(gif, grey.cols, grey.rows, 8, 0, map) == GIF_OK &&
            EGifPutImageDesc(gif, 0, 0, grey.cols, grey.rows, false, nullptr) == GIF_OK;
  for (int y = 0; ok && y < grey.rows; ++y)
    ok =
        EGifPutLine(gif, const_cast<GifPixelType*>(grey.ptr<GifPixelType>(y)), grey.cols) == GIF_OK;
  GifFreeMapObject(map);
  ok = EGifCloseFile(gif, &err) == GIF_OK && ok;
  if (!ok) return make_error(ErrorCode::kIoError, "{}: GIF write failed", path.string());
  return ok_status();
}

}  // namespace dreamsense::vision
