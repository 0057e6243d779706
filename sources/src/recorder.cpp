#include "dreamsense/sources/recorder.hpp"

#include "dreamsense/core/log.hpp"
#include "dreamsense/core/output_file.hpp"
#include "dreamsense/sources/alsa_audio_source.hpp"
#include "dreamsense/sources/camera_source.hpp"
#include "dreamsense/sources/depth_sensor_source.hpp"
#include "dreamsense/sources/udp_skeleton_source.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <yaml-cpp/yaml.h>

#include <chrono>
#include <fstream>
#include <mutex>
#include <set>
#include <thread>

#include "capture_queue.hpp"

namespace dreamsense::sources {

namespace fs = std::filesystem;

namespace {

// std::filesystem's queries without exceptions: a path the system refuses (too long, a symlink
// loop) is simply not there. The throwing forms ended `record --config` on such a path (fuzz
// finding: fuzz_configs, fuzz/findings/record_config_long_path.configs).
bool regular_file_exists(const fs::path& p) {
  std::error_code ec;
  return fs::is_regular_file(p, ec);
}
bool folder_exists(const fs::path& p) {
  std::error_code ec;
  return fs::is_directory(p, ec);
}
bool path_exists(const fs::path& p) {
  std::error_code ec;
  return fs::exists(p, ec);
}

// YAML access with errors that name the file and the key.
class ConfigReader {
 public:
  explicit ConfigReader(fs::path file) : file_(std::move(file)) {}

  tl::unexpected<Error> error(const std::string& key, const std::string& what) const {
    return make_error(ErrorCode::kInvalidArgument, "{}: {}{}{}", file_.string(), key,
                      key.empty() ? "" : ": ", what);
  }

  // A key that is not a plain name (`? [a, b]: 1` makes a list the key) is the user's error, not
  // the YAML::BadConversion that as<std::string>() throws (fuzz finding 6).
  Result<std::string> key_name(const YAML::Node& key, const std::string& context) const {
    if (!key.IsScalar()) return error(context, "a key must be a name, not a list or a map");
    return key.Scalar();
  }

  Status only_keys(const YAML::Node& map, const std::string& context,
                   std::initializer_list<const char*> allowed) const {
    if (!map.IsMap()) return error(context, "expected a map");
    for (const auto& kv : map) {
      DS_ASSIGN_OR_RETURN(const auto key, key_name(kv.first, context));
      if (std::none_of(allowed.begin(), allowed.end(), [&](const char* k) { return key == k; })) {
        std::string list;
        for (const char* k : allowed) list += (list.empty() ? "" : ", ") + std::string(k);
        return error(context.empty() ? key : context + "." + key,
                     fmt::format("unknown key (allowed: {})", list));
      }
    }
    return ok_status();
  }

  template <typename T>
  Status get(const YAML::Node& map, const std::string& context, const char* key, T& out) const {
    const YAML::Node n = map[key];
    if (!n || n.IsNull()) return ok_status();
    try {
      if (!n.IsScalar()) throw YAML::BadConversion(n.Mark());
      out = n.as<T>();
    } catch (const YAML::Exception&) {
      return error(context.empty() ? key : context + "." + key, "wrong type");
    }
    return ok_status();
  }

  Status get_path(const YAML::Node& map, const std::string& context, const char* key,
                  fs::path& out) const {
    std::string s;
    if (auto st = get(map, context, key, s); !st) return st;
    if (!s.empty()) out = fs::path(s).is_absolute() ? fs::path(s) : file_.parent_path() / s;
    return ok_status();
  }

