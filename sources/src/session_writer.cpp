// SessionWriter: append-only, crash-safe session recording (docs/session_format.md).
//
// Crash safety: data bytes go to the kernel with write() as each frame arrives; index lines are
// kept in memory and appended only by flush(), after the data file was fsync'ed. So the index on
// disk never points past data on disk, even after a power cut; after a kill (or power cut)
// everything up to the last flush reads back, and data past the last index line is ignored.

#include "dreamsense/core/log.hpp"
#include "dreamsense/sources/session.hpp"

#include <fmt/format.h>
#include <opencv2/imgcodecs.hpp>
#include <sndfile.h>

#include <algorithm>
#include <bit>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fcntl.h>
#include <functional>
#include <string>
#include <unistd.h>
#include <vector>

#include "posix_file.hpp"

namespace dreamsense::sources {
namespace {

using detail::errno_text;
using detail::sync_dir;

// An append-only file descriptor with the name used in messages.
class AppendFile {
 public:
  AppendFile() = default;
  AppendFile(const AppendFile&) = delete;
  AppendFile& operator=(const AppendFile&) = delete;
  ~AppendFile() {
    if (fd_ >= 0) ::close(fd_);
  }

  Status open(const std::filesystem::path& path, std::string name) {
    name_ = std::move(name);
    fd_ = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd_ < 0)
      return make_error(ErrorCode::kIoError, "{}: cannot create: {}", name_, errno_text(errno));
    return ok_status();
  }
  Status append(const void* data, size_t size) {
    const char* p = static_cast<const char*>(data);
    size_t done = 0;
    while (done < size) {
      const ssize_t n = ::write(fd_, p + done, size - done);
      if (n < 0) {
        if (errno == EINTR) continue;
        return make_error(ErrorCode::kIoError, "{}: write failed: {}", name_, errno_text(errno));
      }
      done += static_cast<size_t>(n);
    }
    size_ += size;
    return ok_status();
  }
  Status append(const std::string& s) { return append(s.data(), s.size()); }
  Status sync() {
    if (fd_ >= 0 && ::fsync(fd_) != 0)
      return make_error(ErrorCode::kIoError, "{}: fsync failed: {}", name_, errno_text(errno));
    return ok_status();
  }
  Status close() {
    if (fd_ < 0) return ok_status();
    const int fd = fd_;
    fd_ = -1;
    if (::close(fd) != 0)
      return make_error(ErrorCode::kIoError, "{}: close failed: {}", name_, errno_text(errno));
    return ok_status();
  }
  uint64_t size() const { return size_; }
  const std::string& name() const { return name_; }

 private:
  int fd_ = -1;
  uint64_t size_ = 0;
  std::string name_;
};

// One declared stream being written.
class StreamWriter {
 public:
  explicit StreamWriter(const StreamEntry& entry) : entry_(entry) {}
  virtual ~StreamWriter() = default;
  virtual Status open(const std::filesystem::path& dir) = 0;
  virtual Status write(const SensorFrame& frame) = 0;
  virtual Status flush() = 0;
  virtual Status close() = 0;

  const StreamEntry& entry() const { return entry_; }
  // Checks that stamps strictly increase, then remembers `stamp`.
  Status check_stamp(Timestamp stamp) {
    if (!stamp.is_set() || stamp.is_special())
      return make_error(ErrorCode::kInvalidArgument, "stream {}: frame stamp is {}", entry_.id,
                        stamp.to_string());
    if (last_stamp_.is_set() && stamp <= last_stamp_)
      return make_error(ErrorCode::kInvalidArgument,
                        "stream {}: stamp {} not after previous {} (stamps must strictly increase)",
                        entry_.id, stamp.ns(), last_stamp_.ns());
    last_stamp_ = stamp;
    return ok_status();
  }

