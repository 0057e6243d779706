// SessionReader: validates a session folder up front, then replays its streams merged by stamp.

#include "dreamsense/core/log.hpp"
#include "dreamsense/sources/session.hpp"
#include "dreamsense/sources/skeleton_json.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>
#include <sndfile.h>

#include <algorithm>
#include <bit>
#include <cerrno>
#include <charconv>
#include <condition_variable>
#include <csetjmp>
#include <cstdio>
#include <cstring>
#include <deque>
#include <exception>
#include <fcntl.h>
#include <fstream>
#include <jpeglib.h>
#include <mutex>
#include <optional>
#include <sstream>
#include <string>
#include <string_view>
#include <sys/stat.h>
#include <system_error>
#include <thread>
#include <unistd.h>
#include <vector>

#include "posix_file.hpp"

namespace dreamsense::sources {
namespace {

using detail::errno_text;

// Upper bound of SessionReaderOptions::decode_threads.
constexpr int kMaxDecodeThreads = 16;

// Streams whose first stamps are further apart than this are on different clocks.
constexpr int64_t kMaxFirstStampSpreadNs = 10'000'000'000LL;

// JPEG decoding straight to OpenCV's layout with libjpeg(-turbo): colour frames are decoded into
// BGR (JCS_EXT_BGR) and grey frames into one channel, directly into the cv::Mat rows. The pixels
// are identical to cv::imdecode(IMREAD_UNCHANGED), which with OpenCV 4.6 decodes to RGB through
// the same libjpeg and then swaps the channels in a scalar loop; that swap cost more than the
// decoding itself (1280x960: 12.7 ms -> 7.6 ms per frame). Returns false (`out` unspecified) for
// anything else (not YCbCr or grey, a libjpeg error): the caller then uses cv::imdecode, so
// unusual or broken frames behave exactly as before. Either way the size the frame's header
// declares (`declared`) is compared with the stream's first (kWrongSize): decoders allocate the
// declared size before they read the data, so a damaged header declaring 30000x30000 pixels
// would otherwise cost gigabytes (libFuzzer's out-of-memory in fuzz.session_stream, 2026-12-01).
struct JpegErrorManager {
  jpeg_error_mgr pub;
  std::jmp_buf jump;
};

[[noreturn]] void jpeg_error_exit(j_common_ptr cinfo) {
  std::longjmp(reinterpret_cast<JpegErrorManager*>(cinfo->err)->jump, 1);
}

// Only trivially destructible locals here: a libjpeg error long-jumps back into this frame.
// libjpeg's warnings ("Corrupt JPEG data: ...") go to stderr by default, one per damaged frame;
// here they are only counted (num_warnings) and the frame is reported as damaged.
void jpeg_silent_output(j_common_ptr /*cinfo*/) {}

enum class JpegDecode { kDecoded, kDamaged, kNotHandled, kWrongSize };

JpegDecode decode_jpeg_direct(const std::vector<uchar>& data, cv::Size expected, cv::Mat* out,
                              cv::Size* declared) {
#ifndef JCS_EXTENSIONS  // plain libjpeg (not libjpeg-turbo) has no BGR output: cv::imdecode
  (void)data;
  (void)expected;
  (void)out;
  (void)declared;
  return JpegDecode::kNotHandled;
#else
  if (data.size() < 4 || data[0] != 0xFF || data[1] != 0xD8) return JpegDecode::kDamaged;
  jpeg_decompress_struct cinfo;
  JpegErrorManager err;
  cinfo.err = jpeg_std_error(&err.pub);
  err.pub.error_exit = jpeg_error_exit;
  err.pub.output_message = jpeg_silent_output;
  if (setjmp(err.jump) != 0) {
    jpeg_destroy_decompress(&cinfo);
    return JpegDecode::kDamaged;
  }
  jpeg_create_decompress(&cinfo);
  jpeg_mem_src(&cinfo, data.data(), static_cast<unsigned long>(data.size()));
  if (jpeg_read_header(&cinfo, TRUE) != JPEG_HEADER_OK) {
    jpeg_destroy_decompress(&cinfo);
    return JpegDecode::kNotHandled;
  }
  *declared = {static_cast<int>(cinfo.image_width), static_cast<int>(cinfo.image_height)};
  if (*declared != expected) {
    jpeg_destroy_decompress(&cinfo);
    return JpegDecode::kWrongSize;
  }
  if (!((cinfo.num_components == 3 && cinfo.jpeg_color_space == JCS_YCbCr) ||
        (cinfo.num_components == 1 && cinfo.jpeg_color_space == JCS_GRAYSCALE))) {
    jpeg_destroy_decompress(&cinfo);
    return JpegDecode::kNotHandled;
  }
  const bool colour = cinfo.num_components == 3;
  cinfo.out_color_space = colour ? JCS_EXT_BGR : JCS_GRAYSCALE;
  jpeg_start_decompress(&cinfo);
  out->create(static_cast<int>(cinfo.output_height), static_cast<int>(cinfo.output_width),
              colour ? CV_8UC3 : CV_8UC1);
  while (cinfo.output_scanline < cinfo.output_height) {
    JSAMPROW row = out->ptr(static_cast<int>(cinfo.output_scanline));
    jpeg_read_scanlines(&cinfo, &row, 1);
  }
  jpeg_finish_decompress(&cinfo);
  const bool warned = err.pub.num_warnings > 0;
  jpeg_destroy_decompress(&cinfo);
  return warned ? JpegDecode::kDamaged : JpegDecode::kDecoded;
#endif
}

struct Context {
  std::filesystem::path dir;
  const SessionManifest* manifest = nullptr;
  SessionReaderOptions options;
  // The session was not closed and allow_incomplete is set: tolerate a torn tail.
  bool tolerate_tail = false;
};

tl::unexpected<Error> missing(const std::string& name) {
  return make_error(ErrorCode::kNotFound, "{}: missing (declared in {})", name, kManifestName);
}

Status require_file(const Context& ctx, const std::string& name) {
  std::error_code ec;
  const auto p = ctx.dir / name;
  if (!std::filesystem::exists(p, ec)) return missing(name);
  if (!std::filesystem::is_regular_file(p, ec))
    return make_error(ErrorCode::kCorruptData, "{}: not a regular file", name);
  // A symlink may point anywhere (e.g. /etc/passwd): session files must stay inside the session.
  if (!ctx.options.follow_links_outside) {
    const auto root = std::filesystem::canonical(ctx.dir, ec);
    const auto target = std::filesystem::canonical(p, ec);
    const auto m = std::mismatch(root.begin(), root.end(), target.begin(), target.end());
    if (ec || m.first != root.end())
      return make_error(ErrorCode::kInvalidArgument,
                        "{}: is a link to a file outside the session folder ({}); refused unless "
                        "--follow-links",
                        name, target.string());
  }
  return ok_status();
}

Result<std::string> read_text(const Context& ctx, const std::string& name) {
  if (auto st = require_file(ctx, name); !st) return tl::unexpected(st.error());
  std::ifstream in(ctx.dir / name, std::ios::binary);
  if (!in) return make_error(ErrorCode::kIoError, "{}: cannot read: {}", name, errno_text(errno));
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

struct Line {
  int number = 0;  // 1-based
  std::string_view text;
  bool terminated = true;  // ends with '\n'
};

std::vector<Line> split_lines(std::string_view text) {
  std::vector<Line> lines;
  size_t pos = 0;
  int number = 1;
  while (pos < text.size()) {
    const size_t nl = text.find('\n', pos);
    Line l;
    l.number = number++;
    if (nl == std::string_view::npos) {
      l.text = text.substr(pos);
      l.terminated = false;
      pos = text.size();
    } else {
      l.text = text.substr(pos, nl - pos);
      pos = nl + 1;
    }
    if (!l.text.empty() && l.text.back() == '\r') l.text.remove_suffix(1);
    lines.push_back(l);
  }
  return lines;
}

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  return s;
}

std::optional<int64_t> parse_int(std::string_view s) {
  s = trim(s);
  int64_t v = 0;
  const auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (ec != std::errc() || p != s.data() + s.size() || s.empty()) return std::nullopt;
  return v;
}

std::string shorten(std::string_view s) {
  return s.size() > 60 ? std::string(s.substr(0, 60)) + "..." : std::string(s);
}

int64_t sample_stamp(int64_t start_ns, int64_t sample, int64_t rate) {
  return start_ns + (sample / rate) * 1000000000LL + (sample % rate) * 1000000000LL / rate;
}

// ----------------------------------------------------------------------------------------------

class StreamReader {
 public:
  explicit StreamReader(const StreamEntry& e) : entry_(e) {
    damage_.stream = e.id;
    damage_.file = e.file;
  }
  virtual ~StreamReader() = default;
  virtual Status open(const Context& ctx) = 0;
  // Stamp of the next frame, or nullopt at the end.
  virtual std::optional<int64_t> peek() const = 0;
  // Reads (and decodes) the next frame; advances even when decoding fails.
  virtual Result<FramePtr> read() = 0;
  virtual std::optional<int64_t> first_stamp() const = 0;
  virtual std::optional<int64_t> last_stamp() const = 0;
  // The file named in clock errors.
  virtual const std::string& main_file() const { return entry_.file; }
  const StreamEntry& entry() const { return entry_; }

