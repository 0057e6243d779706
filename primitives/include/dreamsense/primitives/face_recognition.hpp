#pragma once
// Primitives answered from the face recognition analysers (issue 12): F17 identifyFace and
// F18 identifyFaceExpression, both for the selected camera's face.

#include "dreamsense/primitives/context.hpp"

#include <string_view>

namespace dreamsense::primitives {

// F17: {id, name, score}; id -1 = a face that is not in the gallery (ok, not no_data: the
// controller learns that a stranger is there). no_data without a face.
Answer<FaceIdentityValue> identify_face(const PrimitiveContext& ctx);

// F18: the smoothed expression label with its per-class probabilities and DREAM's legacy id
// (0 happy, 1 sad, 2 angry, 3 fear, 4 neutral, -1 any other label). no_data without a face.
Answer<ClassLabelValue> identify_face_expression(const PrimitiveContext& ctx);

// DREAM's legacy expression id of a label (our CK+ names and DREAM's spellings both accepted).
int dream_expression_id(std::string_view label);

}  // namespace dreamsense::primitives
