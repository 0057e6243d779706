#include "dreamsense/perception/analyzer_registry.hpp"

#include <algorithm>

namespace dreamsense {
namespace fs = std::filesystem;

bool StreamDescription::has_role(std::string_view role) const {
  return std::find(roles.begin(), roles.end(), role) != roles.end();
}

std::vector<const StreamDescription*> PlanContext::with_role(std::string_view role) const {
  std::vector<const StreamDescription*> out;
  for (const auto& s : streams)
    if (s.has_role(role)) out.push_back(&s);
  return out;
}

const StreamDescription* PlanContext::first_with_role(std::string_view role) const {
  for (const auto& s : streams)
    if (s.has_role(role)) return &s;
  return nullptr;
}

std::map<SensorId, CameraModel> PlanContext::cameras_with_role(std::string_view role) const {
  std::map<SensorId, CameraModel> out;
  for (const auto& s : streams)
    if (s.has_role(role) && s.camera) out.emplace(s.id, *s.camera);
  return out;
}

Result<std::optional<fs::path>> PlanContext::metadata_file(std::string_view key) const {
  auto it = metadata.find(std::string(key));
  if (it == metadata.end()) return std::optional<fs::path>{};
  const fs::path relative(it->second);
  if (absolute_paths_allowed && relative.is_absolute()) return std::optional<fs::path>{relative};
  if (relative.empty() || relative.is_absolute())
    return make_error(ErrorCode::kInvalidArgument,
                      "{}: metadata {} must be a path relative to the session folder (got \"{}\")",
                      manifest_path.string(), key, it->second);
  // Session-relative references must stay inside the session (no "..", no symlink out of it).
  std::error_code ec;
  const fs::path root = fs::weakly_canonical(session_dir, ec);
  const fs::path target = fs::weakly_canonical(session_dir / relative, ec);
  const auto mismatch = std::mismatch(root.begin(), root.end(), target.begin(), target.end());
  if (ec || mismatch.first != root.end())
    return make_error(ErrorCode::kInvalidArgument,
                      "{}: metadata {} (\"{}\") leads outside the session folder",
                      manifest_path.string(), key, it->second);
  return std::optional<fs::path>{session_dir / relative};
}

void AnalyzerRegistry::add(AnalyzerFactory factory) {
  DS_CHECK(!factory.name.empty());
  DS_CHECK(static_cast<bool>(factory.plan));
  if (find(factory.name) != nullptr)
    throw CheckFailure("two analyser factories named '" + factory.name + "'");
  factories_.push_back(std::move(factory));
}

const AnalyzerFactory* AnalyzerRegistry::find(std::string_view name) const {
  for (const auto& f : factories_)
    if (f.name == name) return &f;
  return nullptr;
}

}  // namespace dreamsense
