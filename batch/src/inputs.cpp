#include "dreamsense/batch/inputs.hpp"

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <map>
#include <set>
#include <system_error>

namespace dreamsense::batch {
namespace fs = std::filesystem;

const char* to_string(InputKind kind) { return kind == InputKind::kVideo ? "video" : "session"; }

const char* to_string(PlanStatus status) {
  switch (status) {
    case PlanStatus::kRun:
      return "run";
    case PlanStatus::kSkipped:
      return "skipped";
    case PlanStatus::kFailed:
      return "failed";
  }
  return "?";
}

Status InputOptions::check() const {
  if (session_manifest.empty())
    return make_error(ErrorCode::kInvalidArgument, "batch: session_manifest must not be empty");
  for (const auto& e : video_extensions)
    if (e.size() < 2 || e[0] != '.')
      return make_error(ErrorCode::kInvalidArgument,
                        "batch: video extension \"{}\" must start with a dot", e);
  return ok_status();
}

namespace {

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

bool is_folder(const fs::path& p) {
  std::error_code ec;
  return fs::is_directory(p, ec);
}

bool is_session_folder(const fs::path& p, const InputOptions& o) {
  std::error_code ec;
  return is_folder(p) && fs::is_regular_file(p / o.session_manifest, ec);
}

std::string known_extensions(const InputOptions& o) {
  std::string s;
  for (const auto& e : o.video_extensions) s += (s.empty() ? "" : " ") + e;
  return s;
}

PlannedInput make(const std::string& given, const fs::path& path, InputKind kind) {
  PlannedInput p;
  p.given = given;
  p.path = input_identity(path);
  p.kind = kind;
  return p;
}

PlannedInput unusable(const std::string& given, const fs::path& path, PlanStatus status,
                      std::string reason) {
  PlannedInput p;
  p.given = given;
  std::error_code ec;
  p.path = fs::absolute(path, ec).lexically_normal();
  p.status = status;
  p.reason = std::move(reason);
  return p;
}

// A video file: zero-length ones fail here (nothing could decode them).
PlannedInput video(const std::string& given, const fs::path& path) {
  std::error_code ec;
  const auto size = fs::file_size(path, ec);
  if (ec) return unusable(given, path, PlanStatus::kFailed, "cannot read: " + ec.message());
  if (size == 0) return unusable(given, path, PlanStatus::kFailed, "empty file (0 bytes)");
  return make(given, path, InputKind::kVideo);
}

// One level of a folder that is not a session: its sessions and videos, the rest skipped.
void expand_folder(const std::string& given, const fs::path& folder, const InputOptions& o,
                   std::vector<PlannedInput>& out) {
  std::error_code ec;
  std::vector<fs::path> entries;
  for (fs::directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec))
    if (it->path().filename().string().rfind('.', 0) != 0) entries.push_back(it->path());
  if (ec) {
    out.push_back(unusable(given, folder, PlanStatus::kFailed, "cannot list: " + ec.message()));
    return;
  }
  std::sort(entries.begin(), entries.end());
  size_t inputs = 0;
  std::vector<PlannedInput> found;
  for (const auto& e : entries) {
    const std::string shown = (fs::path(given) / e.filename()).string();
    if (is_session_folder(e, o)) {
      found.push_back(make(shown, e, InputKind::kSession));
      ++inputs;
    } else if (is_folder(e)) {
      found.push_back(
          unusable(shown, e, PlanStatus::kSkipped, "folder without " + o.session_manifest));
    } else if (is_video_file(e, o)) {
      found.push_back(video(shown, e));
      ++inputs;
    } else {
      const std::string ext = e.extension().string();
      found.push_back(unusable(shown, e, PlanStatus::kSkipped,
                               ext.empty() ? std::string("not a video file (no extension)")
                                           : "not a video file (extension " + ext + ")"));
    }
  }
  if (inputs == 0) {
    out.push_back(unusable(given, folder, PlanStatus::kFailed,
                           fmt::format("no {}, no session folders and no video files ({}) in it",
                                       o.session_manifest, known_extensions(o))));
  }
  out.insert(out.end(), found.begin(), found.end());
}

uint64_t fnv1a64(const std::string& s) {
  uint64_t h = 14695981039346656037ull;
  for (unsigned char c : s) {
    h ^= c;
    h *= 1099511628211ull;
  }
  return h;
}

}  // namespace

