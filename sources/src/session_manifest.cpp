// session.yaml: reading, validation and atomic writing (format v1, docs/session_format.md).

#include "dreamsense/core/text.hpp"
#include "dreamsense/sources/session.hpp"

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <cerrno>
#include <cstring>
#include <fcntl.h>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <unistd.h>

#include "posix_file.hpp"

namespace dreamsense::sources {
namespace {

using detail::errno_text;
using detail::sync_dir;

constexpr const char* kFormatName = "dreamsense-session";

tl::unexpected<Error> manifest_error(ErrorCode code, const std::string& what) {
  return make_error(code, "{}: {}", kManifestName, what);
}

// A short, one-line rendering of a scalar for error messages.
std::string scalar_text(const YAML::Node& node) {
  if (node.IsScalar()) return node.Scalar();
  if (node.IsSequence()) return "a list";
  if (node.IsMap()) return "a map";
  return "null";
}

// Reads `key` of `map` as T. `context` is the path of the map ("" or "streams[1]").
template <typename T>
Result<T> get_as(const YAML::Node& map, const std::string& context, const char* key,
                 const char* expected) {
  const std::string name = context.empty() ? key : context + "." + key;
  const YAML::Node node = map[key];
  try {
    if (!node.IsScalar()) throw YAML::BadConversion(node.Mark());
    return node.as<T>();
  } catch (const YAML::Exception&) {
    return manifest_error(ErrorCode::kCorruptData, fmt::format("key '{}': expected {}, got '{}'",
                                                               name, expected, scalar_text(node)));
  }
}

template <typename T>
Result<T> required(const YAML::Node& map, const std::string& context, const char* key,
                   const char* expected) {
  if (!map[key]) {
    const std::string name = context.empty() ? key : context + "." + key;
    return manifest_error(ErrorCode::kCorruptData, fmt::format("missing required key '{}'", name));
  }
  return get_as<T>(map, context, key, expected);
}

template <typename T>
Result<T> optional(const YAML::Node& map, const std::string& context, const char* key,
                   const char* expected, T fallback) {
  if (!map[key] || map[key].IsNull()) return fallback;
  return get_as<T>(map, context, key, expected);
}

// Assigns the value of an expression returning Result<T>, or returns its error.
#define DS_ASSIGN(lhs, expr)                          \
  do {                                                \
    auto ds_r_ = (expr);                              \
    if (!ds_r_) return tl::unexpected(ds_r_.error()); \
    lhs = std::move(*ds_r_);                          \
  } while (0)

bool is_safe_relative(const std::string& file) {
  if (file.empty()) return false;
  const std::filesystem::path p(file);
  if (p.is_absolute()) return false;
  for (const auto& part : p)
    if (part == "..") return false;
  return true;
}

Result<StreamEntry> parse_stream(const YAML::Node& node, size_t i) {
  std::string ctx = fmt::format("streams[{}]", i);
  if (!node.IsMap())
    return manifest_error(ErrorCode::kCorruptData,
                          fmt::format("{}: expected a map, got '{}'", ctx, scalar_text(node)));
  StreamEntry s;
  DS_ASSIGN(s.id, (required<std::string>(node, ctx, "id", "a string")));
  ctx = fmt::format("streams[{}] ({})", i, s.id);
  std::string kind;
  DS_ASSIGN(kind, (required<std::string>(node, ctx, "kind", "a string")));
  auto k = sensor_kind_from_string(kind);
  if (!k)
    return manifest_error(
        ErrorCode::kCorruptData,
        fmt::format("key '{}.kind': unknown kind '{}' (expected color, depth, skeleton or audio)",
                    ctx, kind));
  s.kind = *k;
  DS_ASSIGN(s.encoding, (required<std::string>(node, ctx, "encoding", "a string")));
  DS_ASSIGN(s.file, (required<std::string>(node, ctx, "file", "a string")));
  DS_ASSIGN(s.index, (optional<std::string>(node, ctx, "index", "a string", "")));
  DS_ASSIGN(s.rate_hz, (optional<double>(node, ctx, "rate_hz", "a number", 0.0)));
  const bool image = s.kind == SensorKind::kColor || s.kind == SensorKind::kDepth;
  const bool audio = s.kind == SensorKind::kAudio;
  if (image) {
    DS_ASSIGN(s.width, (required<int>(node, ctx, "width", "an integer")));
    DS_ASSIGN(s.height, (required<int>(node, ctx, "height", "an integer")));
  } else {
    DS_ASSIGN(s.width, (optional<int>(node, ctx, "width", "an integer", 0)));
    DS_ASSIGN(s.height, (optional<int>(node, ctx, "height", "an integer", 0)));
  }
  if (audio) {
    DS_ASSIGN(s.sample_rate, (required<int>(node, ctx, "sample_rate", "an integer")));
    DS_ASSIGN(s.channels, (required<int>(node, ctx, "channels", "an integer")));
  } else {
    DS_ASSIGN(s.sample_rate, (optional<int>(node, ctx, "sample_rate", "an integer", 0)));
    DS_ASSIGN(s.channels, (optional<int>(node, ctx, "channels", "an integer", 0)));
  }
  DS_ASSIGN(s.start_ns, (optional<int64_t>(node, ctx, "start_ns", "an integer", int64_t{0})));
  DS_ASSIGN(s.calibration, (optional<std::string>(node, ctx, "calibration", "a string", "")));
  DS_ASSIGN(s.frame, (optional<std::string>(node, ctx, "frame", "a string", "")));
  // role: one name, or roles: a list (docs/session_format.md "Stream roles").
  for (const char* key : {"role", "roles"}) {
    const YAML::Node r = node[key];
    if (!r || r.IsNull()) continue;
    if (r.IsScalar()) {
      s.roles.push_back(r.Scalar());
    } else if (r.IsSequence()) {
      for (const auto& e : r) {
        if (!e.IsScalar())
          return manifest_error(
              ErrorCode::kCorruptData,
              fmt::format("key '{}.{}': expected a list of role names", ctx, key));
        s.roles.push_back(e.Scalar());
      }
    } else {
      return manifest_error(ErrorCode::kCorruptData,
                            fmt::format("key '{}.{}': expected a role name or a list", ctx, key));
    }
  }
  return s;
}

Result<SessionManifest> parse_manifest(const YAML::Node& root) {
  if (!root.IsMap())
    return manifest_error(ErrorCode::kCorruptData, "not a YAML map (expected 'format: " +
                                                       std::string(kFormatName) + "', ...)");
  SessionManifest m;
  std::string format;
  DS_ASSIGN(format, (required<std::string>(root, "", "format", "a string")));
  if (format != kFormatName)
    return manifest_error(ErrorCode::kUnsupported,
                          fmt::format("format '{}' is not '{}'", format, kFormatName));
  DS_ASSIGN(m.format_version, (required<int>(root, "", "format_version", "an integer")));
  if (m.format_version != kSessionFormatVersion)
    return manifest_error(ErrorCode::kUnsupported,
                          fmt::format("unknown format_version {} (this build reads {})",
                                      m.format_version, kSessionFormatVersion));
  DS_ASSIGN(m.name, (optional<std::string>(root, "", "name", "a string", "")));
  DS_ASSIGN(m.clock_origin_unix_ns,
            (optional<int64_t>(root, "", "clock_origin_unix_ns", "an integer", int64_t{0})));
  if (const YAML::Node p = root["participant"]; p && !p.IsNull()) {
    if (!p.IsMap())
      return manifest_error(ErrorCode::kCorruptData, "key 'participant': expected a map");
    DS_ASSIGN(m.participant.id, (optional<int>(p, "participant", "id", "an integer", 0)));
    if (p["gender"] && !p["gender"].IsNull()) {
      std::string g;
      DS_ASSIGN(g, (get_as<std::string>(p, "participant", "gender", "a string")));
      m.participant.gender = g;
    }
    if (p["age_months"] && !p["age_months"].IsNull()) {
      double a = 0;
      DS_ASSIGN(a, (get_as<double>(p, "participant", "age_months", "a number")));
      m.participant.age_months = a;
    }
  }
  DS_ASSIGN(m.condition, (optional<std::string>(root, "", "condition", "a string", "")));
  DS_ASSIGN(m.task, (optional<std::string>(root, "", "task", "a string", "")));
  DS_ASSIGN(m.frame_rate, (optional<double>(root, "", "frame_rate", "a number", 25.0)));
  // Only SessionWriter writes `complete: false`; hand-made or imported manifests may omit it.
  DS_ASSIGN(m.complete, (optional<bool>(root, "", "complete", "true or false", true)));
  DS_ASSIGN(m.truth, (optional<std::string>(root, "", "truth", "a string", "")));
  if (const YAML::Node md = root["metadata"]; md && !md.IsNull()) {
    if (!md.IsMap())
      return manifest_error(ErrorCode::kCorruptData, "key 'metadata': expected a map");
    for (const auto& kv : md) {
      // A list or map as a key is damage, not a BadConversion out of the reader (fuzz finding 6).
      if (!kv.first.IsScalar())
        return manifest_error(ErrorCode::kCorruptData,
                              "key 'metadata': a key must be a name, not a list or a map");
      const std::string key = kv.first.Scalar();
      if (!kv.second.IsScalar() && !kv.second.IsNull())
        return manifest_error(ErrorCode::kCorruptData,
                              fmt::format("key 'metadata.{}': expected a scalar value", key));
      m.metadata[key] = kv.second.IsNull() ? std::string() : kv.second.Scalar();
    }
  }
  const YAML::Node streams = root["streams"];
  if (!streams) return manifest_error(ErrorCode::kCorruptData, "missing required key 'streams'");
  if (!streams.IsSequence() && !streams.IsNull())
    return manifest_error(ErrorCode::kCorruptData, "key 'streams': expected a list");
  for (size_t i = 0; i < streams.size(); ++i) {
    StreamEntry s;
    DS_ASSIGN(s, parse_stream(streams[i], i));
    m.streams.push_back(std::move(s));
  }
  return m;
}

// Writes `text` to `path` and fsyncs it.
Status write_file_synced(const std::filesystem::path& path, const std::string& text) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0)
    return make_error(ErrorCode::kIoError, "{}: cannot write: {}", path.string(),
                      errno_text(errno));
  size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
    if (n < 0) {
      if (errno == EINTR) continue;
      const int err = errno;
      ::close(fd);
      return make_error(ErrorCode::kIoError, "{}: cannot write: {}", path.string(),
                        errno_text(err));
    }
    done += static_cast<size_t>(n);
  }
  if (::fsync(fd) != 0) {
    const int err = errno;
    ::close(fd);
    return make_error(ErrorCode::kIoError, "{}: fsync failed: {}", path.string(), errno_text(err));
  }
  if (::close(fd) != 0)
    return make_error(ErrorCode::kIoError, "{}: close failed: {}", path.string(),
                      errno_text(errno));
  return ok_status();
}