 private:
  fs::path file_;
};

#define DS_TRY(expr)                                                          \
  do {                                                                        \
    if (auto ds_st_ = (expr); !ds_st_) return tl::unexpected(ds_st_.error()); \
  } while (0)

Status copy_into(const fs::path& from, const fs::path& to) {
  std::error_code ec;
  fs::create_directories(to.parent_path(), ec);
  if (folder_exists(from))
    fs::copy(from, to, fs::copy_options::recursive | fs::copy_options::overwrite_existing, ec);
  else
    fs::copy_file(from, to, fs::copy_options::overwrite_existing, ec);
  if (ec)
    return make_error(ErrorCode::kIoError, "cannot copy {} to {}: {}", from.string(), to.string(),
                      ec.message());
  return ok_status();
}

}  // namespace

Status RecordConfig::check() const {
  std::string bad;
  auto add = [&](const std::string& s) { bad += (bad.empty() ? "" : "; ") + s; };
  if (cameras.empty() && skeletons.empty() && depth_sensors.empty() && !audio)
    add("no cameras, depth sensors, skeletons or audio: nothing to record");
  std::set<std::string> ids;
  for (const auto& d : depth_sensors) {
    DepthSensorOptions o;
    o.id = d.id;
    o.driver = d.driver;
    o.device = d.device;
    o.fps = d.fps;
    if (auto st = o.check(); !st) add(st.error().message);
    for (const std::string& sid : {d.id + ".depth", d.id + ".color"})
      if (!ids.insert(sid).second) add(fmt::format("stream id '{}' is used twice", sid));
    if (!d.calibration.empty() && !regular_file_exists(d.calibration))
      add(fmt::format("depth sensor '{}': calibration {} not found", d.id, d.calibration.string()));
  }
  for (const auto& c : cameras) {
    if (c.id.empty()) add("a camera has no id");
    if (c.device.empty()) add(fmt::format("camera '{}' has no device", c.id));
    if (!ids.insert(c.id).second) add(fmt::format("stream id '{}' is used twice", c.id));
    if (!c.calibration.empty() && !regular_file_exists(c.calibration))
      add(fmt::format("camera '{}': calibration {} not found", c.id, c.calibration.string()));
  }
  for (const auto& k : skeletons) {
    if (k.id.empty()) add("a skeleton input has no id");
    if (!ids.insert(k.id).second) add(fmt::format("stream id '{}' is used twice", k.id));
    if (k.port < 0 || k.port > 65535) add(fmt::format("skeleton '{}': port out of range", k.id));
    if (!(k.rate_hz > 0)) add(fmt::format("skeleton '{}': rate_hz must be > 0", k.id));
    if (!k.calibration.empty() && !regular_file_exists(k.calibration))
      add(fmt::format("skeleton '{}': calibration {} not found", k.id, k.calibration.string()));
  }
  if (audio) {
    if (audio->id.empty()) add("audio has no id");
    if (!ids.insert(audio->id).second) add(fmt::format("stream id '{}' is used twice", audio->id));
    if (!audio->calibration.empty() && !regular_file_exists(audio->calibration))
      add(fmt::format("audio: calibration {} not found", audio->calibration.string()));
  }
  if (robot_audio) {
    if (!audio)
      add("robot_audio without audio: the robot's voice is a reference for the microphone "
          "array's analysers");
    if (robot_audio->id.empty()) add("robot_audio has no id");
    if (robot_audio->device.empty()) add("robot_audio has no device");
    if (!ids.insert(robot_audio->id).second)
      add(fmt::format("stream id '{}' is used twice", robot_audio->id));
  }
  if (!speech_grammar.empty() && !regular_file_exists(speech_grammar))
    add(fmt::format("speech_grammar {} not found", speech_grammar.string()));
  if (!voice_enroll.empty() && !folder_exists(voice_enroll))
    add(fmt::format("voice_enroll {} is not a folder", voice_enroll.string()));
  if (!bad.empty()) return make_error(ErrorCode::kInvalidArgument, "record config: {}", bad);
  return ok_status();
}

Result<RecordConfig> read_record_config(const fs::path& file) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(file.string());
  } catch (const YAML::BadFile&) {
    return make_error(ErrorCode::kNotFound, "{}: cannot read the configuration", file.string());
  } catch (const YAML::Exception& e) {
    return make_error(ErrorCode::kInvalidArgument, "{}:{}: {}", file.string(), e.mark.line + 1,
                      e.msg);
  }
  const ConfigReader r(file);
  RecordConfig c;
  DS_TRY(r.only_keys(root, "",
                     {"session", "cameras", "depth_sensors", "skeletons", "audio", "robot_audio"}));
  if (const YAML::Node s = root["session"]; s && !s.IsNull()) {
    DS_TRY(r.only_keys(s, "session",
                       {"name", "participant", "condition", "task", "metadata", "speech_grammar",
                        "voice_enroll"}));
    DS_TRY(r.get(s, "session", "name", c.name));
    DS_TRY(r.get(s, "session", "condition", c.condition));
    DS_TRY(r.get(s, "session", "task", c.task));
    DS_TRY(r.get_path(s, "session", "speech_grammar", c.speech_grammar));
    DS_TRY(r.get_path(s, "session", "voice_enroll", c.voice_enroll));
    if (const YAML::Node p = s["participant"]; p && !p.IsNull()) {
      DS_TRY(r.only_keys(p, "session.participant", {"id", "gender", "age_months"}));
      DS_TRY(r.get(p, "session.participant", "id", c.participant.id));
      std::string gender;
      DS_TRY(r.get(p, "session.participant", "gender", gender));
      if (!gender.empty()) c.participant.gender = gender;
      double age = -1;
      DS_TRY(r.get(p, "session.participant", "age_months", age));
      if (age >= 0) c.participant.age_months = age;
    }
    if (const YAML::Node m = s["metadata"]; m && !m.IsNull()) {
      if (!m.IsMap()) return r.error("session.metadata", "expected a map");
      for (const auto& kv : m) {
        DS_ASSIGN_OR_RETURN(const auto key, r.key_name(kv.first, "session.metadata"));
        if (!kv.second.IsScalar())
          return r.error("session.metadata." + key, "expected a single value");
        c.metadata[key] = kv.second.Scalar();
      }
    }
  }
  if (const YAML::Node cams = root["cameras"]; cams && !cams.IsNull()) {
    if (!cams.IsSequence()) return r.error("cameras", "expected a list");
    for (size_t i = 0; i < cams.size(); ++i) {
      const std::string ctx = fmt::format("cameras[{}]", i);
      RecordCameraConfig cam;
      DS_TRY(r.only_keys(cams[i], ctx, {"id", "device", "width", "height", "fps", "calibration"}));
      DS_TRY(r.get(cams[i], ctx, "id", cam.id));
      DS_TRY(r.get(cams[i], ctx, "device", cam.device));
      DS_TRY(r.get(cams[i], ctx, "width", cam.width));
      DS_TRY(r.get(cams[i], ctx, "height", cam.height));
      DS_TRY(r.get(cams[i], ctx, "fps", cam.fps));
      DS_TRY(r.get_path(cams[i], ctx, "calibration", cam.calibration));
      // A video file given by a relative path is relative to the configuration too.
      if (!cam.device.empty() && !fs::path(cam.device).is_absolute() &&
          regular_file_exists(file.parent_path() / cam.device))
        cam.device = (file.parent_path() / cam.device).string();
      c.cameras.push_back(cam);
    }
  }
  if (const YAML::Node ds = root["depth_sensors"]; ds && !ds.IsNull()) {
    if (!ds.IsSequence()) return r.error("depth_sensors", "expected a list");
    for (size_t i = 0; i < ds.size(); ++i) {
      const std::string ctx = fmt::format("depth_sensors[{}]", i);
      RecordDepthSensorConfig d;
      DS_TRY(r.only_keys(ds[i], ctx, {"id", "driver", "device", "fps", "color", "calibration"}));
      DS_TRY(r.get(ds[i], ctx, "id", d.id));
      DS_TRY(r.get(ds[i], ctx, "driver", d.driver));
      DS_TRY(r.get(ds[i], ctx, "device", d.device));
      DS_TRY(r.get(ds[i], ctx, "fps", d.fps));
      DS_TRY(r.get(ds[i], ctx, "color", d.color));
      DS_TRY(r.get_path(ds[i], ctx, "calibration", d.calibration));
      // An .oni recording given by a relative path is relative to the configuration.
      if (!d.device.empty() && regular_file_exists(file.parent_path() / d.device))
        d.device = (file.parent_path() / d.device).string();
      c.depth_sensors.push_back(d);
    }
  }
  if (const YAML::Node sks = root["skeletons"]; sks && !sks.IsNull()) {
    if (!sks.IsSequence()) return r.error("skeletons", "expected a list");
    for (size_t i = 0; i < sks.size(); ++i) {
      const std::string ctx = fmt::format("skeletons[{}]", i);
      RecordSkeletonConfig k;
      DS_TRY(r.only_keys(sks[i], ctx, {"id", "udp", "rate_hz", "calibration"}));
      DS_TRY(r.get(sks[i], ctx, "id", k.id));
      std::string udp;
      DS_TRY(r.get(sks[i], ctx, "udp", udp));
      // "host:port" or a port alone (127.0.0.1).
      const auto colon = udp.rfind(':');
      const std::string port_text = colon == std::string::npos ? udp : udp.substr(colon + 1);
      if (colon != std::string::npos) k.host = udp.substr(0, colon);
      try {
        size_t used = 0;
        k.port = std::stoi(port_text, &used);
        if (used != port_text.size()) throw std::invalid_argument(port_text);
      } catch (const std::exception&) {
        return r.error(ctx + ".udp", "expected \"host:port\" or a port number");
      }
      DS_TRY(r.get(sks[i], ctx, "rate_hz", k.rate_hz));
      DS_TRY(r.get_path(sks[i], ctx, "calibration", k.calibration));
      c.skeletons.push_back(k);
    }
  }
  if (const YAML::Node a = root["audio"]; a && !a.IsNull()) {
    RecordAudioConfig au;
    DS_TRY(r.only_keys(a, "audio", {"id", "device", "sample_rate", "channels", "calibration"}));
    DS_TRY(r.get(a, "audio", "id", au.id));
    DS_TRY(r.get(a, "audio", "device", au.device));
    DS_TRY(r.get(a, "audio", "sample_rate", au.sample_rate));
    DS_TRY(r.get(a, "audio", "channels", au.channels));
    DS_TRY(r.get_path(a, "audio", "calibration", au.calibration));
    c.audio = au;
  }
  if (const YAML::Node a = root["robot_audio"]; a && !a.IsNull()) {
    RecordRobotAudioConfig ra;
    DS_TRY(r.only_keys(a, "robot_audio", {"id", "device", "sample_rate", "channels"}));
    DS_TRY(r.get(a, "robot_audio", "id", ra.id));
    DS_TRY(r.get(a, "robot_audio", "device", ra.device));
    DS_TRY(r.get(a, "robot_audio", "sample_rate", ra.sample_rate));
    DS_TRY(r.get(a, "robot_audio", "channels", ra.channels));
    c.robot_audio = ra;
  }
  if (auto st = c.check(); !st)
    return make_error(st.error().code, "{}: {}", file.string(), st.error().message);
  return c;
}

