// Model files users pass or ship (YAML through cv::FileStorage, checked by our loaders): gesture
// and action models (modalities/actions), the expression model, the face gallery, the voice
// model, the object gallery, the gaze model and the 3-D face model of a subject calibration.
// Input: byte 0 picks the loader, the rest is the file.
#include "dreamsense/actions/action_model.hpp"
#include "dreamsense/actions/gesture_model.hpp"
#include "dreamsense/expression/expression_model.hpp"
#include "dreamsense/face_identity/face_gallery.hpp"
#include "dreamsense/gaze/gaze_estimator.hpp"
#include "dreamsense/head_pose/face_shape_fit.hpp"
#include "dreamsense/objects/identification.hpp"
#include "dreamsense/voice_id/voice_model.hpp"

#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace dreamsense;
  if (size < 1) return 0;
  const std::string_view file = fuzz::as_text(data + 1, size - 1);
  const auto& scratch = fuzz::scratch();
  switch (data[0] % 9) {
    case 0:
      (void)actions::GestureModel::load(scratch.write("gestures.yaml", file));
      break;
    case 1:
      (void)actions::ActionModel::load(scratch.write("actions.yaml", file));
      break;
    case 2:
      (void)expression::ExpressionModel::load(scratch.write("expression.yaml", file));
      break;
    case 3:
      (void)face_identity::FaceGallery::load(scratch.write("face_gallery.yaml", file));
      break;
    case 4:
      (void)voice_id::VoiceModel::load(scratch.write("voices.yaml", file));
      break;
    case 5:
      (void)objects::ObjectGallery::load(scratch.write("toys.gallery.yaml", file));
      break;
    case 6:
      (void)gaze::read_gaze_model(scratch.write("gaze.yaml", file));
      break;
    case 7:
      (void)head_pose::read_model_from_head(scratch.write("gaze.yaml", file));
      break;
    default:
      (void)head_pose::read_face_model(scratch.write("face_model.yaml", file).string());
      break;
  }
  return 0;
}