// Shortest text that reads back as the same double ("25", "29.97").
std::string number_text(double v) { return fmt::format("{}", v); }

}  // namespace

const StreamEntry* SessionManifest::find(const SensorId& id) const {
  for (const auto& s : streams)
    if (s.id == id) return &s;
  return nullptr;
}

void fill_stream_defaults(StreamEntry& s) {
  if (s.frame.empty()) s.frame = s.id;
  if (!s.file.empty()) return;
  if (s.encoding == "mjpeg") {
    s.file = s.id + ".mjpg";
    if (s.index.empty()) s.index = s.id + ".idx";
  } else if (s.encoding == "raw16" || s.encoding == "png16") {
    s.file = s.id + ".depth";
    if (s.index.empty()) s.index = s.id + ".idx";
  } else if (s.encoding == "jsonl") {
    s.file = s.id + ".jsonl";
  } else if (s.encoding == "wav") {
    s.file = s.id + ".wav";
  }
}

Status check_manifest(const SessionManifest& m) {
  if (m.format_version != kSessionFormatVersion)
    return manifest_error(ErrorCode::kUnsupported,
                          fmt::format("unknown format_version {} (this build reads {})",
                                      m.format_version, kSessionFormatVersion));
  if (m.frame_rate <= 0)
    return manifest_error(ErrorCode::kInvalidArgument,
                          fmt::format("key 'frame_rate': must be > 0, got {}", m.frame_rate));
  if (!m.truth.empty() && !is_safe_relative(m.truth))
    return manifest_error(ErrorCode::kInvalidArgument,
                          fmt::format("key 'truth': '{}' is not a relative path inside the "
                                      "session folder",
                                      m.truth));
  std::set<std::string> ids, files;
  for (size_t i = 0; i < m.streams.size(); ++i) {
    const StreamEntry& s = m.streams[i];
    const std::string ctx = fmt::format("streams[{}] ({})", i, s.id);
    auto bad = [&](ErrorCode code, const std::string& what) {
      return manifest_error(code, fmt::format("{}: {}", ctx, what));
    };
    if (s.id.empty())
      return manifest_error(ErrorCode::kInvalidArgument,
                            fmt::format("key 'streams[{}].id': must not be empty", i));
    if (!ids.insert(s.id).second)
      return manifest_error(ErrorCode::kInvalidArgument,
                            fmt::format("duplicate stream id '{}' (streams[{}])", s.id, i));
    const char* expected = "";
    switch (s.kind) {
      case SensorKind::kColor:
        expected = "mjpeg or video";
        break;
      case SensorKind::kDepth:
        expected = "raw16 or png16";
        break;
      case SensorKind::kSkeleton:
        expected = "jsonl";
        break;
      case SensorKind::kAudio:
        expected = "wav";
        break;
    }
    const bool encoding_ok =
        (s.kind == SensorKind::kColor && (s.encoding == "mjpeg" || s.encoding == "video")) ||
        (s.kind == SensorKind::kDepth && (s.encoding == "raw16" || s.encoding == "png16")) ||
        (s.kind == SensorKind::kSkeleton && s.encoding == "jsonl") ||
        (s.kind == SensorKind::kAudio && s.encoding == "wav");
    if (!encoding_ok)
      return bad(ErrorCode::kUnsupported,
                 fmt::format("key 'encoding': unknown encoding '{}' for kind {} (expected {})",
                             s.encoding, to_string(s.kind), expected));
    if (!is_safe_relative(s.file))
      return bad(
          ErrorCode::kInvalidArgument,
          fmt::format("key 'file': '{}' is not a relative path inside the session folder", s.file));
    const bool indexed = s.encoding == "mjpeg" || s.encoding == "raw16" || s.encoding == "png16" ||
                         s.encoding == "video";
    if (indexed && s.index.empty())
      return bad(ErrorCode::kInvalidArgument,
                 fmt::format("missing required key 'index' (encoding {})", s.encoding));
    if (!s.index.empty() && !is_safe_relative(s.index))
      return bad(ErrorCode::kInvalidArgument,
                 fmt::format("key 'index': '{}' is not a relative path inside the session folder",
                             s.index));
    if (!s.calibration.empty() && !is_safe_relative(s.calibration))
      return bad(ErrorCode::kInvalidArgument,
                 fmt::format("key 'calibration': '{}' is not a relative path inside the session "
                             "folder",
                             s.calibration));
    for (const std::string* f : {&s.file, &s.index}) {
      if (f->empty()) continue;
      if (!files.insert(*f).second)
        return bad(ErrorCode::kInvalidArgument,
                   fmt::format("file '{}' is used by another stream", *f));
    }
    if (s.kind == SensorKind::kColor || s.kind == SensorKind::kDepth) {
      if (s.width <= 0 || s.height <= 0)
        return bad(
            ErrorCode::kInvalidArgument,
            fmt::format("keys 'width', 'height': must be > 0, got {}x{}", s.width, s.height));
    }
    if (s.kind == SensorKind::kAudio) {
      if (s.sample_rate <= 0)
        return bad(ErrorCode::kInvalidArgument,
                   fmt::format("key 'sample_rate': must be > 0, got {}", s.sample_rate));
      if (s.channels <= 0)
        return bad(ErrorCode::kInvalidArgument,
                   fmt::format("key 'channels': must be > 0, got {}", s.channels));
    }
    if (s.rate_hz < 0)
      return bad(ErrorCode::kInvalidArgument,
                 fmt::format("key 'rate_hz': must be >= 0, got {}", s.rate_hz));
  }
  return ok_status();
}