struct LiveCapture::Impl {
  SessionManifest manifest;  // absolute file references (see manifest())
  std::chrono::steady_clock::time_point origin;
  std::vector<std::unique_ptr<CameraSource>> cameras;
  std::vector<std::unique_ptr<UdpSkeletonSource>> skeletons;
  std::vector<std::unique_ptr<DepthSensorSource>> depth_sensors;
  // The microphone array, then the robot's voice when configured.
  std::vector<std::unique_ptr<AlsaAudioSource>> audio;
  std::unique_ptr<SessionWriter> writer;  // when recording
  std::vector<std::thread> pumps;
  // Frames of all devices waiting for next(); the oldest are dropped when the consumer falls
  // behind. Finished with the first failure when the last pump ends.
  detail::CaptureQueue queue{256};
  mutable std::mutex mutex;    // writer, stats, running, failure
  int running = 0;             // pump threads still delivering
  bool until_stopped = false;  // LiveCaptureOptions
  bool stopped = false;        // stop_all() was called
  bool devices_ended = false;  // every device ended by itself; the queue waits for stop_all()
  std::optional<Error> failure;
  bool finished = false;
  RecordStats stats;

  ~Impl() {
    stop_all();
    for (auto& t : pumps)
      if (t.joinable()) t.join();
  }