 protected:
  StreamEntry entry_;
  Timestamp last_stamp_ = Timestamp::unset();
};

// mjpeg (colour), raw16 and png16 (depth): data file + index file with buffered index lines.
class IndexedWriter : public StreamWriter {
 public:
  IndexedWriter(const StreamEntry& entry, const SessionWriterOptions& options)
      : StreamWriter(entry),
        jpeg_quality_(options.jpeg_quality),
        png_compression_(options.png_compression) {}

  Status open(const std::filesystem::path& dir) override {
    if (auto st = data_.open(dir / entry_.file, entry_.file); !st) return st;
    if (auto st = index_.open(dir / entry_.index, entry_.index); !st) return st;
    pending_ = fmt::format("# dreamsense {} index v1\n", entry_.encoding);
    return ok_status();
  }

  Status write(const SensorFrame& frame) override {
    const cv::Mat* image = nullptr;
    if (entry_.kind == SensorKind::kColor) {
      const auto* c = frame.as<ColorImage>();
      if (c == nullptr) return wrong_payload(frame);
      image = &c->image;
      if (image->depth() != CV_8U || (image->channels() != 3 && image->channels() != 1))
        return make_error(ErrorCode::kInvalidArgument,
                          "stream {}: colour image must be CV_8UC3 or CV_8UC1 (type {})", entry_.id,
                          image->type());
    } else {
      const auto* d = frame.as<DepthImage>();
      if (d == nullptr) return wrong_payload(frame);
      image = &d->depth_mm;
      if (image->type() != CV_16UC1)
        return make_error(ErrorCode::kInvalidArgument,
                          "stream {}: depth image must be CV_16UC1 (type {})", entry_.id,
                          image->type());
    }
    if (image->cols != entry_.width || image->rows != entry_.height)
      return make_error(ErrorCode::kInvalidArgument,
                        "stream {}: image is {}x{}, session.yaml declares {}x{}", entry_.id,
                        image->cols, image->rows, entry_.width, entry_.height);
    if (auto st = check_stamp(frame.stamp); !st) return st;

    const uint64_t offset = data_.size();
    if (entry_.kind == SensorKind::kColor) {
      buffer_.clear();
      if (!cv::imencode(".jpg", *image, buffer_, {cv::IMWRITE_JPEG_QUALITY, jpeg_quality_}))
        return make_error(ErrorCode::kInternal, "stream {}: JPEG encoding failed", entry_.id);
      if (auto st = data_.append(buffer_.data(), buffer_.size()); !st) return st;
    } else if (entry_.encoding == "png16") {
      // Lossless 16-bit grey PNG (OpenCV writes the samples big-endian, as PNG requires).
      buffer_.clear();
      bool encoded = false;
      try {
        encoded =
            cv::imencode(".png", *image, buffer_, {cv::IMWRITE_PNG_COMPRESSION, png_compression_});
      } catch (const cv::Exception& e) {
        return make_error(ErrorCode::kInternal, "stream {}: PNG encoding failed: {}", entry_.id,
                          e.err);
      }
      if (!encoded || buffer_.empty())
        return make_error(ErrorCode::kInternal, "stream {}: PNG encoding failed", entry_.id);
      if (auto st = data_.append(buffer_.data(), buffer_.size()); !st) return st;
    } else {
      cv::Mat m = image->isContinuous() ? *image : image->clone();
      if constexpr (std::endian::native == std::endian::big) {
        std::vector<uint16_t> le(m.total());
        const auto* src = m.ptr<uint16_t>();
        for (size_t i = 0; i < le.size(); ++i)
          le[i] = static_cast<uint16_t>((src[i] >> 8) | (src[i] << 8));
        if (auto st = data_.append(le.data(), le.size() * 2); !st) return st;
      } else {
        if (auto st = data_.append(m.data, m.total() * 2); !st) return st;
      }
    }
    pending_ += fmt::format("{},{},{},{}\n", frame.sequence, frame.stamp.ns(), offset,
                            data_.size() - offset);
    return ok_status();
  }