  const StreamDamage& damage() const { return damage_; }
  // Index of the frame the last read() returned or failed on.
  virtual uint64_t last_read_index() const { return 0; }
  // A record in the middle that is skipped.
  // `reading`: found while reading frames (logged even by a second reader of the session).
  void note_damaged(uint64_t record, std::optional<int64_t> stamp, std::string what,
                    bool reading = false) {
    if ((log_damage_ || reading) && damage_.damaged == 0)
      log::warn("{} (skipped; damaged records are counted in summary.json)", what);
    damage_.damaged++;
    if (damage_.first.size() < listed_) damage_.first.push_back({record, stamp, std::move(what)});
  }
  // A partly written last record (or several, for frame streams), dropped with a warning.
  void note_torn_tail(uint64_t records, const std::string& what) {
    damage_.torn_tail += records;
    if (log_damage_) log::warn("{} (a torn tail: {} record(s) at the end dropped)", what, records);
  }
  void set_log_damage(bool on) { log_damage_ = on; }
  void set_listed_damage(size_t n) { listed_ = n; }
  // The records kept at open() and where they are in the data file (SessionReader::records).
  virtual std::vector<RecordLocation> records() const { return {}; }
  // Decodes records()[k] (SessionReader::decode_record); only indexed streams have records.
  virtual Result<FramePtr> decode_record(size_t k) const {
    return make_error(ErrorCode::kUnsupported, "{}: record {}: not an indexed stream", entry_.file,
                      k);
  }
  // Beyond the policy's threshold: an error, unless allowed. In a session marked complete a torn
  // tail is lost data too (a crash leaves one record at most), so it counts.
  Status check_damage_limit(const SessionReaderOptions& options) const {
    const uint64_t torn = torn_tail_counts_ ? damage_.torn_tail : 0;
    const uint64_t lost = damage_.damaged + torn;
    const uint64_t total = damage_.records + torn;
    if (options.allow_damaged || lost == 0 ||
        static_cast<double>(lost) <= options.max_damaged_fraction * static_cast<double>(total))
      return ok_status();
    const std::string first =
        !damage_.first.empty() ? fmt::format("first at record {}: {}", damage_.first.front().record,
                                             damage_.first.front().what)
                               : fmt::format("{} torn at the end", torn);
    return make_error(ErrorCode::kCorruptData,
                      "{}: {} of {} records damaged ({:.0f} %, more than {:.0f} %): {}; "
                      "--allow-damaged analyses what is left",
                      damage_.file, lost, total,
                      100.0 * static_cast<double>(lost) / static_cast<double>(total),
                      100 * options.max_damaged_fraction, first);
  }
  void set_torn_tail_counts(bool on) { torn_tail_counts_ = on; }

 protected:
  StreamEntry entry_;
  StreamDamage damage_;
  bool log_damage_ = true;
  bool torn_tail_counts_ = false;
  size_t listed_ = StreamDamage::kListed;
};

class ReadAhead;

// The 8-byte signature every PNG starts with.
constexpr unsigned char kPngSignature[8] = {0x89, 0x50, 0x4E, 0x47, 0x0D, 0x0A, 0x1A, 0x0A};

// mjpeg (colour), raw16 and png16 (depth): data file + index "sequence,stamp_ns,offset,size".
class IndexedReader : public StreamReader {
 public:
  using StreamReader::StreamReader;
  ~IndexedReader() override {
    if (fd_ >= 0) ::close(fd_);
  }

