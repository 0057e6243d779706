// check_session / repair_session: `dreamsense check SESSION [--repair OUT]`.
// Every record goes through SessionReader (one parser, one damage policy); this file adds the
// per-stream table, the calibration files, the audio length and the byte-for-byte repaired copy.

#include "dreamsense/sources/session_check.hpp"

#include "dreamsense/audio/mic_array.hpp"
#include "dreamsense/core/camera_model.hpp"
#include "dreamsense/core/log.hpp"
#include "dreamsense/core/output_file.hpp"
#include "dreamsense/sources/markers.hpp"
#include "dreamsense/sources/recorder.hpp"

#include <fmt/format.h>
#include <sndfile.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>
#include <set>
#include <sstream>

namespace dreamsense::sources {
namespace {

namespace fs = std::filesystem;

constexpr size_t kListedGaps = 20;

bool indexed(const std::string& encoding) {
  return encoding == "mjpeg" || encoding == "raw16" || encoding == "png16";
}

std::string seconds(int64_t ns) { return fmt::format("{:.3f}", static_cast<double>(ns) * 1e-9); }

// The readers opened here warn about what this check reports anyway (an incomplete session, once
// per stream): quiet while they open, unless debugging.
class QuietLog {
 public:
  QuietLog() : saved_(log::logger().level()) {
    if (saved_ > spdlog::level::debug) log::logger().set_level(spdlog::level::err);
  }
  ~QuietLog() { log::logger().set_level(saved_); }
  QuietLog(const QuietLog&) = delete;
  QuietLog& operator=(const QuietLog&) = delete;