  Status flush() override {
    if (auto st = data_.sync(); !st) return st;
    if (!pending_.empty()) {
      if (auto st = index_.append(pending_); !st) return st;
      pending_.clear();
    }
    return index_.sync();
  }

  Status close() override {
    auto st = flush();
    auto a = data_.close();
    auto b = index_.close();
    if (!st) return st;
    if (!a) return a;
    return b;
  }

 private:
  Status wrong_payload(const SensorFrame& frame) const {
    return make_error(ErrorCode::kInvalidArgument, "stream {}: got a {} frame, declared {}",
                      entry_.id, to_string(frame.kind()), to_string(entry_.kind));
  }
  int jpeg_quality_;
  int png_compression_;
  AppendFile data_, index_;
  std::string pending_;  // index lines not yet written (the data is not yet fsync'ed)
  std::vector<uchar> buffer_;
};

class SkeletonWriter : public StreamWriter {
 public:
  using StreamWriter::StreamWriter;
  Status open(const std::filesystem::path& dir) override {
    return file_.open(dir / entry_.file, entry_.file);
  }
  Status write(const SensorFrame& frame) override {
    const auto* sk = frame.as<Skeleton>();
    if (sk == nullptr)
      return make_error(ErrorCode::kInvalidArgument, "stream {}: got a {} frame, declared {}",
                        entry_.id, to_string(frame.kind()), to_string(entry_.kind));
    if (auto st = check_stamp(frame.stamp); !st) return st;
    std::string line = fmt::format("{{\"stamp_ns\":{},\"sequence\":{},\"bodies\":[",
                                   frame.stamp.ns(), frame.sequence);
    for (size_t b = 0; b < sk->bodies.size(); ++b) {
      const SkeletonBody& body = sk->bodies[b];
      if (b > 0) line += ',';
      line += fmt::format("{{\"id\":{},\"joints\":{{", body.body_id);
      bool first = true;
      for (int j = 0; j < kJointCount; ++j) {
        const JointObservation& o = body.joints[j];
        if (!(o.confidence > 0.f)) continue;
        const auto& p = o.position_m;
        if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2]) ||
            !std::isfinite(o.confidence))
          return make_error(ErrorCode::kInvalidArgument,
                            "stream {}: joint {} of body {} is not finite", entry_.id,
                            joint_name(static_cast<JointId>(j)), body.body_id);
        if (!first) line += ',';
        first = false;
        line +=
            fmt::format("\"{}\":[{:.7f},{:.7f},{:.7f},{:.4f}]", joint_name(static_cast<JointId>(j)),
                        p[0], p[1], p[2], static_cast<double>(o.confidence));
      }
      line += "}}";
    }
    line += "]}\n";
    return file_.append(line);
  }
  Status flush() override { return file_.sync(); }
  Status close() override {
    auto st = flush();
    auto c = file_.close();
    return st ? c : st;
  }

 private:
  AppendFile file_;
};

