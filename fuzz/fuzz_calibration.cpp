// Calibration files: CameraModel YAML (core/camera_model.hpp), the DREAM calibration import
// (XML/YAML, geometry/dream_import.hpp), the table frame (geometry/plane.hpp) and the microphone
// array geometry (audio/mic_array.hpp). Input: byte 0 picks the reader, the rest is the file.
#include "dreamsense/audio/mic_array.hpp"
#include "dreamsense/core/camera_model.hpp"
#include "dreamsense/geometry/dream_import.hpp"
#include "dreamsense/geometry/plane.hpp"

#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace dreamsense;
  if (size < 1) return 0;
  const std::string_view file = fuzz::as_text(data + 1, size - 1);
  const auto& scratch = fuzz::scratch();
  switch (data[0] % 7) {
    case 0:
      (void)read_camera_model(scratch.write("camera.yaml", file));
      break;
    case 1:
      (void)geometry::read_dream_intrinsics(scratch.write("CameraMKMatDMat.xml", file));
      break;
    case 2:
      (void)geometry::read_dream_intrinsics(scratch.write("Kinect0color_KMatDMat.xml", file),
                                            cv::Size(1280, 960));
      break;
    case 3:
      (void)geometry::read_dream_extrinsics(scratch.write("CameraMRMatTMat.xml", file));
      break;
    case 4:
      (void)geometry::read_dream_object_file(scratch.write("ObjectFile.xml", file));
      break;
    case 5:
      (void)geometry::read_table_frame(scratch.write("table.yaml", file));
      break;
    default:
      (void)audio::read_mic_array(scratch.write("mic_array.yaml", file));
      break;
  }
  return 0;
}