 private:
  spdlog::level::level_enum saved_;
};

SessionReaderOptions reader_options(const SessionCheckOptions& o) {
  SessionReaderOptions ro;
  ro.allow_incomplete = true;
  ro.allow_damaged = true;
  ro.log_damage = false;
  ro.listed_damage = std::numeric_limits<size_t>::max();
  ro.require_calibration_files = false;
  ro.decode_threads = o.decode_threads;
  ro.follow_links_outside = o.follow_links_outside;
  return ro;
}

std::optional<std::string> check_calibration(const fs::path& dir, const StreamEntry& s) {
  std::error_code ec;
  if (!fs::exists(dir / s.calibration, ec))
    return fmt::format("{}: missing (declared in {})", s.calibration, kManifestName);
  if (s.kind == SensorKind::kAudio) {
    auto g = audio::read_mic_array(dir / s.calibration);
    if (!g) return g.error().message;
    if (auto st = g->check(); !st) return fmt::format("{}: {}", s.calibration, st.error().message);
    if (static_cast<int>(g->mics_m.size()) != s.channels)
      return fmt::format("{}: {} microphones, the stream has {} channels", s.calibration,
                         g->mics_m.size(), s.channels);
    return std::nullopt;
  }
  auto m = read_camera_model(dir / s.calibration);
  if (!m) return m.error().message;
  return std::nullopt;
}

int64_t median(std::vector<int64_t> v) {
  if (v.empty()) return 0;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

// Reads every record of one stream alone.
void read_stream(const fs::path& dir, const StreamEntry& s, const SessionCheckOptions& options,
                 StreamCheck& c, std::vector<RecordLocation>& records, int64_t& audio_samples) {
  SessionReaderOptions ro = reader_options(options);
  ro.only = {s.id};
  QuietLog quiet;  // what the reader would warn about is in the check's result
  auto opened = SessionReader::open(dir, ro);
  if (!opened) {
    c.error = opened.error().message;
    return;
  }
  std::unique_ptr<SessionReader> reader = std::move(*opened);
  records = reader->records(s.id);
  for (;;) {
    auto f = reader->next();
    if (!f) {
      if (f.error().code == ErrorCode::kEndOfStream) break;
      c.problems.push_back(f.error().message);  // not damage (e.g. an unsupported image type)
      continue;
    }
    const int64_t stamp = (*f)->stamp.ns();
    if (!c.first_ns) c.first_ns = stamp;
    c.last_ns = stamp;
    c.delivered++;
    if (const auto* a = (*f)->as<AudioChunk>(); a != nullptr && a->channels > 0)
      audio_samples += static_cast<int64_t>(a->samples.size()) / a->channels;
    else
      c.delivered_stamps.push_back(stamp);
  }
  c.damage = reader->damage().at(0);
}

// What the recorder's capture.json says of each stream (recorder.hpp, capture_report): a device
// lost during the recording, frames dropped on the way to the disk, audio overruns. Notes, not
// damage: the records on disk are intact. An unreadable report is a session problem, as a bad
// markers.jsonl is.
void add_capture_notes(const fs::path& dir, SessionCheck& out) {
  auto read = read_capture_report(dir);
  if (!read) {
    out.session_problems.push_back(read.error().message);
    return;
  }
  if (!*read) return;
  const nlohmann::json& streams = (**read).at("streams");
  for (StreamCheck& c : out.streams) {
    const auto it = streams.find(c.stream);
    if (it == streams.end() || !it->is_object()) continue;
    const auto count = [&](const char* key) -> uint64_t {
      const auto v = it->find(key);
      return v != it->end() && v->is_number_unsigned() ? v->get<uint64_t>() : 0;
    };
    if (const auto lost = it->find("lost"); lost != it->end() && lost->is_string())
      c.notes.push_back(fmt::format("{}: the device was lost during the recording: {}",
                                    kCaptureReportFile, lost->get<std::string>()));
    if (const uint64_t n = count("frames_dropped"); n > 0)
      c.notes.push_back(
          fmt::format("{}: {} frames/chunks dropped while recording (the disk or "
                      "the analysis fell behind)",
                      kCaptureReportFile, n));
    if (const uint64_t n = count("overruns"); n > 0)
      c.notes.push_back(fmt::format("{}: {} audio overruns in the device", kCaptureReportFile, n));
  }
}

}  // namespace

Status SessionCheckOptions::check() const {
  std::vector<std::string> bad;
  if (!(gap_factor > 1)) bad.push_back(fmt::format("gap_factor must be > 1, got {}", gap_factor));
  if (audio_tolerance.ns() < 0)
    bad.push_back(fmt::format("audio_tolerance must be >= 0, got {} s", audio_tolerance.seconds()));
  if (decode_threads < 0 || decode_threads > 16)
    bad.push_back(fmt::format("decode_threads must be in [0, 16], got {}", decode_threads));
  if (bad.empty()) return ok_status();
  std::string msg = "SessionCheckOptions: ";
  for (size_t i = 0; i < bad.size(); ++i) msg += (i ? "; " : "") + bad[i];
  return make_error(ErrorCode::kInvalidArgument, std::move(msg));
}

bool SessionCheck::sound() const {
  if (!manifest_ok || !session_problems.empty()) return false;
  return std::all_of(streams.begin(), streams.end(),
                     [](const StreamCheck& s) { return s.sound(); });
}

namespace {

// What check_session keeps for the repair, beside the public result.
struct StreamInternals {
  std::vector<RecordLocation> records;
  int64_t audio_samples = 0;
};

Result<SessionCheck> check_session_impl(const fs::path& dir, const SessionCheckOptions& options,
                                        std::vector<StreamInternals>* internals) {
  if (auto st = options.check(); !st) return tl::unexpected(st.error());
  SessionCheck out;
  out.dir = dir;
  SessionManifest m;
  {
    auto r = read_manifest(dir);
    if (!r) {
      out.session_problems.push_back(r.error().message);
      return out;
    }
    m = std::move(*r);
  }
  out.manifest_ok = true;
  out.complete = m.complete;
  if (!m.complete)
    out.session_problems.push_back(fmt::format(
        "{}: complete: false (the recorder was not closed, e.g. it crashed)", kManifestName));
  if (auto roles = stream_roles(m); !roles) out.session_problems.push_back(roles.error().message);
  if (auto markers = read_markers(dir); markers)
    out.markers = markers->size();
  else
    out.session_problems.push_back(markers.error().message);

  std::vector<SensorId> readable;
  std::vector<StreamInternals> local(m.streams.size());
  for (size_t i = 0; i < m.streams.size(); ++i) {
    const StreamEntry& s = m.streams[i];
    StreamCheck c;
    c.stream = s.id;
    c.kind = to_string(s.kind);
    c.encoding = s.encoding;
    c.file = s.file;
    c.index = s.index;
    c.calibration = s.calibration;
    c.damage.stream = s.id;
    c.damage.file = s.file;
    if (!s.calibration.empty()) c.calibration_error = check_calibration(dir, s);
    read_stream(dir, s, options, c, local[i].records, local[i].audio_samples);
    if (c.error) {
      c.problems.insert(c.problems.begin(), *c.error);
    } else {
      readable.push_back(s.id);
      std::vector<int64_t> steps;
      for (size_t k = 1; k < c.delivered_stamps.size(); ++k)
        steps.push_back(c.delivered_stamps[k] - c.delivered_stamps[k - 1]);
      c.median_step_ns = median(steps);
      for (size_t k = 0; k < steps.size(); ++k) {
        if (static_cast<double>(steps[k]) <= options.gap_factor * c.median_step_ns) continue;
        c.gap_count++;
        c.gap_total_ns += steps[k];
        if (c.gaps.size() < kListedGaps) c.gaps.push_back({c.delivered_stamps[k], steps[k]});
      }
      if (s.kind == SensorKind::kAudio && s.sample_rate > 0)
        c.audio_seconds = static_cast<double>(local[i].audio_samples) / s.sample_rate;
      const StreamDamage& d = c.damage;
      if (d.damaged > 0) {
        std::string where;
        if (!d.first.empty()) where = fmt::format("; first: {}", d.first.front().what);
        c.problems.push_back(
            fmt::format("{}: {} damaged record(s) of {}{}", s.file, d.damaged, d.records, where));
      }
      if (d.torn_tail > 0)
        c.problems.push_back(
            fmt::format("{}: {} record(s) torn at the end (partly written)", s.file, d.torn_tail));
      if (d.records == 0 && d.torn_tail == 0)  // records counts the damaged ones too
        c.notes.push_back(fmt::format("{}: no records (nothing was recorded; not damage)", s.file));
    }
    if (c.calibration_error) c.problems.push_back(*c.calibration_error);
    out.streams.push_back(std::move(c));
  }

  add_capture_notes(dir, out);

  // Across streams: one clock (SessionReader::open checks it when it opens them together).
  if (readable.size() >= 2) {
    SessionReaderOptions ro = reader_options(options);
    ro.only = readable;
    ro.decode_threads = 0;
    QuietLog quiet;
    if (auto r = SessionReader::open(dir, ro); !r)
      out.session_problems.push_back(r.error().message);
  }

  // The audio against the session clock: it should cover what the other streams cover.
  std::optional<int64_t> start, end;
  for (size_t i = 0; i < m.streams.size(); ++i) {
    const StreamCheck& c = out.streams[i];
    if (m.streams[i].kind == SensorKind::kAudio || !c.first_ns) continue;
    start = start ? std::min(*start, *c.first_ns) : *c.first_ns;
    const int64_t e = *c.last_ns + c.median_step_ns;
    end = end ? std::max(*end, e) : e;
  }
  for (size_t i = 0; i < m.streams.size(); ++i) {
    const StreamEntry& s = m.streams[i];
    StreamCheck& c = out.streams[i];
    if (s.kind != SensorKind::kAudio || !c.audio_seconds || !start) continue;
    const int64_t a_start = s.start_ns;
    const int64_t a_end = s.start_ns + static_cast<int64_t>(*c.audio_seconds * 1e9);
    c.audio_missing_start_ns = std::max<int64_t>(0, a_start - *start);
    c.audio_missing_end_ns = std::max<int64_t>(0, *end - a_end);
    const int64_t tol = options.audio_tolerance.ns();
    if (c.audio_missing_start_ns > tol || c.audio_missing_end_ns > tol)
      c.problems.push_back(fmt::format(
          "{}: {:.2f} s of audio for {:.2f} s of session: it starts {:.2f} s after and ends "
          "{:.2f} s before the other streams (more than {:.2f} s missing)",
          s.file, *c.audio_seconds, static_cast<double>(*end - *start) * 1e-9,
          static_cast<double>(c.audio_missing_start_ns) * 1e-9,
          static_cast<double>(c.audio_missing_end_ns) * 1e-9, options.audio_tolerance.seconds()));
  }
  if (internals != nullptr) *internals = std::move(local);
  return out;
}

}  // namespace

Result<SessionCheck> check_session(const fs::path& session_dir,
                                   const SessionCheckOptions& options) {
  return check_session_impl(session_dir, options, nullptr);
}

nlohmann::json SessionCheck::to_json() const {
  using nlohmann::json;
  json streams_json = json::array();
  for (const StreamCheck& c : streams) {
    json s = {{"stream", c.stream},
              {"kind", c.kind},
              {"encoding", c.encoding},
              {"file", c.file},
              {"sound", c.sound()}};
    if (!c.index.empty()) s["index"] = c.index;
    if (c.error) s["error"] = *c.error;
    s["records"] = c.damage.records;
    s["delivered"] = c.delivered;
    s["damaged"] = c.damage.damaged;
    s["torn_tail"] = c.damage.torn_tail;
    s["empty_lines"] = c.damage.empty_lines;
    s["first_ns"] = c.first_ns ? json(*c.first_ns) : json(nullptr);
    s["last_ns"] = c.last_ns ? json(*c.last_ns) : json(nullptr);
    s["median_step_ns"] = c.median_step_ns;
    json gaps = json::array();
    for (const StampGap& g : c.gaps)
      gaps.push_back({{"after_ns", g.after_ns}, {"length_ns", g.length_ns}});
    s["gaps"] = {{"count", c.gap_count}, {"total_ns", c.gap_total_ns}, {"first", gaps}};
    json damaged = json::array();
    for (const DamagedRecord& d : c.damage.first)
      damaged.push_back({{"record", d.record},
                         {"stamp_ns", d.stamp_ns ? json(*d.stamp_ns) : json(nullptr)},
                         {"what", d.what}});
    s["damaged_records"] = damaged;
    if (!c.calibration.empty())
      s["calibration"] = {
          {"file", c.calibration},
          {"error", c.calibration_error ? json(*c.calibration_error) : json(nullptr)}};
    if (c.audio_seconds)
      s["audio"] = {{"seconds", *c.audio_seconds},
                    {"missing_start_ns", c.audio_missing_start_ns},
                    {"missing_end_ns", c.audio_missing_end_ns}};
    s["problems"] = c.problems;
    s["notes"] = c.notes;
    streams_json.push_back(std::move(s));
  }
  return {{"session", dir.string()},      {"sound", sound()},   {"complete", complete},
          {"problems", session_problems}, {"markers", markers}, {"streams", streams_json}};
}

std::string SessionCheck::table(size_t listed) const {
  std::string out;
  size_t w = 6;
  for (const StreamCheck& c : streams) w = std::max(w, c.stream.size());
  out += fmt::format("{:<{}}  {:<8} {:<8} {:>8} {:>8} {:>5} {:>5} {:>17}  {:<11} {}\n", "stream", w,
                     "kind", "encoding", "records", "damaged", "torn", "gaps", "span (s)",
                     "calibration", "status");
  for (const StreamCheck& c : streams) {
    const std::string span =
        c.first_ns ? fmt::format("{}-{}", seconds(*c.first_ns), seconds(*c.last_ns)) : "-";
    const std::string calib = c.calibration.empty() ? "-" : c.calibration_error ? "BAD" : "ok";
    const std::string status = c.error                 ? "UNREADABLE"
                               : !c.sound()            ? "DAMAGED"
                               : c.damage.records == 0 ? "empty"
                                                       : "ok";
    out += fmt::format("{:<{}}  {:<8} {:<8} {:>8} {:>8} {:>5} {:>5} {:>17}  {:<11} {}\n", c.stream,
                       w, c.kind, c.encoding, c.damage.records, c.damage.damaged,
                       c.damage.torn_tail, c.gap_count, span, calib, status);
  }
  if (markers > 0) out += fmt::format("markers: {} (markers.jsonl)\n", markers);
  for (const std::string& p : session_problems) out += fmt::format("session: {}\n", p);
  for (const StreamCheck& c : streams) {
    for (const std::string& p : c.problems) out += fmt::format("{}: {}\n", c.stream, p);
    for (const std::string& n : c.notes) out += fmt::format("{}: note: {}\n", c.stream, n);
    for (size_t i = 0; i < c.damage.first.size() && i < listed; ++i) {
      const DamagedRecord& d = c.damage.first[i];
      out += fmt::format("{}:   record {}{}: {}\n", c.stream, d.record,
                         d.stamp_ns ? fmt::format(" at {} s", seconds(*d.stamp_ns)) : "", d.what);
    }
    if (c.damage.first.size() > listed)
      out += fmt::format("{}:   ... and {} more damaged record(s) (--json lists them all)\n",
                         c.stream, c.damage.first.size() - listed);
    for (size_t i = 0; i < c.gaps.size() && i < listed; ++i)
      out += fmt::format("{}:   gap of {} s after {} s\n", c.stream, seconds(c.gaps[i].length_ns),
                         seconds(c.gaps[i].after_ns));
  }
  out += sound() ? "session is sound\n" : "session has damage or errors\n";
  return out;
}

// ---------------------------------------------------------------------------------------------
// Repair

namespace {

Result<std::string> read_all(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  if (!in)
    return make_error(ErrorCode::kIoError, "{}: cannot read: {}", p.string(), std::strerror(errno));
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

Status write_all(const fs::path& p, const std::string& data) {
  std::ofstream out(p, std::ios::binary | std::ios::trunc);
  out.write(data.data(), static_cast<std::streamsize>(data.size()));
  out.close();
  if (!out) return make_error(ErrorCode::kIoError, "{}: cannot write", p.string());
  return ok_status();
}

uint32_t be32(const std::string& d, size_t i) {
  return static_cast<uint32_t>(static_cast<unsigned char>(d[i])) << 24 |
         static_cast<uint32_t>(static_cast<unsigned char>(d[i + 1])) << 16 |
         static_cast<uint32_t>(static_cast<unsigned char>(d[i + 2])) << 8 |
         static_cast<uint32_t>(static_cast<unsigned char>(d[i + 3]));
}

// The end of the complete JPEG starting at `p` (SOI .. EOI, walking its marker segments and
// entropy-coded data), or nullopt when it is not one or runs past the end of `d`.
std::optional<size_t> jpeg_end(const std::string& d, size_t p) {
  const auto at = [&](size_t i) { return static_cast<unsigned char>(d[i]); };
  if (p + 4 > d.size() || at(p) != 0xFF || at(p + 1) != 0xD8) return std::nullopt;
  size_t i = p + 2;
  while (i + 1 < d.size()) {
    if (at(i) != 0xFF) return std::nullopt;
    while (i + 1 < d.size() && at(i + 1) == 0xFF) ++i;  // fill bytes
    if (i + 1 >= d.size()) return std::nullopt;
    const unsigned char marker = at(i + 1);
    if (marker == 0xD9) return i + 2;
    if ((marker >= 0xD0 && marker <= 0xD7) || marker == 0x01) {
      i += 2;
      continue;
    }
    if (i + 4 > d.size()) return std::nullopt;
    const size_t len = static_cast<size_t>(at(i + 2)) << 8 | at(i + 3);
    if (len < 2) return std::nullopt;
    i += 2 + len;
    if (marker != 0xDA) continue;
    // Entropy-coded data: up to the next marker that is not a stuffed 0xFF00 or a restart.
    while (i + 1 < d.size() && !(at(i) == 0xFF && at(i + 1) != 0x00 && at(i + 1) != 0xFF &&
                                 !(at(i + 1) >= 0xD0 && at(i + 1) <= 0xD7)))
      ++i;
  }
  return std::nullopt;
}

// The end of the complete PNG starting at `p` (signature .. IEND chunk).
std::optional<size_t> png_end(const std::string& d, size_t p) {
  static const char kSig[8] = {'\x89', 'P', 'N', 'G', '\r', '\n', '\x1A', '\n'};
  if (p + 8 > d.size() || std::memcmp(d.data() + p, kSig, 8) != 0) return std::nullopt;
  size_t i = p + 8;
  while (i + 12 <= d.size()) {
    const size_t len = be32(d, i);
    const bool iend = d.compare(i + 4, 4, "IEND") == 0;
    if (len > d.size() - i - 12) return std::nullopt;
    i += 12 + len;
    if (iend) return i;
  }
  return std::nullopt;
}

// A frame found in the data after the last indexed one (an index cut short).
struct FoundFrame {
  uint64_t offset = 0, size = 0;
  bool complete = true;  // false: it starts like a frame but breaks before the next one
};

// Walks the data after the last indexed frame: one slot per frame start (JPEG SOI, PNG signature,
// raw16 frame size). A frame that breaks is skipped up to the next frame start (so the frames
// after it keep their places); a broken frame at the very end is a torn tail, not a slot.
std::vector<FoundFrame> find_frames(const std::string& tail, const StreamEntry& s) {
  std::vector<FoundFrame> out;
  size_t p = 0;
  const size_t raw = static_cast<size_t>(s.width) * static_cast<size_t>(s.height) * 2;
  static const std::string kJpegStart("\xFF\xD8\xFF", 3);
  static const std::string kPngStart("\x89PNG\r\n\x1A\n", 8);
  const std::string& start = s.encoding == "mjpeg" ? kJpegStart : kPngStart;
  while (p < tail.size()) {
    if (s.encoding == "raw16") {
      if (raw == 0 || tail.size() - p < raw) break;
      out.push_back({p, raw, true});
      p += raw;
      continue;
    }
    if (tail.compare(p, start.size(), start) != 0) break;  // not a frame start: stop
    const std::optional<size_t> end = s.encoding == "mjpeg" ? jpeg_end(tail, p) : png_end(tail, p);
    if (end) {
      out.push_back({p, *end - p, true});
      p = *end;
      continue;
    }
    const size_t next = tail.find(start, p + start.size());
    if (next == std::string::npos) break;  // torn at the end
    out.push_back({p, next - p, false});
    p = next;
  }
  return out;
}

struct IndexedRecord {
  uint64_t sequence = 0;
  int64_t stamp_ns = 0;
  uint64_t offset = 0, size = 0;
};

// Writes `file` and `index` in `out_root` from the records of `src_data`.
Status write_indexed(const fs::path& src_data, const fs::path& out_root, const StreamEntry& s,
                     const std::vector<IndexedRecord>& records) {
  std::ifstream in(src_data, std::ios::binary);
  if (!in) return make_error(ErrorCode::kIoError, "{}: cannot read", src_data.string());
  std::ofstream data(out_root / s.file, std::ios::binary | std::ios::trunc);
  std::string index = fmt::format("# dreamsense {} index v1\n", s.encoding);
  std::string buffer;
  uint64_t offset = 0;
  for (const IndexedRecord& r : records) {
    buffer.resize(r.size);
    in.seekg(static_cast<std::streamoff>(r.offset));
    if (!in.read(buffer.data(), static_cast<std::streamsize>(r.size)))
      return make_error(ErrorCode::kIoError, "{}: cannot read {} bytes at {}", src_data.string(),
                        r.size, r.offset);
    data.write(buffer.data(), static_cast<std::streamsize>(r.size));
    index += fmt::format("{},{},{},{}\n", r.sequence, r.stamp_ns, offset, r.size);
    offset += r.size;
  }
  data.close();
  if (!data)
    return make_error(ErrorCode::kIoError, "{}: cannot write", (out_root / s.file).string());
  return write_all(out_root / s.index, index);
}

// A WAV holding exactly the samples the source holds (the header of a torn one declares more).
Status rewrite_wav(const fs::path& src, const fs::path& dst) {
  SF_INFO info{};
  SNDFILE* in = sf_open(src.c_str(), SFM_READ, &info);
  if (in == nullptr)
    return make_error(ErrorCode::kCorruptData, "{}: unreadable: {}", src.string(),
                      sf_strerror(nullptr));
  SF_INFO out_info{};
  out_info.samplerate = info.samplerate;
  out_info.channels = info.channels;
  out_info.format = info.format;
  SNDFILE* out = sf_open(dst.c_str(), SFM_WRITE, &out_info);
  if (out == nullptr) {
    sf_close(in);
    return make_error(ErrorCode::kIoError, "{}: cannot write: {}", dst.string(),
                      sf_strerror(nullptr));
  }
  // Integer samples pass through unscaled (doubles hold 32-bit integers exactly).
  sf_command(in, SFC_SET_NORM_DOUBLE, nullptr, SF_FALSE);
  sf_command(out, SFC_SET_NORM_DOUBLE, nullptr, SF_FALSE);
  std::vector<double> block(static_cast<size_t>(4096 * info.channels));
  Status st = ok_status();
  for (;;) {
    const sf_count_t got = sf_readf_double(in, block.data(), 4096);
    if (got <= 0) break;
    if (sf_writef_double(out, block.data(), got) != got) {
      st = make_error(ErrorCode::kIoError, "{}: write failed: {}", dst.string(), sf_strerror(out));
      break;
    }
  }
  sf_close(in);
  if (sf_close(out) != 0 && st)
    st = make_error(ErrorCode::kIoError, "{}: cannot close", dst.string());
  return st;
}

// Copies every file of the session that is not a stream file or session.yaml (calibration,
// truth, grammar, enrolment recordings, ...). Links are followed only to files inside it.
Status copy_other_files(const fs::path& src, const fs::path& dst, const std::set<fs::path>& skip,
                        std::vector<std::string>& notes) {
  std::error_code ec;
  const fs::path root = fs::canonical(src, ec);
  for (auto it = fs::recursive_directory_iterator(src, ec); !ec && it != fs::end(it);
       it.increment(ec)) {
    const fs::path rel = it->path().lexically_relative(src);
    if (rel.empty() || *rel.begin() == StagedOutputDir::kStageName) {
      if (it->is_directory()) it.disable_recursion_pending();
      continue;
    }
    if (skip.count(rel) != 0) continue;
    if (it->is_symlink()) {
      const fs::path target = fs::canonical(it->path(), ec);
      const auto m = std::mismatch(root.begin(), root.end(), target.begin(), target.end());
      if (ec || m.first != root.end()) {
        notes.push_back(
            fmt::format("{}: a link out of the session folder, not copied", rel.string()));
        ec.clear();
        if (it->is_directory()) it.disable_recursion_pending();
        continue;
      }
    }
    if (it->is_directory()) {
      fs::create_directories(dst / rel, ec);
    } else if (it->is_regular_file()) {
      fs::create_directories((dst / rel).parent_path(), ec);
      fs::copy_file(it->path(), dst / rel, fs::copy_options::overwrite_existing, ec);
    }
    if (ec)
      return make_error(ErrorCode::kIoError, "{}: cannot copy: {}", rel.string(), ec.message());
  }
  if (ec) return make_error(ErrorCode::kIoError, "{}: cannot list: {}", src.string(), ec.message());
  return ok_status();
}

// Writes stream `s` of the copy from `src_dir` (the original, or the copy itself on the second
// pass) and fills `r`.
Status write_stream(const fs::path& src_dir, const fs::path& out_root, const StreamEntry& s,
                    const StreamCheck& c, const StreamInternals& in, bool session_complete,
                    StreamRepair& r) {
  if (indexed(s.encoding)) {
    const std::set<int64_t> delivered(c.delivered_stamps.begin(), c.delivered_stamps.end());
    std::vector<IndexedRecord> out;
    for (const RecordLocation& l : in.records)
      if (delivered.count(l.stamp_ns) != 0)
        out.push_back({l.sequence, l.stamp_ns, l.offset, l.size});
    r.kept = out.size();
    r.dropped = c.damage.damaged;
    r.torn_cut = c.damage.torn_tail;
    // An index cut short: index the complete frames after the last indexed one again, with
    // stamps continued at the stream's median step.
    std::error_code ec;
    const uint64_t data_size = fs::file_size(src_dir / s.file, ec);
    const uint64_t covered =
        in.records.empty() ? 0 : in.records.back().offset + in.records.back().size;
    if (!ec && !in.records.empty() && data_size > covered) {
      // In a session marked complete the reader counted these frames as damaged, estimated from
      // the mean frame size (SessionReader, IndexedReader::open): they are not dropped.
      const uint64_t mean = std::max<uint64_t>(1, covered / in.records.size());
      const uint64_t estimated = session_complete ? (data_size - covered) / mean : 0;
      r.dropped = r.dropped >= estimated ? r.dropped - estimated : 0;
      std::ifstream f(src_dir / s.file, std::ios::binary);
      std::string tail(data_size - covered, '\0');
      f.seekg(static_cast<std::streamoff>(covered));
      if (f.read(tail.data(), static_cast<std::streamsize>(tail.size()))) {
        std::vector<int64_t> steps;
        for (size_t k = 1; k < in.records.size(); ++k)
          steps.push_back(in.records[k].stamp_ns - in.records[k - 1].stamp_ns);
        int64_t step = median(steps);
        if (step <= 0) step = static_cast<int64_t>(1e9 / (s.rate_hz > 0 ? s.rate_hz : 25.0));
        const RecordLocation& last = in.records.back();
        uint64_t k = 0;
        for (const FoundFrame& f : find_frames(tail, s)) {
          ++k;
          if (!f.complete) {
            r.dropped++;
            continue;
          }
          out.push_back({last.sequence + k, last.stamp_ns + static_cast<int64_t>(k) * step,
                         covered + f.offset, f.size});
          r.recovered++;
        }
      }
    }
    return write_indexed(src_dir / s.file, out_root, s, out);
  }
  std::error_code ec;
  fs::create_directories((out_root / s.file).parent_path(), ec);
  if (s.encoding == "jsonl") {
    auto text = read_all(src_dir / s.file);
    if (!text) return tl::unexpected(text.error());
    std::string out;
    out.reserve(text->size());
    for (const RecordLocation& l : in.records) {
      out.append(*text, l.offset, l.size);
      out += '\n';
    }
    r.kept = in.records.size();
    r.dropped = c.damage.damaged;
    r.torn_cut = c.damage.torn_tail;
    return write_all(out_root / s.file, out);
  }
  if (s.encoding == "wav") {
    r.kept = c.delivered;
    r.torn_cut = c.damage.torn_tail;
    if (c.damage.torn_tail == 0) {
      fs::copy_file(src_dir / s.file, out_root / s.file, fs::copy_options::overwrite_existing, ec);
      if (ec) return make_error(ErrorCode::kIoError, "{}: cannot copy: {}", s.file, ec.message());
      return ok_status();
    }
    return rewrite_wav(src_dir / s.file, out_root / s.file);
  }
  // "video" (read-only, e.g. imported): copied as it is.
  r.kept = c.delivered;
  for (const std::string& f : {s.file, s.index}) {
    if (f.empty()) continue;
    fs::create_directories((out_root / f).parent_path(), ec);
    fs::copy_file(src_dir / f, out_root / f, fs::copy_options::overwrite_existing, ec);
    if (ec) return make_error(ErrorCode::kIoError, "{}: cannot copy: {}", f, ec.message());
  }
  return ok_status();
}

}  // namespace

nlohmann::json SessionRepair::to_json() const {
  nlohmann::json streams_json = nlohmann::json::array();
  for (const StreamRepair& r : streams)
    streams_json.push_back({{"stream", r.stream},
                            {"kept", r.kept},
                            {"dropped", r.dropped},
                            {"torn_cut", r.torn_cut},
                            {"recovered", r.recovered},
                            {"removed", r.removed},
                            {"calibration_removed", r.calibration_removed}});
  return {{"complete", complete},
          {"sound", after.sound()},
          {"notes", notes},
          {"streams", streams_json},
          {"copy", after.to_json()}};
}

Result<SessionRepair> repair_session(const fs::path& session_dir, const fs::path& out_dir,
                                     const SessionRepairOptions& options) {
  std::error_code ec;
  if (fs::exists(out_dir, ec)) {
    if (!fs::is_directory(out_dir, ec))
      return make_error(ErrorCode::kInvalidArgument, "{}: exists and is not a folder",
                        out_dir.string());
    if (fs::equivalent(out_dir, session_dir, ec))
      return make_error(ErrorCode::kInvalidArgument,
                        "{}: is the session itself; the repaired copy goes to a new folder",
                        out_dir.string());
    if (!fs::is_empty(out_dir, ec) && !options.force)
      return make_error(ErrorCode::kInvalidArgument,
                        "{}: exists and is not empty; --force replaces its contents",
                        out_dir.string());
  }
  {
    const fs::path a = fs::weakly_canonical(session_dir, ec), b = fs::weakly_canonical(out_dir, ec);
    const auto m = std::mismatch(a.begin(), a.end(), b.begin(), b.end());
    if (m.first == a.end())
      return make_error(ErrorCode::kInvalidArgument,
                        "{}: is inside the session folder; the repaired copy goes elsewhere",
                        out_dir.string());
  }

  SessionRepair rep;
  std::vector<StreamInternals> internals;
  {
    auto before = check_session_impl(session_dir, options.check, &internals);
    if (!before) return tl::unexpected(before.error());
    rep.before = std::move(*before);
  }
  if (!rep.before.manifest_ok)
    return make_error(ErrorCode::kCorruptData, "cannot repair: {}",
                      rep.before.session_problems.at(0));
  auto manifest = read_manifest(session_dir);
  if (!manifest) return tl::unexpected(manifest.error());
  SessionManifest m = std::move(*manifest);
  for (const std::string& p : rep.before.session_problems)
    if (p.find("complete: false") == std::string::npos)
      return make_error(ErrorCode::kCorruptData, "cannot repair: {}", p);

  std::vector<std::string> existing;
  if (fs::is_directory(out_dir, ec))
    for (const auto& e : fs::directory_iterator(out_dir, ec))
      if (e.path().filename() != StagedOutputDir::kStageName)
        existing.push_back(e.path().filename().string());
  auto staged = StagedOutputDir::create(out_dir);
  if (!staged) return tl::unexpected(staged.error());
  const fs::path root = staged->staged(kManifestName).parent_path();

  bool complete = true;
  std::set<fs::path> stream_files = {kManifestName};
  SessionManifest copy = m;
  copy.streams.clear();
  for (size_t i = 0; i < m.streams.size(); ++i) {
    StreamEntry s = m.streams[i];
    const StreamCheck& c = rep.before.streams[i];
    stream_files.insert(fs::path(s.file).lexically_normal());
    if (!s.index.empty()) stream_files.insert(fs::path(s.index).lexically_normal());
    StreamRepair r;
    r.stream = s.id;
    if (c.error) {
      r.removed = true;
      complete = false;
      rep.notes.push_back(fmt::format("stream {} left out: {}", s.id, *c.error));
      rep.streams.push_back(r);
      continue;
    }
    if (c.calibration_error) {
      r.calibration_removed = true;
      complete = false;
      rep.notes.push_back(
          fmt::format("stream {}: calibration left out: {}", s.id, *c.calibration_error));
      s.calibration.clear();
    }
    if (s.encoding == "video" && c.damage.damaged > 0) {
      complete = false;
      rep.notes.push_back(
          fmt::format("stream {}: a video is copied as it is (its {} damaged "
                      "frame(s) stay)",
                      s.id, c.damage.damaged));
    }
    if (c.audio_missing_start_ns > options.check.audio_tolerance.ns() ||
        c.audio_missing_end_ns > options.check.audio_tolerance.ns()) {
      complete = false;
      rep.notes.push_back(fmt::format("stream {}: audio missing at the start or end", s.id));
    }
    if (auto st = write_stream(session_dir, root, s, c, internals[i], m.complete, r); !st)
      return tl::unexpected(st.error());
    rep.streams.push_back(r);
    copy.streams.push_back(s);
  }
  if (auto st = copy_other_files(session_dir, root, stream_files, rep.notes); !st)
    return tl::unexpected(st.error());

  uint64_t dropped = 0, torn = 0, recovered = 0;
  for (const StreamRepair& r : rep.streams) {
    dropped += r.dropped;
    torn += r.torn_cut;
    recovered += r.recovered;
  }
  copy.metadata["repaired"] = fmt::format(
      "dreamsense check --repair: {} damaged record(s) dropped, {} torn-tail record(s) cut, {} "
      "frame(s) indexed again",
      dropped, torn, recovered);
  copy.complete = true;  // so that checking the copy judges its records, not the flag
  if (auto st = write_manifest(root, copy); !st) return tl::unexpected(st.error());

  // The copy is checked by the same reader. Frames indexed again that do not decode are dropped
  // in a second pass over the copy itself.
  std::vector<StreamInternals> after_internals;
  for (int pass = 0; pass < 2; ++pass) {
    auto after = check_session_impl(root, options.check, &after_internals);
    if (!after) return tl::unexpected(after.error());
    rep.after = std::move(*after);
    bool redo = false;
    for (size_t i = 0; i < copy.streams.size() && pass == 0; ++i) {
      const StreamCheck& c = rep.after.streams[i];
      if (!indexed(copy.streams[i].encoding) || (c.damage.damaged == 0 && c.damage.torn_tail == 0))
        continue;
      StreamRepair second;
      const fs::path tmp = root / (copy.streams[i].file + ".repair");
      fs::rename(root / copy.streams[i].file, tmp, ec);
      if (ec)
        return make_error(ErrorCode::kIoError, "{}: cannot rename: {}", tmp.string(), ec.message());
      if (auto st = write_indexed(tmp, root, copy.streams[i],
                                  [&] {
                                    std::set<int64_t> ok(c.delivered_stamps.begin(),
                                                         c.delivered_stamps.end());
                                    std::vector<IndexedRecord> v;
                                    for (const RecordLocation& l : after_internals[i].records)
                                      if (ok.count(l.stamp_ns) != 0)
                                        v.push_back({l.sequence, l.stamp_ns, l.offset, l.size});
                                    return v;
                                  }());
          !st)
        return tl::unexpected(st.error());
      fs::remove(tmp, ec);
      for (StreamRepair& r : rep.streams)
        if (r.stream == copy.streams[i].id) {
          const uint64_t lost = c.damage.damaged + c.damage.torn_tail;
          r.recovered = r.recovered >= lost ? r.recovered - lost : 0;
          r.dropped += lost;
        }
      redo = true;
    }
    if (!redo) break;
  }
  rep.complete = complete && rep.after.sound();
  if (!rep.complete) {
    copy.complete = false;
    if (auto st = write_manifest(root, copy); !st) return tl::unexpected(st.error());
    rep.after.complete = false;
    rep.after.session_problems.push_back(fmt::format(
        "{}: complete: false (the repair could not restore everything)", kManifestName));
  }
  if (auto st =
          staged->publish(options.force ? existing : std::vector<std::string>{}, kManifestName);
      !st)
    return tl::unexpected(st.error());
  return rep;
}

}  // namespace dreamsense::sources