class WavWriter : public StreamWriter {
 public:
  // `on_start` is called with the first chunk's stamp (the writer records it in the manifest).
  WavWriter(const StreamEntry& entry, std::function<Status(int64_t)> on_start)
      : StreamWriter(entry), on_start_(std::move(on_start)) {}
  ~WavWriter() override {
    if (file_ != nullptr) sf_close(file_);
  }
  Status open(const std::filesystem::path& dir) override {
    SF_INFO info{};
    info.samplerate = entry_.sample_rate;
    info.channels = entry_.channels;
    info.format = SF_FORMAT_WAV | SF_FORMAT_PCM_16;
    file_ = sf_open((dir / entry_.file).c_str(), SFM_WRITE, &info);
    if (file_ == nullptr)
      return make_error(ErrorCode::kIoError, "{}: cannot create: {}", entry_.file,
                        sf_strerror(nullptr));
    // Rewrite the header after every write, so the file is valid after a kill.
    sf_command(file_, SFC_SET_UPDATE_HEADER_AUTO, nullptr, SF_TRUE);
    return ok_status();
  }
  Status write(const SensorFrame& frame) override {
    const auto* a = frame.as<AudioChunk>();
    if (a == nullptr)
      return make_error(ErrorCode::kInvalidArgument, "stream {}: got a {} frame, declared {}",
                        entry_.id, to_string(frame.kind()), to_string(entry_.kind));
    if (a->sample_rate != entry_.sample_rate || a->channels != entry_.channels)
      return make_error(ErrorCode::kInvalidArgument,
                        "stream {}: chunk is {} Hz x {} channels, session.yaml declares {} Hz x "
                        "{} channels",
                        entry_.id, a->sample_rate, a->channels, entry_.sample_rate,
                        entry_.channels);
    if (a->samples.size() % static_cast<size_t>(a->channels) != 0)
      return make_error(ErrorCode::kInvalidArgument,
                        "stream {}: chunk has {} samples, not a multiple of {} channels", entry_.id,
                        a->samples.size(), a->channels);
    if (a->samples.empty()) return ok_status();
    if (frames_written_ == 0) {
      if (!frame.stamp.is_set() || frame.stamp.is_special())
        return make_error(ErrorCode::kInvalidArgument, "stream {}: chunk stamp is {}", entry_.id,
                          frame.stamp.to_string());
      start_ns_ = frame.stamp.ns();
      if (auto st = on_start_(start_ns_); !st) return st;
    } else {
    }
    // Devices do not always deliver contiguous chunks (ALSA xruns, the `null` device): the WAV
    // must stay on the session clock, so a gap is filled with silence and an overlap is cut, both
    // counted (gap_samples/overlap_samples, logged); only an absurd jump is an error.
    size_t skip = 0;  // leading samples per channel already covered by earlier chunks
    if (frames_written_ > 0) {
      const int64_t expected = stamp_of(frames_written_);
      const int64_t sample_ns = 1000000000LL / entry_.sample_rate + 1;
      const int64_t offset_ns = frame.stamp.ns() - expected;
      const int64_t offset =
          std::llround(static_cast<double>(offset_ns) * 1e-9 * entry_.sample_rate);
      if (std::llabs(offset_ns) > kMaxAudioJumpS * 1000000000LL)
        return make_error(ErrorCode::kInvalidArgument,
                          "stream {}: chunk stamp {} is {:.1f} s from the expected {} (more than "
                          "{} s: not the same clock)",
                          entry_.id, frame.stamp.ns(), offset_ns * 1e-9, expected, kMaxAudioJumpS);
      if (offset > 0 && std::llabs(offset_ns) > sample_ns) {
        if (gap_samples_ == 0)
          log::warn("stream {}: audio gap of {} samples at {} filled with silence (counted)",
                    entry_.id, offset, frame.stamp.to_string());
        shorts_.assign(static_cast<size_t>(offset * entry_.channels), 0);
        if (sf_writef_short(file_, shorts_.data(), offset) != offset)
          return make_error(ErrorCode::kIoError, "{}: write failed: {}", entry_.file,
                            sf_strerror(file_));
        frames_written_ += offset;
        gap_samples_ += offset;
      } else if (offset < 0 && std::llabs(offset_ns) > sample_ns) {
        skip = static_cast<size_t>(std::min<int64_t>(-offset, a->frames()));
        if (overlap_samples_ == 0)
          log::warn(
              "stream {}: audio chunk at {} overlaps the previous one by {} samples (cut, "
              "counted)",
              entry_.id, frame.stamp.to_string(), -offset);
        overlap_samples_ += static_cast<int64_t>(skip);
        if (static_cast<int64_t>(skip) == a->frames()) return ok_status();
      }
    }
    last_stamp_ = frame.stamp;
    const size_t first = skip * static_cast<size_t>(a->channels);
    shorts_.resize(a->samples.size() - first);
    for (size_t i = 0; i < shorts_.size(); ++i) {
      const float v = std::clamp(a->samples[first + i], -1.f, 1.f);
      shorts_[i] = static_cast<int16_t>(std::lrint(v * 32767.f));
    }
    const sf_count_t n = static_cast<sf_count_t>(a->frames() - skip);
    if (sf_writef_short(file_, shorts_.data(), n) != n)
      return make_error(ErrorCode::kIoError, "{}: write failed: {}", entry_.file,
                        sf_strerror(file_));
    frames_written_ += n;
    return ok_status();
  }
  Status flush() override {
    if (file_ != nullptr) sf_write_sync(file_);
    return ok_status();
  }
  Status close() override {
    if (file_ == nullptr) return ok_status();
    sf_write_sync(file_);
    const int rc = sf_close(file_);
    file_ = nullptr;
    if (rc != 0)
      return make_error(ErrorCode::kIoError, "{}: close failed: {}", entry_.file,
                        sf_error_number(rc));
    return ok_status();
  }

