#include "dreamsense/body/body_analyzer.hpp"

#include <cmath>
#include <limits>

namespace dreamsense::body {
namespace {
std::optional<cv::Vec3d> anchor(const SkeletonBody& b) {
  for (JointId j : {JointId::kShoulderCenter, JointId::kHead, JointId::kSpine})
    if (b.joint(j).valid()) return b.joint(j).position_m;
  return std::nullopt;
}
}  // namespace

Status ChildSelectionOptions::check() const {
  if (!(max_jump_m > 0))
    return make_error(ErrorCode::kInvalidArgument, "ChildSelectionOptions: max_jump_m must be > 0");
  return ok_status();
}

std::optional<size_t> select_child(const std::vector<SkeletonBody>& bodies,
                                   const std::optional<cv::Vec3d>& previous,
                                   const ChildSelectionOptions& options) {
  auto nearest = [&](const cv::Vec3d& target) -> std::pair<std::optional<size_t>, double> {
    std::optional<size_t> best;
    double best_d = std::numeric_limits<double>::infinity();
    for (size_t i = 0; i < bodies.size(); ++i) {
      auto a = anchor(bodies[i]);
      if (!a) continue;
      const double d = cv::norm(*a - target);
      if (d < best_d) {
        best_d = d;
        best = i;
      }
    }
    return {best, best_d};
  };
  if (previous) {
    auto [i, d] = nearest(*previous);
    if (i && d <= options.max_jump_m) return i;
  }
  return nearest(options.expected_position_m).first;
}

}  // namespace dreamsense::body