  Status open(const Context& ctx) override {
    if (auto st = require_file(ctx, entry_.file); !st) return st;
    auto text = read_text(ctx, entry_.index);
    if (!text) return tl::unexpected(text.error());
    fd_ = ::open((ctx.dir / entry_.file).c_str(), O_RDONLY | O_CLOEXEC);
    if (fd_ < 0)
      return make_error(ErrorCode::kIoError, "{}: cannot read: {}", entry_.file, errno_text(errno));
    struct stat st {};
    if (::fstat(fd_, &st) != 0)
      return make_error(ErrorCode::kIoError, "{}: cannot stat: {}", entry_.file, errno_text(errno));
    const uint64_t data_size = static_cast<uint64_t>(st.st_size);
    const bool raw16 = entry_.encoding == "raw16";
    const bool png16 = entry_.encoding == "png16";
    const uint64_t depth_bytes = static_cast<uint64_t>(entry_.width) * entry_.height * 2;

    const auto lines = split_lines(*text);
    for (size_t i = 0; i < lines.size(); ++i) {
      const Line& l = lines[i];
      const std::string_view t = trim(l.text);
      if (t.empty()) {
        damage_.empty_lines++;
        continue;
      }
      if (t.front() == '#') continue;
      Entry e;
      std::vector<std::string_view> fields;
      for (size_t pos = 0;;) {
        const size_t comma = t.find(',', pos);
        fields.push_back(t.substr(pos, comma == std::string_view::npos ? t.npos : comma - pos));
        if (comma == std::string_view::npos) break;
        pos = comma + 1;
      }
      int64_t values[4] = {0, 0, 0, 0};
      bool ok = fields.size() == 4;
      for (size_t f = 0; ok && f < 4; ++f) {
        auto v = parse_int(fields[f]);
        ok = v.has_value();
        if (ok) values[f] = *v;
      }
      damage_.records++;
      if (!ok || values[0] < 0 || values[2] < 0 || values[3] <= 0) {
        if (!l.terminated) {  // the recorder died while writing this line
          damage_.records--;
          note_torn_tail(1, fmt::format("{}: line {} is cut", entry_.index, l.number));
          break;
        }
        note_damaged(static_cast<uint64_t>(l.number), std::nullopt,
                     fmt::format("{}: line {}: malformed index line '{}' (expected "
                                 "sequence,stamp_ns,offset,size)",
                                 entry_.index, l.number, shorten(t)));
        continue;
      }
      e.frame = damage_.records - 1;  // the frame's place among the index's records
      e.sequence = static_cast<uint64_t>(values[0]);
      e.stamp_ns = values[1];
      e.offset = static_cast<uint64_t>(values[2]);
      e.size = static_cast<uint64_t>(values[3]);
      if (!entries_.empty() && e.stamp_ns <= entries_.back().stamp_ns) {
        note_damaged(static_cast<uint64_t>(l.number), e.stamp_ns,
                     fmt::format("{}: line {}: stamp {} not after previous {}", entry_.index,
                                 l.number, e.stamp_ns, entries_.back().stamp_ns));
        continue;
      }
      if (raw16 && e.size != depth_bytes) {
        note_damaged(
            static_cast<uint64_t>(l.number), e.stamp_ns,
            fmt::format("{}: line {}: frame of {} bytes, a {}x{} raw16 frame has {}", entry_.index,
                        l.number, e.size, entry_.width, entry_.height, depth_bytes));
        continue;
      }
      entries_.push_back(e);
    }

    // Truncation: index entries past the end of the data are a torn tail (the data file was cut
    // or not flushed); one in the middle is a damaged record.
    const auto inside = [&](const Entry& e) {
      return e.offset <= data_size && e.size <= data_size - e.offset;
    };
    {
      size_t keep = entries_.size();
      while (keep > 0 && !inside(entries_[keep - 1])) --keep;
      if (keep != entries_.size()) {
        note_torn_tail(entries_.size() - keep,
                       fmt::format("{}: index has {} frames, the data ends inside or before frame "
                                   "{}",
                                   entry_.file, entries_.size(), keep));
        damage_.records -= entries_.size() - keep;
        entries_.resize(keep);
      }
    }

    // Cheap integrity check of every frame: a JPEG has SOI at the start and EOI at the end, a PNG
    // its 8-byte signature at the start (its CRCs are checked when it is decoded). Broken frames
    // at the very end are a torn tail; in the middle they are skipped and counted.
    const auto frame_ok = [&](const Entry& e) {
      if (!inside(e)) return false;
      if (raw16) return true;
      return png16 ? png_signature_ok(e) : jpeg_markers_ok(e);
    };
    {
      size_t keep = entries_.size();
      while (keep > 0 && !frame_ok(entries_[keep - 1])) --keep;
      if (keep != entries_.size()) {
        note_torn_tail(entries_.size() - keep,
                       fmt::format("{}: the last {} frame(s) are incomplete", entry_.file,
                                   entries_.size() - keep));
        damage_.records -= entries_.size() - keep;
        entries_.resize(keep);
      }
    }
    std::vector<Entry> usable;
    usable.reserve(entries_.size());
    for (size_t k = 0; k < entries_.size(); ++k) {
      const Entry& e = entries_[k];
      if (frame_ok(e)) {
        usable.push_back(e);
        continue;
      }
      note_damaged(e.frame, e.stamp_ns,
                   fmt::format("{}: frame {} (offset {}, {} bytes) is {}", entry_.file, e.frame,
                               e.offset, e.size,
                               !inside(e) ? "outside the data file"
                               : png16    ? "not a PNG (no PNG signature)"
                                          : "not a complete JPEG (no SOI/EOI marker)"));
    }
    entries_ = std::move(usable);

    // Data the index does not cover (an index cut short in a session marked complete): those
    // frames would be lost silently. Counted as damaged, estimated from the mean frame size; a
    // recorder that was killed leaves this normally (its index lags), so only warn then.
    if (!entries_.empty()) {
      const Entry& last = entries_.back();
      const uint64_t covered = last.offset + last.size;
      const uint64_t mean = std::max<uint64_t>(1, covered / entries_.size());
      const uint64_t missing = data_size > covered ? (data_size - covered) / mean : 0;
      if (missing >= 1 && !ctx.tolerate_tail) {
        damage_.records += missing;
        note_damaged(entries_.size(), std::nullopt,
                     fmt::format("{}: about {} frame(s) ({} bytes) after the last indexed frame "
                                 "are not in {}; `dreamsense check --repair` rebuilds the index",
                                 entry_.file, missing, data_size - covered, entry_.index));
        damage_.damaged += missing - 1;
      } else if (missing >= 1) {
        log::warn(
            "{}: incomplete session: about {} frame(s) after the last indexed one are not "
            "indexed yet",
            entry_.file, missing);
      }
    }
    return check_damage_limit(ctx.options);
  }

  std::optional<int64_t> peek() const override {
    if (next_ >= entries_.size()) return std::nullopt;
    return entries_[next_].stamp_ns;
  }
  std::optional<int64_t> first_stamp() const override {
    if (entries_.empty()) return std::nullopt;
    return entries_.front().stamp_ns;
  }
  std::optional<int64_t> last_stamp() const override {
    if (entries_.empty()) return std::nullopt;
    return entries_.back().stamp_ns;
  }

  Result<FramePtr> read() override;
  uint64_t last_read_index() const override { return next_ == 0 ? 0 : entries_[next_ - 1].frame; }
  std::vector<RecordLocation> records() const override {
    std::vector<RecordLocation> out;
    out.reserve(entries_.size());
    for (const Entry& e : entries_)
      out.push_back({e.frame, e.sequence, e.stamp_ns, e.offset, e.size});
    return out;
  }

  Result<FramePtr> decode_record(size_t k) const override {
    if (k >= entries_.size())
      return make_error(ErrorCode::kInvalidArgument, "{}: record {} of {} does not exist",
                        entry_.file, k, entries_.size());
    std::vector<uchar> buffer;
    return decode(k, buffer);
  }

  size_t frame_count() const { return entries_.size(); }
  int64_t stamp_of(size_t k) const { return entries_[k].stamp_ns; }
  // Decoding is handed to `read_ahead` (owned by the SessionReader, outlives this reader's reads).
  void set_read_ahead(ReadAhead* read_ahead) { read_ahead_ = read_ahead; }