  void stop_all() {
    bool end_now = false;
    {
      std::lock_guard lock(mutex);
      stopped = true;
      end_now = devices_ended;
    }
    for (auto& c : cameras) c->stop();
    for (auto& k : skeletons) k->stop();
    for (auto& d : depth_sensors) d->stop();
    for (auto& a : audio) a->stop();
    if (end_now) queue.finish(std::nullopt);
  }

  void fail(const Error& e) {
    {
      std::lock_guard lock(mutex);
      if (!failure) failure = e;
    }
    stop_all();
  }

  // A device failed mid-session: its streams go offline; the other devices and the recording go
  // on (a session must not end because one camera was unplugged).
  void lose(const Source& device, const Error& e) {
    const double at_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - origin).count();
    std::vector<std::string> ids;
    for (const SensorDescription& d : device.info().sensors) ids.push_back(d.id);
    log::error(
        "live capture: {} ({:.1f} s into the session): {} offline from here on; the other "
        "devices go on",
        e.message, at_s, fmt::join(ids, ", "));
    std::lock_guard lock(mutex);
    for (const auto& id : ids)
      stats.streams[id].lost = fmt::format("{} ({:.1f} s)", e.message, at_s);
  }

  // Moves one device's frames into the recording and the merged queue.
  void pump(Source& source) {
    while (true) {
      auto f = source.next();
      if (!f) {
        if (!is_end_of_stream(f.error())) lose(source, f.error());
        break;
      }
      Status written = ok_status();
      {
        std::lock_guard lock(mutex);
        if (writer) written = writer->write(**f);
        if (written) ++stats.streams[(*f)->sensor].frames_written;
      }
      if (!written) {
        fail(written.error());
        break;
      }
      queue.push(std::move(*f), [this](const FramePtr& dropped) {
        std::lock_guard lock(mutex);
        ++stats.streams[dropped->sensor].frames_dropped;
      });
    }
    std::optional<Error> end;
    {
      std::lock_guard lock(mutex);
      if (--running > 0) return;
      end = failure;
      if (until_stopped && !stopped && !failure) {
        devices_ended = true;  // stop_all() ends the stream
        return;
      }
    }
    queue.finish(std::move(end));
  }
};