Result<std::map<SensorId, std::vector<std::string>>> stream_roles(const SessionManifest& m) {
  struct RoleRule {
    const char* role;
    SensorKind kind;
    bool exclusive;
  };
  static const RoleRule kKnown[] = {
      {"child_camera", SensorKind::kColor, false}, {"table_camera", SensorKind::kColor, true},
      {"table_depth", SensorKind::kDepth, true},   {"body", SensorKind::kSkeleton, true},
      {"mic_array", SensorKind::kAudio, true},     {"robot_audio", SensorKind::kAudio, true},
  };
  auto rule = [](const std::string& role) -> const RoleRule* {
    for (const auto& r : kKnown)
      if (role == r.role) return &r;
    return nullptr;
  };
  std::map<SensorId, std::vector<std::string>> out;
  std::map<std::string, SensorId> claimed;  // exclusive role -> stream
  // Declared roles first, so that a default never takes a role a later stream declares.
  for (const auto& s : m.streams) {
    for (const auto& role : s.roles) {
      const RoleRule* r = rule(role);
      if (r != nullptr && r->kind != s.kind)
        return manifest_error(ErrorCode::kInvalidArgument,
                              fmt::format("stream '{}': role {} needs a {} stream, not {}", s.id,
                                          role, to_string(r->kind), to_string(s.kind)));
      if (r != nullptr && r->exclusive && !claimed.emplace(role, s.id).second)
        return manifest_error(ErrorCode::kInvalidArgument,
                              fmt::format("streams '{}' and '{}' both claim the role {}, which "
                                          "only one stream can have",
                                          claimed[role], s.id, role));
      out[s.id].push_back(role);
    }
  }
  auto starts_with = [](const std::string& id, const char* prefix) {
    return id.rfind(prefix, 0) == 0;
  };
  for (const auto& s : m.streams) {
    if (!s.roles.empty()) continue;
    std::string role;
    if (s.kind == SensorKind::kColor && starts_with(s.id, "camera")) role = "child_camera";
    if (s.kind == SensorKind::kColor && starts_with(s.id, "top")) role = "table_camera";
    if (s.kind == SensorKind::kDepth && starts_with(s.id, "top")) role = "table_depth";
    if (s.kind == SensorKind::kSkeleton) role = "body";
    if (s.kind == SensorKind::kAudio) role = "mic_array";
    if (role.empty()) {
      out[s.id];
      continue;
    }
    const RoleRule* r = rule(role);
    if (r->exclusive && !claimed.emplace(role, s.id).second) {
      out[s.id];  // by convention only the first such stream gets an exclusive role
      continue;
    }
    out[s.id].push_back(role);
  }
  return out;
}