  // Reads and decodes frame k into a new frame; `buffer` is scratch space. Thread-safe: it only
  // reads state fixed at open() (pread does not move the file offset).
  Result<FramePtr> decode(size_t k, std::vector<uchar>& buffer) const {
    const Entry& e = entries_.at(k);
    buffer.resize(e.size);
    size_t done = 0;
    while (done < e.size) {
      const ssize_t n =
          ::pread(fd_, buffer.data() + done, e.size - done, static_cast<off_t>(e.offset + done));
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0)
        return make_error(ErrorCode::kCorruptData, "{}: frame {}: read failed: {}", entry_.file,
                          e.frame, n < 0 ? errno_text(errno) : "unexpected end of file");
      done += static_cast<size_t>(n);
    }
    const Timestamp stamp = Timestamp::from_ns(e.stamp_ns);
    if (entry_.encoding == "raw16") {
      cv::Mat depth(entry_.height, entry_.width, CV_16UC1);
      std::memcpy(depth.data, buffer.data(), e.size);
      if constexpr (std::endian::native == std::endian::big) {
        auto* p = depth.ptr<uint16_t>();
        for (size_t i = 0; i < depth.total(); ++i)
          p[i] = static_cast<uint16_t>((p[i] >> 8) | (p[i] << 8));
      }
      DepthImage d;
      d.depth_mm = depth;
      return make_frame(entry_.id, stamp, e.sequence, std::move(d));
    }
    if (entry_.encoding == "png16") return decode_png16(e, stamp, buffer);
    cv::Mat image;
    cv::Size declared;
    const JpegDecode direct =
        decode_jpeg_direct(buffer, {entry_.width, entry_.height}, &image, &declared);
    if (direct == JpegDecode::kWrongSize) return wrong_size(e, declared.width, declared.height);
    if (direct == JpegDecode::kDamaged)
      return make_error(ErrorCode::kCorruptData,
                        "{}: corrupt: frame {} (offset {}) holds corrupt JPEG data", entry_.file,
                        e.frame, e.offset);
    if (direct == JpegDecode::kNotHandled) {
      try {
        image = cv::imdecode(buffer, cv::IMREAD_UNCHANGED);
      } catch (const cv::Exception&) {
        image.release();
      }
    }
    if (image.empty())
      return make_error(ErrorCode::kCorruptData,
                        "{}: corrupt: frame {} (offset {}) does not decode", entry_.file, e.frame,
                        e.offset);
    if (image.size() != cv::Size(entry_.width, entry_.height))
      return wrong_size(e, image.cols, image.rows);
    if (image.depth() != CV_8U || (image.channels() != 1 && image.channels() != 3))
      return make_error(ErrorCode::kUnsupported, "{}: frame {}: unsupported image type {}",
                        entry_.file, e.frame, image.type());
    ColorImage c;
    c.image = image;
    return make_frame(entry_.id, stamp, e.sequence, std::move(c));
  }