LiveCapture::LiveCapture(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
LiveCapture::~LiveCapture() = default;

Result<std::unique_ptr<LiveCapture>> LiveCapture::open(const RecordConfig& config,
                                                       const std::optional<fs::path>& record_dir,
                                                       const SessionWriterOptions& writer_options,
                                                       const LiveCaptureOptions& capture_options) {
  if (auto st = config.check(); !st) return tl::unexpected(st.error());
  if (auto st = writer_options.check(); !st) return tl::unexpected(st.error());
  if (record_dir && path_exists(*record_dir / kManifestName))
    return make_error(ErrorCode::kInvalidArgument,
                      "{} already holds a session (choose a new folder)", record_dir->string());

  auto m = std::make_unique<Impl>();
  m->until_stopped = capture_options.until_stopped;
  // Open every device first: a missing camera is an error before anything is written.
  m->origin = std::chrono::steady_clock::now();
  const auto wall_origin = std::chrono::system_clock::now();
  for (const auto& c : config.cameras) {
    CameraSourceOptions co;
    co.sensor = c.id;
    co.device = c.device;
    co.width = c.width;
    co.height = c.height;
    co.fps = c.fps;
    co.clock_origin = m->origin;
    auto cam = CameraSource::open(co);
    if (!cam) return tl::unexpected(cam.error());
    m->cameras.push_back(std::move(*cam));
  }
  for (const auto& d : config.depth_sensors) {
    DepthSensorOptions o;
    o.id = d.id;
    o.driver = d.driver;
    o.device = d.device;
    o.fps = d.fps;
    o.color = d.color;
    o.clock_origin = m->origin;
    auto src = DepthSensorSource::open(o);
    if (!src) return tl::unexpected(src.error());
    m->depth_sensors.push_back(std::move(*src));
  }
  for (const auto& k : config.skeletons) {
    UdpSkeletonSourceOptions so;
    so.sensor = k.id;
    so.host = k.host;
    so.port = k.port;
    so.rate_hz = k.rate_hz;
    so.clock_origin = m->origin;
    auto src = UdpSkeletonSource::open(so);
    if (!src) return tl::unexpected(src.error());
    m->skeletons.push_back(std::move(*src));
  }
  auto open_audio = [&](const SensorId& id, const std::string& device, int sample_rate,
                        int channels) -> Status {
    AlsaAudioSourceOptions ao;
    ao.sensor = id;
    ao.device = device;
    ao.sample_rate = sample_rate;
    ao.channels = channels;
    ao.clock_origin = m->origin;
    auto a = AlsaAudioSource::open(ao);
    if (!a) return tl::unexpected(a.error());
    m->audio.push_back(std::move(*a));
    return ok_status();
  };
  if (config.audio)
    DS_RETURN_IF_ERROR(open_audio(config.audio->id, config.audio->device, config.audio->sample_rate,
                                  config.audio->channels));
  if (config.robot_audio)
    DS_RETURN_IF_ERROR(open_audio(config.robot_audio->id, config.robot_audio->device,
                                  config.robot_audio->sample_rate, config.robot_audio->channels));

  SessionManifest& man = m->manifest;
  man.name = !config.name.empty() ? config.name
             : record_dir         ? record_dir->filename().string()
                                  : std::string("live");
  man.clock_origin_unix_ns =
      std::chrono::duration_cast<std::chrono::nanoseconds>(wall_origin.time_since_epoch()).count();
  man.participant = config.participant;
  man.condition = config.condition;
  man.task = config.task;
  man.metadata = config.metadata;
  man.metadata["generator"] = "dreamsense record";
  auto absolute = [](const fs::path& p) { return fs::absolute(p).lexically_normal().string(); };
  for (size_t i = 0; i < m->cameras.size(); ++i) {
    StreamEntry s;
    s.id = config.cameras[i].id;
    s.kind = SensorKind::kColor;
    s.encoding = "mjpeg";
    s.rate_hz = m->cameras[i]->fps();
    s.width = m->cameras[i]->size().width;
    s.height = m->cameras[i]->size().height;
    if (!config.cameras[i].calibration.empty())
      s.calibration = absolute(config.cameras[i].calibration);
    man.streams.push_back(s);
  }
  for (size_t i = 0; i < m->depth_sensors.size(); ++i)
    for (const SensorDescription& d : m->depth_sensors[i]->info().sensors) {
      StreamEntry s;
      s.id = d.id;
      s.kind = d.kind;
      s.encoding = d.kind == SensorKind::kDepth ? "raw16" : "mjpeg";
      s.rate_hz = d.rate_hz;
      s.width = d.width;
      s.height = d.height;
      if (!config.depth_sensors[i].calibration.empty())
        s.calibration = absolute(config.depth_sensors[i].calibration);
      man.streams.push_back(s);
    }
  for (size_t i = 0; i < m->skeletons.size(); ++i) {
    StreamEntry s;
    s.id = config.skeletons[i].id;
    s.kind = SensorKind::kSkeleton;
    s.encoding = "jsonl";
    s.rate_hz = config.skeletons[i].rate_hz;
    if (!config.skeletons[i].calibration.empty())
      s.calibration = absolute(config.skeletons[i].calibration);
    man.streams.push_back(s);
  }
  for (const auto& a : m->audio) {
    const SensorDescription d = a->info().sensors.front();  // info() returns a copy
    StreamEntry s;
    s.id = d.id;
    s.kind = SensorKind::kAudio;
    s.encoding = "wav";
    s.sample_rate = d.sample_rate;
    s.channels = d.channels;
    s.rate_hz = d.rate_hz;
    const bool robot = config.robot_audio && d.id == config.robot_audio->id;
    if (!robot && !config.audio->calibration.empty())
      s.calibration = absolute(config.audio->calibration);
    // With two audio streams each says what it is (stream_roles would otherwise give the first
    // the microphone array's role by default and the second none).
    if (config.robot_audio) s.roles = {robot ? "robot_audio" : "mic_array"};
    man.streams.push_back(s);
  }
  if (!config.speech_grammar.empty())
    man.metadata["speech_grammar"] = absolute(config.speech_grammar);
  if (!config.voice_enroll.empty()) man.metadata["voice_enroll"] = absolute(config.voice_enroll);

  if (record_dir) {
    // The recording holds copies of every referenced file, under relative names.
    SessionManifest rec = man;
    std::error_code ec;
    fs::create_directories(*record_dir, ec);
    if (ec)
      return make_error(ErrorCode::kIoError, "cannot create {}: {}", record_dir->string(),
                        ec.message());
    for (auto& s : rec.streams) {
      if (s.calibration.empty()) continue;
      const std::string rel = "calib/" + s.id + ".yaml";
      if (auto st = copy_into(s.calibration, *record_dir / rel); !st)
        return tl::unexpected(st.error());
      s.calibration = rel;
    }
    if (auto g = rec.metadata.find("speech_grammar"); g != rec.metadata.end()) {
      if (auto st = copy_into(g->second, *record_dir / "speech.gram"); !st)
        return tl::unexpected(st.error());
      g->second = "speech.gram";
    }
    if (auto v = rec.metadata.find("voice_enroll"); v != rec.metadata.end()) {
      if (auto st = copy_into(v->second, *record_dir / "enroll"); !st)
        return tl::unexpected(st.error());
      v->second = "enroll";
    }
    auto w = SessionWriter::create(*record_dir, rec, writer_options);
    if (!w) return tl::unexpected(w.error());
    m->writer = std::move(*w);
  }

  for (const auto& s : man.streams) m->stats.streams[s.id] = {};
  Impl* raw = m.get();
  m->running = static_cast<int>(m->cameras.size() + m->skeletons.size() + m->depth_sensors.size() +
                                m->audio.size());
  for (size_t i = 0; i < m->cameras.size(); ++i)
    m->pumps.emplace_back([raw, i] { raw->pump(*raw->cameras[i]); });
  for (size_t i = 0; i < m->skeletons.size(); ++i)
    m->pumps.emplace_back([raw, i] { raw->pump(*raw->skeletons[i]); });
  for (size_t i = 0; i < m->depth_sensors.size(); ++i)
    m->pumps.emplace_back([raw, i] { raw->pump(*raw->depth_sensors[i]); });
  for (size_t i = 0; i < m->audio.size(); ++i)
    m->pumps.emplace_back([raw, i] { raw->pump(*raw->audio[i]); });
  return std::unique_ptr<LiveCapture>(new LiveCapture(std::move(m)));
}

Result<FramePtr> LiveCapture::next() { return impl_->queue.pop("live capture stopped"); }

SourceInfo LiveCapture::info() const {
  SourceInfo i;
  i.live = true;
  for (const auto& s : impl_->manifest.streams) {
    SensorDescription d;
    d.id = s.id;
    d.kind = s.kind;
    d.rate_hz = s.rate_hz;
    d.width = s.width;
    d.height = s.height;
    d.sample_rate = s.sample_rate;
    d.channels = s.channels;
    d.calibration = s.calibration;
    d.frame = s.id;
    i.sensors.push_back(d);
  }
  return i;
}

const SessionManifest& LiveCapture::manifest() const { return impl_->manifest; }
std::map<SensorId, int> LiveCapture::skeleton_ports() const {
  std::map<SensorId, int> ports;
  for (const auto& k : impl_->skeletons) ports[k->info().sensors.front().id] = k->port();
  return ports;
}
std::chrono::steady_clock::time_point LiveCapture::clock_origin() const { return impl_->origin; }
void LiveCapture::stop() { impl_->stop_all(); }

bool LiveCapture::failed() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->failure.has_value();
}

