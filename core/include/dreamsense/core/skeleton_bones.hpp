#pragma once
// The Kinect v1 skeleton tree (sensor_frame.hpp JointId): its 19 bones, for drawing skeletons and
// for walking the tree (actions' normalisation).

#include "dreamsense/core/sensor_frame.hpp"

#include <array>
#include <utility>

namespace dreamsense {

// (parent, child), from the shoulder centre outwards.
inline constexpr std::array<std::pair<JointId, JointId>, 19> kSkeletonBones = {{
    {JointId::kShoulderCenter, JointId::kHead},
    {JointId::kShoulderCenter, JointId::kShoulderLeft},
    {JointId::kShoulderLeft, JointId::kElbowLeft},
    {JointId::kElbowLeft, JointId::kWristLeft},
    {JointId::kWristLeft, JointId::kHandLeft},
    {JointId::kShoulderCenter, JointId::kShoulderRight},
    {JointId::kShoulderRight, JointId::kElbowRight},
    {JointId::kElbowRight, JointId::kWristRight},
    {JointId::kWristRight, JointId::kHandRight},
    {JointId::kShoulderCenter, JointId::kSpine},
    {JointId::kSpine, JointId::kHipCenter},
    {JointId::kHipCenter, JointId::kHipLeft},
    {JointId::kHipLeft, JointId::kKneeLeft},
    {JointId::kKneeLeft, JointId::kAnkleLeft},
    {JointId::kAnkleLeft, JointId::kFootLeft},
    {JointId::kHipCenter, JointId::kHipRight},
    {JointId::kHipRight, JointId::kKneeRight},
    {JointId::kKneeRight, JointId::kAnkleRight},
    {JointId::kAnkleRight, JointId::kFootRight},
}};

}  // namespace dreamsense