 private:
  struct Entry {
    uint64_t frame = 0;  // place among the index's records (damaged ones included), from 0
    uint64_t sequence = 0;
    int64_t stamp_ns = 0;
    uint64_t offset = 0, size = 0;
  };
  // Sizes as a header declares them (PNG: 32-bit unsigned).
  tl::unexpected<Error> wrong_size(const Entry& e, int64_t width, int64_t height) const {
    return make_error(ErrorCode::kCorruptData, "{}: frame {} is {}x{}, session.yaml declares {}x{}",
                      entry_.file, e.frame, width, height, entry_.width, entry_.height);
  }
  // PNG's first chunk is IHDR (13 bytes: width, height big-endian, bit depth, colour type, ...),
  // right after the signature that open() checked. Read before decoding, see decode_jpeg_direct.
  Status check_png16_header(const Entry& e, const std::vector<uchar>& png) const {
    const auto big_endian = [&](size_t at) {
      return (uint32_t{png[at]} << 24) | (uint32_t{png[at + 1]} << 16) |
             (uint32_t{png[at + 2]} << 8) | uint32_t{png[at + 3]};
    };
    constexpr size_t kIhdrEnd = 8 + 8 + 13;
    if (png.size() < kIhdrEnd || big_endian(8) != 13 || std::memcmp(&png[12], "IHDR", 4) != 0)
      return make_error(ErrorCode::kCorruptData,
                        "{}: corrupt: frame {} (offset {}) does not decode (no PNG header, IHDR)",
                        entry_.file, e.frame, e.offset);
    const uint32_t width = big_endian(16), height = big_endian(20);
    const int bit_depth = png[24], colour_type = png[25];
    if (bit_depth != 16 || colour_type != 0)
      return make_error(ErrorCode::kCorruptData,
                        "{}: corrupt: frame {} (offset {}) is not a 16-bit grey PNG (bit depth {}, "
                        "colour type {})",
                        entry_.file, e.frame, e.offset, bit_depth, colour_type);
    if (width != static_cast<uint32_t>(entry_.width) ||
        height != static_cast<uint32_t>(entry_.height))
      return wrong_size(e, width, height);
    return ok_status();
  }
  Result<FramePtr> decode_png16(const Entry& e, Timestamp stamp,
                                const std::vector<uchar>& buffer) const {
    if (auto header = check_png16_header(e, buffer); !header) return tl::unexpected(header.error());
    cv::Mat depth;
    try {
      depth = cv::imdecode(buffer, cv::IMREAD_UNCHANGED);
    } catch (const cv::Exception&) {
      depth.release();
    }
    if (depth.empty())
      return make_error(ErrorCode::kCorruptData,
                        "{}: corrupt: frame {} (offset {}) does not decode", entry_.file, e.frame,
                        e.offset);
    if (depth.type() != CV_16UC1)
      return make_error(ErrorCode::kCorruptData,
                        "{}: corrupt: frame {} (offset {}) is not a 16-bit grey PNG (decodes to "
                        "OpenCV type {})",
                        entry_.file, e.frame, e.offset, depth.type());
    if (depth.size() != cv::Size(entry_.width, entry_.height))
      return wrong_size(e, depth.cols, depth.rows);
    DepthImage d;
    d.depth_mm = depth;
    return make_frame(entry_.id, stamp, e.sequence, std::move(d));
  }
  bool png_signature_ok(const Entry& e) const {
    unsigned char head[8] = {};
    return e.size >= 8 && ::pread(fd_, head, 8, static_cast<off_t>(e.offset)) == 8 &&
           std::memcmp(head, kPngSignature, 8) == 0;
  }
  bool jpeg_markers_ok(const Entry& e) const {
    unsigned char head[2] = {0, 0}, tail[2] = {0, 0};
    return e.size >= 4 && ::pread(fd_, head, 2, static_cast<off_t>(e.offset)) == 2 &&
           ::pread(fd_, tail, 2, static_cast<off_t>(e.offset + e.size - 2)) == 2 &&
           head[0] == 0xFF && head[1] == 0xD8 && tail[0] == 0xFF && tail[1] == 0xD9;
  }
  int fd_ = -1;
  std::vector<Entry> entries_;
  size_t next_ = 0;
  std::vector<uchar> buffer_;
  ReadAhead* read_ahead_ = nullptr;
};

// Read-ahead decoding of the indexed streams on worker threads.
//
// The order in which next() returns the frames of the indexed streams depends only on their index
// stamps (a stable merge by stamp, ties by manifest order; the other streams only interleave), so
// it is known at open(). ReadAhead walks that order ("the plan") and keeps at most `window` frames
// queued, being decoded or decoded ahead of the caller. Workers decode the earliest queued frames;
// take() returns the front of the plan, decoding it on the caller's thread if no worker has
// started it yet. Each frame is decoded exactly once by the same code as without read-ahead, and
// its Result (frame or error) is returned at its own place, so only speed changes.
class ReadAhead {
 public:
  // `streams`: the indexed streams in manifest order; threads >= 1, window >= 1. The workers start
  // at the first take(), so a reader opened only for its manifest or info costs no decoding.
  ReadAhead(std::vector<const IndexedReader*> streams, int threads, int window)
      : streams_(std::move(streams)),
        planned_(streams_.size(), 0),
        threads_(threads),
        window_(window) {}
  ReadAhead(const ReadAhead&) = delete;
  ReadAhead& operator=(const ReadAhead&) = delete;
  // Stops the workers after the frame each is decoding; queued frames are dropped.
  ~ReadAhead() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
    }
    work_cv_.notify_all();
    for (auto& t : workers_) t.join();
  }

  // Frame k of `stream`, which must be the next frame of the plan (next() consumes the indexed
  // streams in plan order).
  Result<FramePtr> take(const IndexedReader* stream, size_t k) {
    if (!started_) start();
    std::unique_lock<std::mutex> lock(mutex_);
    DS_CHECK(!slots_.empty());
    Slot& slot = slots_.front();
    DS_CHECK(slot.stream == stream);
    DS_CHECK_EQ(slot.k, k);
    if (slot.state == State::kQueued) {  // no worker on it yet: decode it here
      slot.state = State::kDecoding;
      lock.unlock();
      run(slot, caller_buffer_);
      lock.lock();
    } else {
      done_cv_.wait(lock, [&] { return slot.state == State::kDone; });
    }
    std::optional<Result<FramePtr>> result = std::move(slot.result);
    const std::exception_ptr failure = slot.failure;
    slots_.pop_front();
    refill();
    lock.unlock();
    work_cv_.notify_all();
    if (failure) std::rethrow_exception(failure);
    return std::move(*result);
  }

 private:
  enum class State { kQueued, kDecoding, kDone };
  struct Slot {
    const IndexedReader* stream = nullptr;
    size_t k = 0;
    State state = State::kQueued;
    std::optional<Result<FramePtr>> result;
    std::exception_ptr failure;  // an exception of decode(), rethrown by take()
  };

  void start() {
    started_ = true;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      refill();
    }
    try {
      for (int i = 0; i < threads_; ++i) workers_.emplace_back([this] { work(); });
    } catch (const std::system_error& e) {  // no more threads: take() decodes what is left
      log::warn("session reader: started {} of {} decode threads: {}", workers_.size(), threads_,
                e.what());
    }
  }

  // Appends the next frames of the plan up to the window. Caller holds mutex_.
  void refill() {
    while (slots_.size() < static_cast<size_t>(window_)) {
      size_t best = streams_.size();
      for (size_t s = 0; s < streams_.size(); ++s) {
        if (planned_[s] >= streams_[s]->frame_count()) continue;
        if (best == streams_.size() ||
            streams_[s]->stamp_of(planned_[s]) < streams_[best]->stamp_of(planned_[best]))
          best = s;  // ties: the earlier stream in the manifest, as in next()
      }
      if (best == streams_.size()) return;  // plan exhausted
      Slot slot;
      slot.stream = streams_[best];
      slot.k = planned_[best]++;
      slots_.push_back(std::move(slot));
    }
  }

  // Decodes `slot` (state kDecoding, owned by this thread) without holding mutex_.
  static void run(Slot& slot, std::vector<uchar>& buffer) {
    try {
      slot.result = slot.stream->decode(slot.k, buffer);
    } catch (...) {
      slot.failure = std::current_exception();
    }
  }

  void work() {
    std::vector<uchar> buffer;
    std::unique_lock<std::mutex> lock(mutex_);
    for (;;) {
      Slot* slot = nullptr;
      work_cv_.wait(lock, [&] {
        if (stop_) return true;
        for (Slot& s : slots_)
          if (s.state == State::kQueued) {
            slot = &s;
            return true;
          }
        return false;
      });
      if (stop_) return;
      slot->state = State::kDecoding;
      lock.unlock();
      run(*slot, buffer);  // deque elements keep their address; take() waits for kDone
      lock.lock();
      slot->state = State::kDone;
      done_cv_.notify_all();
    }
  }

  const std::vector<const IndexedReader*> streams_;  // manifest order
  std::vector<size_t> planned_;                      // per stream: next frame not yet in slots_
  const int threads_;
  const int window_;
  std::mutex mutex_;
  std::condition_variable work_cv_;  // a frame was queued, or stop
  std::condition_variable done_cv_;  // a frame was decoded
  std::deque<Slot> slots_;           // the plan from the caller's next frame on
  bool stop_ = false;
  std::vector<uchar> caller_buffer_;  // used by take() only, i.e. by one thread at a time
  bool started_ = false;              // likewise
  std::vector<std::thread> workers_;
};

Result<FramePtr> IndexedReader::read() {
  const size_t k = next_++;
  if (read_ahead_ != nullptr) return read_ahead_->take(this, k);
  return decode(k, buffer_);
}

// "video": any container OpenCV reads + one stamp_ns per line (read-only).
class VideoReader : public StreamReader {
 public:
  using StreamReader::StreamReader;

