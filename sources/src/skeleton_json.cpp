#include "dreamsense/sources/skeleton_json.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include <algorithm>
#include <cmath>
#include <string>

namespace dreamsense::sources {

Result<SkeletonJson> parse_skeleton_json(std::string_view text) {
  auto bad = [](const std::string& what) {
    return make_error(ErrorCode::kCorruptData, "{}", what);
  };
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    return bad(fmt::format("malformed JSON: {}", e.what()));
  }
  if (!j.is_object()) return bad("expected a JSON object");
  SkeletonJson out;
  if (j.contains("stamp_ns")) {
    if (!j["stamp_ns"].is_number_integer()) return bad("'stamp_ns' is not an integer");
    out.stamp_ns = j["stamp_ns"].get<int64_t>();
  }
  if (j.contains("sequence")) {
    if (!j["sequence"].is_number_unsigned()) return bad("'sequence' is not a non-negative integer");
    out.sequence = j["sequence"].get<uint64_t>();
  }
  if (!j.contains("bodies")) return out;
  const auto& bodies = j["bodies"];
  if (!bodies.is_array()) return bad("'bodies' is not a list");
  for (size_t b = 0; b < bodies.size(); ++b) {
    const auto& jb = bodies[b];
    if (!jb.is_object()) return bad(fmt::format("bodies[{}] is not an object", b));
    SkeletonBody body;
    body.body_id = static_cast<int>(b);
    if (jb.contains("id")) {
      if (!jb["id"].is_number_integer())
        return bad(fmt::format("bodies[{}].id is not an integer", b));
      body.body_id = jb["id"].get<int>();
    }
    if (jb.contains("joints")) {
      const auto& joints = jb["joints"];
      if (!joints.is_object()) return bad(fmt::format("bodies[{}].joints is not an object", b));
      for (const auto& [name, v] : joints.items()) {
        auto id = joint_from_name(name);
        if (!id) return bad(fmt::format("bodies[{}]: unknown joint '{}'", b, name));
        if (!v.is_array() || (v.size() != 3 && v.size() != 4) ||
            !std::all_of(v.begin(), v.end(), [](const auto& x) { return x.is_number(); }))
          return bad(fmt::format("bodies[{}].joints.{}: expected [x, y, z, confidence]", b, name));
        // Plausible (docs/session_format.md): finite, within 100 m of the sensor, confidence in
        // [0, 1].
        const cv::Vec3d p(v[0].get<double>(), v[1].get<double>(), v[2].get<double>());
        const double c = v.size() == 4 ? v[3].get<double>() : 1.0;
        if (!cv::checkRange(p, true, nullptr, -kMaxSkeletonJointDistanceM,
                            kMaxSkeletonJointDistanceM) ||
            !std::isfinite(c) || c < 0 || c > 1)
          return bad(fmt::format(
              "bodies[{}].joints.{}: implausible value (position within {} m, confidence in "
              "[0, 1])",
              b, name, kMaxSkeletonJointDistanceM));
        JointObservation& o = body.joint(*id);
        o.position_m = p;
        o.confidence = static_cast<float>(c);
      }
    }
    out.skeleton.bodies.push_back(body);
  }
  return out;
}

}  // namespace dreamsense::sources
