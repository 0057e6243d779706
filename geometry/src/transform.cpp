#include "dreamsense/geometry/transform.hpp"

#include <algorithm>
#include <cmath>
#include <set>

namespace dreamsense::geometry {

double rotation_angle_deg(const cv::Matx33d& A, const cv::Matx33d& B) {
  // Chordal form |A - B|_F = 2 sqrt(2) sin(theta / 2): accurate for small angles, where the
  // trace form acos((tr(A^T B) - 1) / 2) loses precision (and rounds to 0).
  const double s = cv::norm(A - B, cv::NORM_L2) / (2.0 * std::sqrt(2.0));
  return 2.0 * std::asin(std::clamp(s, 0.0, 1.0)) * 180.0 / CV_PI;
}

cv::Matx33d nearest_rotation(const cv::Matx33d& M) {
  cv::Mat w, u, vt;
  cv::SVD::compute(cv::Mat(M), w, u, vt, cv::SVD::FULL_UV);
  cv::Mat R = u * vt;
  if (cv::determinant(R) < 0) {
    cv::Mat d = cv::Mat::eye(3, 3, CV_64F);
    d.at<double>(2, 2) = -1;
    R = u * d * vt;
  }
  return cv::Matx33d(R);
}

double orthonormality_error(const cv::Matx33d& M) {
  const cv::Matx33d E = M * M.t() - cv::Matx33d::eye();
  double worst = 0;
  for (int i = 0; i < 9; ++i) worst = std::max(worst, std::abs(E.val[i]));
  return worst;
}

TransformTree::TransformTree(std::string root) : root_(std::move(root)) {}

bool TransformTree::has(const std::string& frame) const {
  return frame == root_ || nodes_.count(frame) > 0;
}

std::vector<std::string> TransformTree::frame_names() const {
  std::vector<std::string> out{root_};
  for (const auto& [name, node] : nodes_) out.push_back(name);
  return out;
}

Status TransformTree::add(const std::string& parent, const std::string& child,
                          const RigidTransform& parent_from_child) {
  if (child.empty()) return make_error(ErrorCode::kInvalidArgument, "frame name is empty");
  if (has(child))
    return make_error(ErrorCode::kInvalidArgument, "frame '{}' is already in the tree", child);
  if (!has(parent))
    return make_error(ErrorCode::kNotFound, "parent frame '{}' of '{}' is not in the tree", parent,
                      child);
  if (orthonormality_error(parent_from_child.R) > 1e-6 || cv::determinant(parent_from_child.R) < 0)
    return make_error(ErrorCode::kInvalidArgument, "transform {}_from_{}: R is not a rotation",
                      parent, child);
  nodes_[child] = Node{parent, parent_from_child};
  return ok_status();
}

Status TransformTree::update(const std::string& child, const RigidTransform& parent_from_child) {
  auto it = nodes_.find(child);
  if (it == nodes_.end())
    return make_error(ErrorCode::kNotFound, "frame '{}' is not a non-root frame of the tree",
                      child);
  if (orthonormality_error(parent_from_child.R) > 1e-6 || cv::determinant(parent_from_child.R) < 0)
    return make_error(ErrorCode::kInvalidArgument, "transform for '{}': R is not a rotation",
                      child);
  it->second.parent_from_this = parent_from_child;
  return ok_status();
}

Result<RigidTransform> TransformTree::global_from(const std::string& frame) const {
  if (!has(frame)) return make_error(ErrorCode::kNotFound, "frame '{}' is not in the tree", frame);
  RigidTransform root_from_frame;
  std::string f = frame;
  // add() only attaches to existing frames, so the tree has no cycles.
  while (f != root_) {
    const Node& n = nodes_.at(f);
    root_from_frame = n.parent_from_this * root_from_frame;
    f = n.parent;
  }
  return root_from_frame;
}

Result<RigidTransform> TransformTree::lookup(const std::string& target,
                                             const std::string& source) const {
  auto g_t = global_from(target);
  if (!g_t) return tl::unexpected(g_t.error());
  auto g_s = global_from(source);
  if (!g_s) return tl::unexpected(g_s.error());
  return g_t->inverse() * *g_s;
}

Result<cv::Vec3d> TransformTree::point_local_to_global(const std::string& local,
                                                       const cv::Vec3d& p) const {
  auto g = global_from(local);
  if (!g) return tl::unexpected(g.error());
  return g->apply(p);
}

Result<cv::Vec3d> TransformTree::point_global_to_local(const std::string& local,
                                                       const cv::Vec3d& p) const {
  auto g = global_from(local);
  if (!g) return tl::unexpected(g.error());
  return g->inverse().apply(p);
}

Result<cv::Matx33d> TransformTree::rotation_local_to_global(const std::string& local,
                                                            const cv::Matx33d& R_local) const {
  auto g = global_from(local);
  if (!g) return tl::unexpected(g.error());
  return g->R * R_local;
}

Result<cv::Matx33d> TransformTree::rotation_global_to_local(const std::string& local,
                                                            const cv::Matx33d& R_global) const {
  auto g = global_from(local);
  if (!g) return tl::unexpected(g.error());
  return g->R.t() * R_global;
}

Result<TransformTree> TransformTree::from_cameras(const std::vector<CameraModel>& cameras) {
  TransformTree tree;
  for (const auto& cam : cameras) {
    if (cam.frame.empty() || cam.frame == tree.root())
      return make_error(ErrorCode::kInvalidArgument,
                        "camera frame name '{}' cannot be a child of '{}'", cam.frame, tree.root());
    if (auto s = tree.add(tree.root(), cam.frame, camera_from_world(cam).inverse()); !s)
      return tl::unexpected(s.error());
  }
  return tree;
}

}  // namespace dreamsense::geometry