  Status open(const Context& ctx) override {
    if (auto st = require_file(ctx, entry_.file); !st) return st;
    auto text = read_text(ctx, entry_.index);
    if (!text) return tl::unexpected(text.error());
    for (const Line& l : split_lines(*text)) {
      const std::string_view t = trim(l.text);
      if (t.empty() || t.front() == '#') continue;
      auto v = parse_int(t);
      if (!v)
        return make_error(ErrorCode::kCorruptData,
                          "{}: line {}: malformed stamp '{}' (expected one stamp_ns per line)",
                          entry_.index, l.number, shorten(t));
      if (!stamps_.empty() && *v <= stamps_.back())
        return make_error(ErrorCode::kCorruptData, "{}: line {}: stamp {} not after previous {}",
                          entry_.index, l.number, *v, stamps_.back());
      stamps_.push_back(*v);
    }
    try {
      capture_.open((ctx.dir / entry_.file).string(), cv::CAP_ANY);
    } catch (const cv::Exception&) {
    }
    if (!capture_.isOpened())
      return make_error(ErrorCode::kCorruptData, "{}: unreadable: OpenCV cannot open the video",
                        entry_.file);
    const auto count = static_cast<int64_t>(capture_.get(cv::CAP_PROP_FRAME_COUNT));
    if (count > 0 && count != static_cast<int64_t>(stamps_.size()))
      return make_error(ErrorCode::kCorruptData, "{}: {}: video has {} frames but {} has {} stamps",
                        entry_.file,
                        count < static_cast<int64_t>(stamps_.size()) ? "truncated" : "mismatch",
                        count, entry_.index, stamps_.size());
    const int w = static_cast<int>(capture_.get(cv::CAP_PROP_FRAME_WIDTH));
    const int h = static_cast<int>(capture_.get(cv::CAP_PROP_FRAME_HEIGHT));
    if (w > 0 && h > 0 && (w != entry_.width || h != entry_.height))
      return make_error(ErrorCode::kCorruptData, "{}: video is {}x{}, session.yaml declares {}x{}",
                        entry_.file, w, h, entry_.width, entry_.height);
    return ok_status();
  }
  std::optional<int64_t> peek() const override {
    if (next_ >= stamps_.size()) return std::nullopt;
    return stamps_[next_];
  }
  std::optional<int64_t> first_stamp() const override {
    if (stamps_.empty()) return std::nullopt;
    return stamps_.front();
  }
  std::optional<int64_t> last_stamp() const override {
    if (stamps_.empty()) return std::nullopt;
    return stamps_.back();
  }
  uint64_t last_read_index() const override { return next_ == 0 ? 0 : next_ - 1; }
  Result<FramePtr> read() override {
    const size_t k = next_++;
    cv::Mat image;
    bool ok = false;
    try {
      ok = capture_.read(image);
    } catch (const cv::Exception&) {
      ok = false;
    }
    if (!ok || image.empty())
      return make_error(ErrorCode::kCorruptData, "{}: corrupt: frame {} cannot be read",
                        entry_.file, k);
    if (image.cols != entry_.width || image.rows != entry_.height)
      return make_error(ErrorCode::kCorruptData,
                        "{}: frame {} is {}x{}, session.yaml declares {}x{}", entry_.file, k,
                        image.cols, image.rows, entry_.width, entry_.height);
    ColorImage c;
    c.image = image;
    return make_frame(entry_.id, Timestamp::from_ns(stamps_[k]), k, std::move(c));
  }

 private:
  std::vector<int64_t> stamps_;
  cv::VideoCapture capture_;
  size_t next_ = 0;
};

// Skeleton "jsonl": parsed completely at open (frames are small).
class SkeletonReader : public StreamReader {
 public:
  using StreamReader::StreamReader;

  Status open(const Context& ctx) override {
    auto text = read_text(ctx, entry_.file);
    if (!text) return tl::unexpected(text.error());
    for (const Line& l : split_lines(*text)) {
      if (trim(l.text).empty()) {
        damage_.empty_lines++;
        continue;
      }
      auto frame = parse_line(l);
      if (!frame && !l.terminated) {  // the recorder died while writing the last line
        note_torn_tail(1, fmt::format("line {}: {}", l.number, frame.error().message));
        break;
      }
      damage_.records++;
      if (!frame) {
        note_damaged(static_cast<uint64_t>(l.number), std::nullopt, frame.error().message);
        continue;
      }
      if (!frames_.empty() && (*frame)->stamp <= frames_.back()->stamp) {
        note_damaged(static_cast<uint64_t>(l.number), (*frame)->stamp.ns(),
                     fmt::format("{}: line {}: stamp {} not after previous {}", entry_.file,
                                 l.number, (*frame)->stamp.ns(), frames_.back()->stamp.ns()));
        continue;
      }
      frames_.push_back(std::move(*frame));
      locations_.push_back({static_cast<uint64_t>(l.number), frames_.back()->sequence,
                            frames_.back()->stamp.ns(),
                            static_cast<uint64_t>(l.text.data() - text->data()), l.text.size()});
    }
    return check_damage_limit(ctx.options);
  }
  std::optional<int64_t> peek() const override {
    if (next_ >= frames_.size()) return std::nullopt;
    return frames_[next_]->stamp.ns();
  }
  std::optional<int64_t> first_stamp() const override {
    if (frames_.empty()) return std::nullopt;
    return frames_.front()->stamp.ns();
  }
  std::optional<int64_t> last_stamp() const override {
    if (frames_.empty()) return std::nullopt;
    return frames_.back()->stamp.ns();
  }
  Result<FramePtr> read() override { return frames_.at(next_++); }
  std::vector<RecordLocation> records() const override { return locations_; }

 private:
  Result<FramePtr> parse_line(const Line& l) const {
    auto parsed = parse_skeleton_json(l.text);
    if (!parsed)
      return make_error(ErrorCode::kCorruptData, "{}: line {}: {}", entry_.file, l.number,
                        parsed.error().message);
    if (!parsed->stamp_ns)
      return make_error(ErrorCode::kCorruptData, "{}: line {}: missing integer 'stamp_ns'",
                        entry_.file, l.number);
    return make_frame(entry_.id, Timestamp::from_ns(*parsed->stamp_ns),
                      parsed->sequence.value_or(frames_.size()), std::move(parsed->skeleton));
  }

  std::vector<FramePtr> frames_;
  std::vector<RecordLocation> locations_;  // where each of frames_ is in the file
  size_t next_ = 0;
};

// The byte length the "data" chunk of a RIFF/WAVE file declares (nullopt: not RIFF, not found, or
// the "unknown length" values 0 / 0xFFFFFFFF that streaming writers use).
std::optional<int64_t> riff_data_bytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  unsigned char header[12];
  if (!in.read(reinterpret_cast<char*>(header), 12)) return std::nullopt;
  if (std::memcmp(header, "RIFF", 4) != 0 || std::memcmp(header + 8, "WAVE", 4) != 0)
    return std::nullopt;
  for (int i = 0; i < 64; ++i) {
    unsigned char chunk[8];
    if (!in.read(reinterpret_cast<char*>(chunk), 8)) return std::nullopt;
    const uint32_t size = static_cast<uint32_t>(chunk[4]) | static_cast<uint32_t>(chunk[5]) << 8 |
                          static_cast<uint32_t>(chunk[6]) << 16 |
                          static_cast<uint32_t>(chunk[7]) << 24;
    if (std::memcmp(chunk, "data", 4) == 0) {
      if (size == 0 || size == 0xFFFFFFFFu) return std::nullopt;
      return static_cast<int64_t>(size);
    }
    in.seekg(static_cast<std::streamoff>(size + (size & 1)), std::ios::cur);
  }
  return std::nullopt;
}

// Audio "wav": delivered in chunks of options.audio_chunk.
class WavReader : public StreamReader {
 public:
  using StreamReader::StreamReader;
  ~WavReader() override {
    if (file_ != nullptr) sf_close(file_);
  }

