// Training-data tool (issue 20): the expression network's input pixels of every face of an
// expression dataset, framed exactly as the pipeline frames them (vision/face_crops.hpp: the
// project's cascade + dlib landmarks, else the documented fallbacks), for
// tools/train_fer_net.py, which fine-tunes the network on them. Not part of the pipeline.
//   fer_crops DATASET DIR OUT.bin
// Layout: "DSFC", int32 version 1, int32 n, int32 side (112); per item int32 label index
// (kExpressionLabels order), int32 alignment source (vision::AlignedFace::source, -1: no face),
// then two side x side grey images (uint8, row-major): the eye-aligned crop (face_api block)
// and the package's landmark box crop (face_api_box block, expression::face_api_box_crop), each
// padded to a square and resized as the network's input_blob does. The mirror images are not stored
// (a flip).
#include "dreamsense/eval/faces/datasets.hpp"
#include "dreamsense/expression/features.hpp"
#include "dreamsense/expression/labels.hpp"
#include "dreamsense/vision/face_api_net.hpp"
#include "dreamsense/vision/face_crops.hpp"
#include "dreamsense/vision/face_locator.hpp"
#include "dreamsense/vision/image_io.hpp"

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <cstdio>
#include <fstream>
#include <iterator>
#include <string>

using namespace dreamsense;

int main(int argc, char** argv) {
  if (argc != 4) {
    std::fprintf(stderr, "usage: fer_crops DATASET DIR OUT.bin\n");
    return 2;
  }
  auto items = eval::faces::read_expression_dataset(argv[1], argv[2]);
  if (!items) {
    std::fprintf(stderr, "%s\n", items.error().message.c_str());
    return 1;
  }
  vision::FaceCropOptions crop;
  crop.alignment = vision::AlignmentOptions{};
  auto landmarker = vision::load_landmarker();
  if (!landmarker) {
    std::fprintf(stderr, "%s\n", landmarker.error().message.c_str());
    return 1;
  }
  auto aligner = vision::make_face_crop_aligner(crop, *landmarker);
  if (!aligner) {
    std::fprintf(stderr, "%s\n", aligner.error().message.c_str());
    return 1;
  }
  const int side = vision::kFaceApiInputPx;
  std::ofstream out(argv[3], std::ios::binary);
  const int header[4] = {0x43465344 /* "DSFC" */, 1, static_cast<int>(items->size()), side};
  out.write(reinterpret_cast<const char*>(header), sizeof header);
  cv::setNumThreads(1);
  for (size_t i = 0; i < items->size(); ++i) {
    const auto& it = (*items)[i];
    auto grey = vision::read_grey_image(it.path);
    if (!grey) {
      std::fprintf(stderr, "%s\n", grey.error().message.c_str());
      return 1;
    }
    auto face = aligner->align(*grey);
    if (!face) {
      std::fprintf(stderr, "%s\n", face.error().message.c_str());
      return 1;
    }
    int label = 0;
    for (; label < static_cast<int>(std::size(expression::kExpressionLabels)); ++label)
      if (it.label == expression::kExpressionLabels[label]) break;
    const int source = *face ? static_cast<int>((*face)->source) : -1;
    out.write(reinterpret_cast<const char*>(&label), 4);
    out.write(reinterpret_cast<const char*>(&source), 4);
    const cv::Mat aligned = *face ? vision::resample_face(*grey, **face, side)
                                  : vision::face_api_square_input(*grey, side);
    const cv::Mat box =
        *face ? vision::face_api_square_input(expression::face_api_box_crop(*grey, **face), side)
              : aligned;
    for (const cv::Mat& view : {aligned, box}) {
      const cv::Mat c = view.isContinuous() ? view : view.clone();
      out.write(reinterpret_cast<const char*>(c.data), static_cast<std::streamsize>(side * side));
    }
    if (i % 500 == 0) std::fprintf(stderr, "%zu/%zu\n", i, items->size());
  }
  return out ? 0 : 1;
}