int LiveCapture::devices_running() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->running;
}

Result<RecordStats> LiveCapture::finish() {
  Impl& m = *impl_;
  if (m.finished) return make_error(ErrorCode::kInvalidArgument, "live capture already finished");
  m.finished = true;
  m.stop_all();
  for (auto& t : m.pumps)
    if (t.joinable()) t.join();
  m.stats.duration_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - m.origin).count();
  for (size_t i = 0; i < m.cameras.size(); ++i)
    m.stats.streams[m.manifest.streams[i].id].frames_dropped +=
        m.cameras[i]->stats().dropped_frames;
  for (const auto& a : m.audio) {
    auto& s = m.stats.streams[a->info().sensors.front().id];
    s.frames_dropped += a->stats().dropped_chunks;
    s.overruns = a->stats().overruns;
  }
  for (const auto& [id, s] : m.stats.streams)
    if (s.frames_dropped > 0 || s.overruns > 0)
      log::warn("live capture: stream '{}' dropped {} frames/chunks, {} audio overruns", id,
                s.frames_dropped, s.overruns);
  if (m.writer) {
    // Before close(): a session marked complete has its report. Written as a partial file and
    // renamed, so a kill mid-write leaves no torn report. Not writing it costs the report, not
    // the recording.
    OutputFile report;
    Status written = report.open(m.writer->dir() / kCaptureReportFile);
    if (written) written = report.write(capture_report(m.stats).dump(2) + "\n");
    if (written) written = report.commit();
    if (!written) log::warn("capture report not written: {}", written.error().message);
    if (auto st = m.writer->close(); !st) return tl::unexpected(st.error());
  }
  if (m.failure)
    return make_error(m.failure->code, "{} (the recording was closed with what was captured)",
                      m.failure->message);
  return m.stats;
}