Result<std::map<SensorId, CameraModel>> read_color_calibrations(
    const std::filesystem::path& session_dir, const SessionManifest& manifest) {
  std::map<SensorId, CameraModel> out;
  for (const StreamEntry& s : manifest.streams) {
    if (s.kind != SensorKind::kColor || s.calibration.empty()) continue;
    auto m = read_camera_model(session_dir / s.calibration);
    if (!m) return tl::unexpected(m.error());
    out.emplace(s.id, std::move(*m));
  }
  return out;
}

Result<SessionManifest> read_manifest(const std::filesystem::path& session_dir) {
  const auto path = session_dir / kManifestName;
  std::error_code ec;
  if (!std::filesystem::is_directory(session_dir, ec))
    return make_error(ErrorCode::kNotFound, "{}: not a session folder (no such directory)",
                      session_dir.string());
  if (!std::filesystem::exists(path, ec))
    return make_error(ErrorCode::kNotFound, "{}: missing in {} (not a session folder)",
                      kManifestName, session_dir.string());
  std::ifstream in(path);
  if (!in)
    return make_error(ErrorCode::kIoError, "{}: cannot read: {}", kManifestName, errno_text(errno));
  std::stringstream text;
  text << in.rdbuf();
  // Names and notes end up in JSON outputs, which must be UTF-8: refuse here, naming the line,
  // rather than fail after the whole analysis.
  if (auto bad = find_invalid_utf8(text.str()))
    return manifest_error(ErrorCode::kCorruptData,
                          fmt::format("line {}: not valid UTF-8 text (byte {})",
                                      line_of_offset(text.str(), *bad), *bad));
  YAML::Node root;
  try {
    root = YAML::Load(text.str());
  } catch (const YAML::Exception& e) {
    return manifest_error(ErrorCode::kCorruptData,
                          fmt::format("line {}: invalid YAML: {}", e.mark.line + 1, e.msg));
  }
  auto m = parse_manifest(root);
  if (!m) return m;
  if (auto st = check_manifest(*m); !st) return tl::unexpected(st.error());
  return m;
}