  Status open(const Context& ctx) override {
    if (auto st = require_file(ctx, entry_.file); !st) return st;
    SF_INFO info{};
    file_ = sf_open((ctx.dir / entry_.file).c_str(), SFM_READ, &info);
    if (file_ == nullptr)
      return make_error(ErrorCode::kCorruptData, "{}: unreadable: {}", entry_.file,
                        sf_strerror(nullptr));
    if (info.samplerate != entry_.sample_rate)
      return make_error(ErrorCode::kCorruptData, "{}: sample rate {} Hz, {} declares {} Hz",
                        entry_.file, info.samplerate, kManifestName, entry_.sample_rate);
    if (info.channels != entry_.channels)
      return make_error(ErrorCode::kCorruptData, "{}: {} channels, {} declares {}", entry_.file,
                        info.channels, kManifestName, entry_.channels);
    // libsndfile silently shortens a WAV whose data chunk runs past the end of the file: check
    // the declared length ourselves.
    if (auto declared = riff_data_bytes(ctx.dir / entry_.file)) {
      const int64_t frame_bytes = static_cast<int64_t>(info.channels) *
                                  ((info.format & SF_FORMAT_SUBMASK) == SF_FORMAT_PCM_16 ? 2 : 0);
      if (frame_bytes > 0 && *declared / frame_bytes > info.frames) {
        const int64_t chunk =
            std::max<int64_t>(1, ctx.options.audio_chunk.ns() * entry_.sample_rate / 1000000000LL);
        const int64_t lost = *declared / frame_bytes - info.frames;
        note_torn_tail(static_cast<uint64_t>((lost + chunk - 1) / chunk),
                       fmt::format("{}: header declares {} samples, the data holds {} ({:.2f} s "
                                   "cut)",
                                   entry_.file, *declared / frame_bytes, info.frames,
                                   static_cast<double>(lost) / entry_.sample_rate));
      }
    }
    pcm16_ = (info.format & SF_FORMAT_SUBMASK) == SF_FORMAT_PCM_16;
    if (!pcm16_) sf_command(file_, SFC_SET_NORM_FLOAT, nullptr, SF_TRUE);
    total_ = info.frames;
    chunk_ = std::max<int64_t>(1, ctx.options.audio_chunk.ns() * entry_.sample_rate / 1000000000LL);
    damage_.records = static_cast<uint64_t>((total_ + chunk_ - 1) / chunk_);
    return check_damage_limit(ctx.options);
  }
  std::optional<int64_t> peek() const override {
    if (pos_ >= total_) return std::nullopt;
    return stamp_of(pos_);
  }
  std::optional<int64_t> first_stamp() const override {
    if (total_ <= 0) return std::nullopt;
    return stamp_of(0);
  }
  std::optional<int64_t> last_stamp() const override {
    if (total_ <= 0) return std::nullopt;
    return stamp_of((total_ - 1) / chunk_ * chunk_);
  }
  Result<FramePtr> read() override {
    const int64_t want = std::min(chunk_, total_ - pos_);
    const int ch = entry_.channels;
    AudioChunk a;
    a.sample_rate = entry_.sample_rate;
    a.channels = ch;
    a.samples.resize(static_cast<size_t>(want * ch));
    sf_count_t got = 0;
    if (pcm16_) {
      shorts_.resize(a.samples.size());
      got = sf_readf_short(file_, shorts_.data(), want);
      for (size_t i = 0; i < static_cast<size_t>(std::max<sf_count_t>(got, 0) * ch); ++i)
        a.samples[i] = std::max(-1.f, static_cast<float>(shorts_[i]) / 32767.f);
    } else {
      got = sf_readf_float(file_, a.samples.data(), want);
    }
    const int64_t first = pos_;
    const uint64_t sequence = static_cast<uint64_t>(pos_ / chunk_);
    if (got <= 0) {
      pos_ = total_;
      return make_error(ErrorCode::kCorruptData, "{}: corrupt: read failed at sample {}: {}",
                        entry_.file, first, sf_strerror(file_));
    }
    if (got < want) {  // the header claimed more than the file holds
      a.samples.resize(static_cast<size_t>(got * ch));
      total_ = pos_ + got;
    }
    pos_ += got;
    return make_frame(entry_.id, Timestamp::from_ns(stamp_of(first)), sequence, std::move(a));
  }

 private:
  int64_t stamp_of(int64_t sample) const {
    return sample_stamp(entry_.start_ns, sample, entry_.sample_rate);
  }
  SNDFILE* file_ = nullptr;
  bool pcm16_ = true;
  int64_t total_ = 0, pos_ = 0, chunk_ = 1;
  std::vector<int16_t> shorts_;
};

}  // namespace

// ----------------------------------------------------------------------------------------------

Status SessionReaderOptions::check() const {
  std::vector<std::string> bad;
  if (audio_chunk.ns() <= 0)
    bad.push_back(fmt::format("audio_chunk must be > 0, got {} s", audio_chunk.seconds()));
  if (decode_threads < 0 || decode_threads > kMaxDecodeThreads)
    bad.push_back(fmt::format("decode_threads must be in [0, {}], got {}", kMaxDecodeThreads,
                              decode_threads));
  if (read_ahead_frames < 1)
    bad.push_back(fmt::format("read_ahead_frames must be >= 1, got {}", read_ahead_frames));
  if (!(max_damaged_fraction >= 0 && max_damaged_fraction <= 1))
    bad.push_back(
        fmt::format("max_damaged_fraction must be in [0, 1], got {}", max_damaged_fraction));
  if (bad.empty()) return ok_status();
  std::string msg = "SessionReaderOptions: ";
  for (size_t i = 0; i < bad.size(); ++i) msg += (i ? "; " : "") + bad[i];
  return make_error(ErrorCode::kInvalidArgument, std::move(msg));
}

struct SessionReader::Impl {
  std::filesystem::path dir;
  SessionManifest manifest;
  SessionReaderOptions options;
  std::vector<std::unique_ptr<StreamReader>> streams;  // manifest order
  SourceInfo info;
  // Declared last: destroyed (workers stopped) before the streams it decodes from.
  std::unique_ptr<ReadAhead> read_ahead;
};

SessionReader::SessionReader() : impl_(std::make_unique<Impl>()) {}
SessionReader::~SessionReader() = default;

const SessionManifest& SessionReader::manifest() const { return impl_->manifest; }
const std::filesystem::path& SessionReader::dir() const { return impl_->dir; }
SourceInfo SessionReader::info() const { return impl_->info; }