 private:
  int64_t stamp_of(int64_t sample) const {
    const int64_t sr = entry_.sample_rate;
    return start_ns_ + (sample / sr) * 1000000000LL + (sample % sr) * 1000000000LL / sr;
  }
  static constexpr int64_t kMaxAudioJumpS = 60;
  std::function<Status(int64_t)> on_start_;
  SNDFILE* file_ = nullptr;
  int64_t frames_written_ = 0;
  int64_t gap_samples_ = 0, overlap_samples_ = 0;
  int64_t start_ns_ = 0;
  std::vector<int16_t> shorts_;
};

}  // namespace

Status SessionWriterOptions::check() const {
  std::vector<std::string> bad;
  if (jpeg_quality < 1 || jpeg_quality > 100)
    bad.push_back(fmt::format("jpeg_quality must be in [1, 100], got {}", jpeg_quality));
  if (png_compression < 0 || png_compression > 9)
    bad.push_back(fmt::format("png_compression must be in [0, 9], got {}", png_compression));
  if (flush_interval.ns() <= 0)
    bad.push_back(fmt::format("flush_interval must be > 0, got {} s", flush_interval.seconds()));
  if (bad.empty()) return ok_status();
  std::string msg = "SessionWriterOptions: ";
  for (size_t i = 0; i < bad.size(); ++i) msg += (i ? "; " : "") + bad[i];
  return make_error(ErrorCode::kInvalidArgument, std::move(msg));
}

struct SessionWriter::Impl {
  std::filesystem::path dir;
  SessionManifest manifest;
  SessionWriterOptions options;
  std::vector<std::unique_ptr<StreamWriter>> streams;
  Timestamp last_flush = Timestamp::unset();
  bool open = false;
  bool dir_synced = false;

  StreamWriter* find(const SensorId& id) {
    for (auto& s : streams)
      if (s->entry().id == id) return s.get();
    return nullptr;
  }
};

SessionWriter::SessionWriter() : impl_(std::make_unique<Impl>()) {}

SessionWriter::~SessionWriter() {
  if (impl_ && impl_->open) {
    if (auto st = close(); !st)
      log::error("session writer {}: {}", impl_->dir.string(), st.error().message);
  }
}

const std::filesystem::path& SessionWriter::dir() const { return impl_->dir; }