Status write_manifest(const std::filesystem::path& session_dir, const SessionManifest& m) {
  YAML::Emitter out;
  out << YAML::BeginMap;
  out << YAML::Key << "format" << YAML::Value << kFormatName;
  out << YAML::Key << "format_version" << YAML::Value << m.format_version;
  out << YAML::Key << "name" << YAML::Value << m.name;
  out << YAML::Key << "clock_origin_unix_ns" << YAML::Value
      << static_cast<long long>(m.clock_origin_unix_ns);
  out << YAML::Key << "participant" << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "id" << YAML::Value << m.participant.id;
  if (m.participant.gender) out << YAML::Key << "gender" << YAML::Value << *m.participant.gender;
  if (m.participant.age_months)
    out << YAML::Key << "age_months" << YAML::Value << number_text(*m.participant.age_months);
  out << YAML::EndMap;
  out << YAML::Key << "condition" << YAML::Value << m.condition;
  out << YAML::Key << "task" << YAML::Value << m.task;
  out << YAML::Key << "frame_rate" << YAML::Value << number_text(m.frame_rate);
  out << YAML::Key << "complete" << YAML::Value << m.complete;
  out << YAML::Key << "truth" << YAML::Value << m.truth;
  out << YAML::Key << "metadata" << YAML::Value << YAML::BeginMap;
  for (const auto& [k, v] : m.metadata) out << YAML::Key << k << YAML::Value << v;
  out << YAML::EndMap;
  out << YAML::Key << "streams" << YAML::Value << YAML::BeginSeq;
  for (const auto& s : m.streams) {
    out << YAML::BeginMap;
    out << YAML::Key << "id" << YAML::Value << s.id;
    out << YAML::Key << "kind" << YAML::Value << to_string(s.kind);
    out << YAML::Key << "encoding" << YAML::Value << s.encoding;
    out << YAML::Key << "file" << YAML::Value << s.file;
    if (!s.index.empty()) out << YAML::Key << "index" << YAML::Value << s.index;
    out << YAML::Key << "rate_hz" << YAML::Value << number_text(s.rate_hz);
    if (s.kind == SensorKind::kColor || s.kind == SensorKind::kDepth) {
      out << YAML::Key << "width" << YAML::Value << s.width;
      out << YAML::Key << "height" << YAML::Value << s.height;
    }
    if (s.kind == SensorKind::kAudio) {
      out << YAML::Key << "sample_rate" << YAML::Value << s.sample_rate;
      out << YAML::Key << "channels" << YAML::Value << s.channels;
      out << YAML::Key << "start_ns" << YAML::Value << static_cast<long long>(s.start_ns);
    }
    if (!s.calibration.empty()) out << YAML::Key << "calibration" << YAML::Value << s.calibration;
    if (!s.frame.empty()) out << YAML::Key << "frame" << YAML::Value << s.frame;
    if (s.roles.size() == 1) out << YAML::Key << "role" << YAML::Value << s.roles.front();
    if (s.roles.size() > 1) out << YAML::Key << "roles" << YAML::Value << s.roles;
    out << YAML::EndMap;
  }
  out << YAML::EndSeq;
  out << YAML::EndMap;
  if (!out.good())
    return manifest_error(ErrorCode::kInternal,
                          fmt::format("cannot emit YAML: {}", out.GetLastError()));
  std::string text = "# dreamsense session manifest (docs/session_format.md)\n";
  text += out.c_str();
  text += "\n";

  const auto final_path = session_dir / kManifestName;
  const auto tmp_path = session_dir / fmt::format(".{}.tmp.{}", kManifestName, ::getpid());
  if (auto st = write_file_synced(tmp_path, text); !st) return st;
  std::error_code ec;
  std::filesystem::rename(tmp_path, final_path, ec);
  if (ec) {
    std::filesystem::remove(tmp_path, ec);
    return make_error(ErrorCode::kIoError, "{}: cannot replace {}: {}", tmp_path.string(),
                      final_path.string(), ec.message());
  }
  sync_dir(session_dir);
  return ok_status();
}

}  // namespace dreamsense::sources