Result<std::unique_ptr<SessionReader>> SessionReader::open(const std::filesystem::path& session_dir,
                                                           SessionReaderOptions options) {
  if (auto st = options.check(); !st) return tl::unexpected(st.error());
  auto manifest = read_manifest(session_dir);
  if (!manifest) return tl::unexpected(manifest.error());

  std::unique_ptr<SessionReader> reader(new SessionReader());
  Impl& impl = *reader->impl_;
  impl.dir = session_dir;
  impl.manifest = std::move(*manifest);
  impl.options = options;
  const SessionManifest& m = impl.manifest;

  for (const auto& id : options.only) {
    if (m.find(id) != nullptr) continue;
    std::string ids;
    for (const auto& s : m.streams) ids += (ids.empty() ? "" : ", ") + s.id;
    return make_error(ErrorCode::kNotFound, "{}: no stream '{}' (streams: {})", kManifestName, id,
                      ids);
  }

  Context ctx;
  ctx.dir = session_dir;
  ctx.manifest = &m;
  ctx.options = options;
  if (!m.complete) {
    if (!options.allow_incomplete)
      return make_error(ErrorCode::kCorruptData,
                        "{}: incomplete session (complete: false: the recorder was not closed, "
                        "e.g. it crashed); allow_incomplete is off",
                        kManifestName);
    log::warn("{}: incomplete session (complete: false); reading up to the last complete record",
              (session_dir / kManifestName).string());
    ctx.tolerate_tail = true;
  }
  if (!m.truth.empty() && !std::filesystem::exists(session_dir / m.truth))
    log::warn("{}: declared in {} but missing", m.truth, kManifestName);

  for (const auto& s : m.streams) {
    if (!options.only.empty() &&
        std::find(options.only.begin(), options.only.end(), s.id) == options.only.end())
      continue;
    if (!s.calibration.empty() && options.require_calibration_files) {
      if (auto st = require_file(ctx, s.calibration); !st) return tl::unexpected(st.error());
    }
    std::unique_ptr<StreamReader> r;
    if (s.encoding == "mjpeg" || s.encoding == "raw16" || s.encoding == "png16")
      r = std::make_unique<IndexedReader>(s);
    else if (s.encoding == "video")
      r = std::make_unique<VideoReader>(s);
    else if (s.encoding == "jsonl")
      r = std::make_unique<SkeletonReader>(s);
    else if (s.encoding == "wav")
      r = std::make_unique<WavReader>(s);
    else
      return make_error(ErrorCode::kUnsupported, "{}: stream {}: unknown encoding '{}'",
                        kManifestName, s.id, s.encoding);
    r->set_log_damage(options.log_damage);
    r->set_listed_damage(options.listed_damage);
    r->set_torn_tail_counts(m.complete);
    if (auto st = r->open(ctx); !st) return tl::unexpected(st.error());
    impl.streams.push_back(std::move(r));
  }

  // Clock check: every stream's first stamp must be near the others'.
  std::vector<int64_t> firsts;
  for (const auto& r : impl.streams)
    if (auto f = r->first_stamp()) firsts.push_back(*f);
  if (firsts.size() >= 2) {
    std::vector<int64_t> sorted = firsts;
    std::sort(sorted.begin(), sorted.end());
    const int64_t median = sorted[(sorted.size() - 1) / 2];
    for (const auto& r : impl.streams) {
      auto f = r->first_stamp();
      if (!f || std::llabs(*f - median) <= kMaxFirstStampSpreadNs) continue;
      return make_error(ErrorCode::kCorruptData,
                        "{}: clock mismatch: first stamp {} is {:.1f} s from the other streams' "
                        "({}); streams must share the session clock",
                        r->main_file(), Timestamp::from_ns(*f).to_string(),
                        static_cast<double>(*f - median) * 1e-9,
                        Timestamp::from_ns(median).to_string());
    }
  }

  SourceInfo& info = impl.info;
  info.live = false;
  std::optional<int64_t> start, end;
  for (const auto& r : impl.streams) {
    const StreamEntry& s = r->entry();
    SensorDescription d;
    d.id = s.id;
    d.kind = s.kind;
    d.rate_hz = s.kind == SensorKind::kAudio ? 1e9 / static_cast<double>(options.audio_chunk.ns())
                                             : (s.rate_hz > 0 ? s.rate_hz : m.frame_rate);
    d.width = s.width;
    d.height = s.height;
    d.sample_rate = s.sample_rate;
    d.channels = s.channels;
    if (!s.calibration.empty())
      d.calibration = std::filesystem::absolute(session_dir / s.calibration).lexically_normal();
    d.frame = s.frame.empty() ? s.id : s.frame;
    info.sensors.push_back(std::move(d));
    if (auto f = r->first_stamp()) start = start ? std::min(*start, *f) : *f;
    if (auto l = r->last_stamp()) end = end ? std::max(*end, *l) : *l;
  }
  if (start) info.start = Timestamp::from_ns(*start);
  if (end) info.end = Timestamp::from_ns(*end);

  if (options.decode_threads > 0) {
    std::vector<IndexedReader*> indexed;
    for (const auto& r : impl.streams)
      if (auto* ir = dynamic_cast<IndexedReader*>(r.get()); ir != nullptr && ir->frame_count() > 0)
        indexed.push_back(ir);
    if (!indexed.empty()) {
      impl.read_ahead = std::make_unique<ReadAhead>(
          std::vector<const IndexedReader*>(indexed.begin(), indexed.end()), options.decode_threads,
          options.read_ahead_frames);
      for (auto* ir : indexed) ir->set_read_ahead(impl.read_ahead.get());
    }
  }
  return reader;
}

std::vector<RecordLocation> SessionReader::records(const SensorId& id) const {
  for (const auto& r : impl_->streams)
    if (r->entry().id == id) return r->records();
  return {};
}

Result<FramePtr> SessionReader::decode_record(const SensorId& id, size_t k) const {
  for (const auto& r : impl_->streams)
    if (r->entry().id == id) return r->decode_record(k);
  return make_error(ErrorCode::kNotFound, "{}: stream '{}' is not read", impl_->dir.string(), id);
}

std::vector<StreamDamage> SessionReader::damage() const {
  std::vector<StreamDamage> out;
  for (const auto& r : impl_->streams) out.push_back(r->damage());
  return out;
}

bool SessionReader::stream_ended(const SensorId& id) const {
  for (const auto& r : impl_->streams)
    if (r->entry().id == id) return !r->peek().has_value();
  return true;
}

Result<FramePtr> SessionReader::next() {
  for (;;) {
    StreamReader* best = nullptr;
    int64_t best_stamp = 0;
    for (auto& r : impl_->streams) {
      auto s = r->peek();
      if (!s) continue;
      if (best == nullptr || *s < best_stamp) {  // ties: the earlier stream in the manifest
        best = r.get();
        best_stamp = *s;
      }
    }
    if (best == nullptr)
      return make_error(ErrorCode::kEndOfStream, "{}: end of session", impl_->dir.string());
    Result<FramePtr> frame = best->read();
    if (frame || frame.error().code != ErrorCode::kCorruptData) return frame;
    // A frame that does not decode costs that frame: skipped, counted, reported.
    best->note_damaged(best->last_read_index(), best_stamp, frame.error().message, true);
    if (auto st = best->check_damage_limit(impl_->options); !st) return tl::unexpected(st.error());
  }
}

}  // namespace dreamsense::sources