Result<std::unique_ptr<SessionWriter>> SessionWriter::create(
    const std::filesystem::path& session_dir, SessionManifest manifest,
    SessionWriterOptions options) {
  if (auto st = options.check(); !st) return tl::unexpected(st.error());
  manifest.format_version = kSessionFormatVersion;
  manifest.complete = false;
  for (const auto& s : manifest.streams)
    if (s.encoding == "video")
      return make_error(ErrorCode::kUnsupported,
                        "stream {}: encoding 'video' is read-only (record colour as mjpeg)", s.id);
  for (auto& s : manifest.streams) fill_stream_defaults(s);
  if (auto st = check_manifest(manifest); !st) return tl::unexpected(st.error());

  std::error_code ec;
  std::filesystem::create_directories(session_dir, ec);
  if (ec || !std::filesystem::is_directory(session_dir))
    return make_error(ErrorCode::kIoError, "{}: cannot create session folder: {}",
                      session_dir.string(), ec ? ec.message() : "not a directory");
  if (std::filesystem::exists(session_dir / kManifestName, ec))
    return make_error(ErrorCode::kInvalidArgument,
                      "{}: already contains a session ({}); refusing to overwrite it",
                      session_dir.string(), kManifestName);
  if (::access(session_dir.c_str(), W_OK) != 0)
    return make_error(ErrorCode::kIoError, "{}: session folder is not writable: {}",
                      session_dir.string(), errno_text(errno));

  std::unique_ptr<SessionWriter> w(new SessionWriter());
  Impl& impl = *w->impl_;
  impl.dir = session_dir;
  impl.manifest = std::move(manifest);
  impl.options = options;
  for (const auto& s : impl.manifest.streams) {
    std::unique_ptr<StreamWriter> sw;
    if (s.encoding == "mjpeg" || s.encoding == "raw16" || s.encoding == "png16") {
      sw = std::make_unique<IndexedWriter>(s, options);
    } else if (s.encoding == "jsonl") {
      sw = std::make_unique<SkeletonWriter>(s);
    } else {
      Impl* ip = &impl;
      const SensorId id = s.id;
      sw = std::make_unique<WavWriter>(s, [ip, id](int64_t start_ns) -> Status {
        for (auto& e : ip->manifest.streams)
          if (e.id == id) e.start_ns = start_ns;
        return write_manifest(ip->dir, ip->manifest);
      });
    }
    impl.streams.push_back(std::move(sw));
  }
  // Streams' files are created (empty) before the manifest, so a manifest on disk always
  // declares files that exist.
  for (auto& s : impl.streams)
    if (auto st = s->open(session_dir); !st) return tl::unexpected(st.error());
  if (auto st = write_manifest(session_dir, impl.manifest); !st) return tl::unexpected(st.error());
  impl.open = true;
  return w;
}

Status SessionWriter::write(const SensorFrame& frame) {
  Impl& impl = *impl_;
  if (!impl.open)
    return make_error(ErrorCode::kFailedPrecondition, "{}: session writer is closed",
                      impl.dir.string());
  StreamWriter* s = impl.find(frame.sensor);
  if (s == nullptr)
    return make_error(ErrorCode::kNotFound, "stream {}: not declared in the session manifest",
                      frame.sensor);
  if (auto st = s->write(frame); !st) return st;
  if (!impl.last_flush.is_set()) {
    // The first flush comes 0.25 s after the first frame, so a recording killed in its first
    // second still reads back; then one every flush_interval.
    impl.last_flush = frame.stamp - impl.options.flush_interval + Duration::from_ms(250);
  } else if (frame.stamp >= impl.last_flush + impl.options.flush_interval) {
    if (auto st = flush(); !st) return st;
    impl.last_flush = frame.stamp;
  }
  return ok_status();
}

Status SessionWriter::flush() {
  Impl& impl = *impl_;
  if (!impl.open) return ok_status();
  for (auto& s : impl.streams)
    if (auto st = s->flush(); !st) return st;
  if (!impl.dir_synced) {
    sync_dir(impl.dir);
    impl.dir_synced = true;
  }
  return ok_status();
}

Status SessionWriter::close() {
  Impl& impl = *impl_;
  if (!impl.open) return ok_status();
  impl.open = false;
  Status first = ok_status();
  for (auto& s : impl.streams) {
    auto st = s->close();
    if (!st && first) first = st;
  }
  if (!first) return first;
  sync_dir(impl.dir);
  impl.manifest.complete = true;
  return write_manifest(impl.dir, impl.manifest);
}

}  // namespace dreamsense::sources