bool is_video_file(const fs::path& path, const InputOptions& options) {
  const std::string ext = lower(path.extension().string());
  return std::find(options.video_extensions.begin(), options.video_extensions.end(), ext) !=
         options.video_extensions.end();
}

fs::path input_identity(const fs::path& path) {
  std::error_code ec;
  fs::path p = fs::weakly_canonical(fs::absolute(path, ec), ec);
  if (ec) p = fs::absolute(path, ec).lexically_normal();
  if (!p.has_filename() && p.has_parent_path() && p != p.root_path()) p = p.parent_path();
  return p;
}

std::string output_name(const fs::path& identity, const InputOptions& options) {
  const fs::path file = identity.filename();
  std::string stem = is_video_file(file, options) ? file.stem().string() : file.string();
  for (char& c : stem)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '_' || c == '-')) c = '_';
  if (!stem.empty() && stem[0] == '.') stem[0] = '_';
  if (stem.size() > 60) stem.resize(60);
  if (stem.empty()) stem = "input";
  return fmt::format("{}-{:08x}", stem, static_cast<uint32_t>(fnv1a64(identity.string())));
}

std::vector<PlannedInput> expand_inputs(const std::vector<std::string>& arguments,
                                        const InputOptions& options) {
  std::vector<PlannedInput> out;
  for (const auto& given : arguments) {
    const fs::path p(given);
    std::error_code ec;
    const auto st = fs::status(p, ec);
    if (given.empty()) {
      out.push_back(unusable(given, p, PlanStatus::kFailed, "empty path"));
    } else if (!fs::exists(st)) {
      out.push_back(unusable(given, p, PlanStatus::kFailed, "no such file or folder"));
    } else if (fs::is_directory(st)) {
      if (is_session_folder(p, options))
        out.push_back(make(given, p, InputKind::kSession));
      else
        expand_folder(given, p, options, out);
    } else if (fs::is_regular_file(st)) {
      if (p.filename() == options.session_manifest)
        out.push_back(make(given, p.parent_path().empty() ? fs::path(".") : p.parent_path(),
                           InputKind::kSession));
      else if (is_video_file(p, options))
        out.push_back(video(given, p));
      else
        out.push_back(unusable(given, p, PlanStatus::kFailed,
                               fmt::format("not a session folder (no {}) nor a video file ({})",
                                           options.session_manifest, known_extensions(options))));
    } else {
      out.push_back(unusable(given, p, PlanStatus::kFailed, "not a regular file or folder"));
    }
  }
  // Duplicates, path-safety and names.
  std::map<std::string, size_t> first_of_path;
  std::map<std::string, std::string> path_of_name;
  for (size_t i = 0; i < out.size(); ++i) {
    auto& in = out[i];
    if (in.status != PlanStatus::kRun) continue;
    const std::string key = in.path.string();
    if (auto [it, fresh] = first_of_path.emplace(key, i); !fresh) {
      in.status = PlanStatus::kSkipped;
      in.reason = "duplicate of " + out[it->second].given;
      continue;
    }
    if (key.find_first_of("\n\r") != std::string::npos) {
      in.status = PlanStatus::kFailed;
      in.reason = "path contains a line break";
      continue;
    }
    in.name = output_name(in.path, options);
    if (auto [it, fresh] = path_of_name.emplace(in.name, key); !fresh) {
      // Two different paths with the same stem and the same 32-bit hash: vanishingly rare, and
      // never resolved silently (a name must not depend on the other inputs).
      in.status = PlanStatus::kFailed;
      in.reason =
          fmt::format("output name {} is also that of {}; rename one of them", in.name, it->second);
      in.name.clear();
    }
  }
  return out;
}

}  // namespace dreamsense::batch