nlohmann::json capture_report(const RecordStats& stats) {
  nlohmann::json streams = nlohmann::json::object();
  for (const auto& [id, st] : stats.streams)
    streams[id] = {{"frames_captured", st.frames_written},
                   {"frames_dropped", st.frames_dropped},
                   {"overruns", st.overruns},
                   {"lost", st.lost.empty() ? nlohmann::json() : nlohmann::json(st.lost)}};
  return {{"duration_s", stats.duration_s}, {"streams", streams}};
}

Result<std::optional<nlohmann::json>> read_capture_report(const fs::path& session_dir) {
  const fs::path file = session_dir / kCaptureReportFile;
  std::error_code ec;
  if (!fs::exists(file, ec)) return std::optional<nlohmann::json>();
  std::ifstream in(file);
  nlohmann::json report = nlohmann::json::parse(in, nullptr, /*allow_exceptions=*/false);
  if (report.is_discarded() || !report.is_object() || !report.contains("streams") ||
      !report["streams"].is_object())
    return make_error(ErrorCode::kCorruptData,
                      "{}: not a capture report (a JSON object with \"streams\")", file.string());
  return std::optional<nlohmann::json>(std::move(report));
}

Status lost_devices(const RecordStats& stats) {
  std::vector<std::string> lost;
  for (const auto& [id, s] : stats.streams)
    if (!s.lost.empty()) lost.push_back(fmt::format("{}: {}", id, s.lost));
  if (lost.empty()) return ok_status();
  return make_error(ErrorCode::kIoError,
                    "a device failed during the session ({}); the other devices went on and "
                    "everything captured was kept",
                    fmt::join(lost, "; "));
}

Result<RecordStats> record_session(const RecordConfig& config, const fs::path& out_dir,
                                   const RecordOptions& options) {
  auto capture = LiveCapture::open(config, out_dir, options.writer);
  if (!capture) return tl::unexpected(capture.error());
  // Frames are written by the capture's own threads; here they are only taken off the queue.
  std::thread drain([&] {
    while ((*capture)->next()) {
    }
  });
  const auto origin = (*capture)->clock_origin();
  auto last_progress = std::chrono::steady_clock::now();
  while (true) {
    const auto now = std::chrono::steady_clock::now();
    const double elapsed = std::chrono::duration<double>(now - origin).count();
    if (options.duration_s && elapsed >= *options.duration_s) break;
    if (options.stop && options.stop->load()) break;
    // A failed recording, or nothing left to record (every device ended or was lost).
    if ((*capture)->failed() || (*capture)->devices_running() == 0) break;
    if (options.progress && now - last_progress >= std::chrono::seconds(1)) {
      options.progress(elapsed);
      last_progress = now;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  (*capture)->stop();
  drain.join();
  return (*capture)->finish();
}

}  // namespace dreamsense::sources
