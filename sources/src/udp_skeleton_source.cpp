#include "dreamsense/sources/udp_skeleton_source.hpp"

#include "dreamsense/core/log.hpp"
#include "dreamsense/sources/skeleton_json.hpp"

#include <arpa/inet.h>
#include <atomic>
#include <cerrno>
#include <cstring>
#include <mutex>
#include <netinet/in.h>
#include <poll.h>
#include <string_view>
#include <sys/socket.h>
#include <unistd.h>
#include <vector>

namespace dreamsense::sources {

Status UdpSkeletonSourceOptions::check() const {
  std::string bad;
  if (sensor.empty()) bad += " sensor must not be empty;";
  if (port < 0 || port > 65535) bad += " port must be in [0, 65535];";
  if (!(rate_hz > 0)) bad += " rate_hz must be > 0;";
  in_addr a{};
  if (inet_pton(AF_INET, host.c_str(), &a) != 1) bad += " host must be an IPv4 address;";
  if (!bad.empty())
    return make_error(ErrorCode::kInvalidArgument, "UdpSkeletonSourceOptions:{}", bad);
  return ok_status();
}

struct UdpSkeletonSource::Impl {
  UdpSkeletonSourceOptions options;
  int fd = -1;
  int port = 0;
  std::atomic<bool> stopped{false};
  uint64_t sequence = 0;
  mutable std::mutex mutex;  // stats
  UdpSkeletonStats stats;
  ~Impl() {
    if (fd >= 0) ::close(fd);
  }
};

UdpSkeletonSource::UdpSkeletonSource(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
UdpSkeletonSource::~UdpSkeletonSource() = default;

Result<std::unique_ptr<UdpSkeletonSource>> UdpSkeletonSource::open(
    const UdpSkeletonSourceOptions& options) {
  if (auto s = options.check(); !s) return tl::unexpected(s.error());
  auto m = std::make_unique<Impl>();
  m->options = options;
  m->fd = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (m->fd < 0)
    return make_error(ErrorCode::kIoError, "{}: cannot create a UDP socket: {}", options.sensor,
                      std::strerror(errno));
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(static_cast<uint16_t>(options.port));
  inet_pton(AF_INET, options.host.c_str(), &addr.sin_addr);
  if (::bind(m->fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0)
    return make_error(ErrorCode::kIoError, "{}: cannot listen on udp {}:{}: {}", options.sensor,
                      options.host, options.port, std::strerror(errno));
  socklen_t len = sizeof addr;
  ::getsockname(m->fd, reinterpret_cast<sockaddr*>(&addr), &len);
  m->port = ntohs(addr.sin_port);
  if (options.host != "127.0.0.1")
    log::warn("{}: skeleton input listens on {}:{} (not only this machine)", options.sensor,
              options.host, m->port);
  return std::unique_ptr<UdpSkeletonSource>(new UdpSkeletonSource(std::move(m)));
}

Result<FramePtr> UdpSkeletonSource::next() {
  Impl& m = *impl_;
  std::vector<char> buffer(65536);
  while (!m.stopped) {
    pollfd p{m.fd, POLLIN, 0};
    const int ready = ::poll(&p, 1, 100);  // wake up to see stop()
    if (ready < 0 && errno != EINTR)
      return make_error(ErrorCode::kIoError, "{}: poll: {}", m.options.sensor,
                        std::strerror(errno));
    if (ready <= 0) continue;
    const ssize_t n = ::recv(m.fd, buffer.data(), buffer.size(), 0);
    if (n <= 0) continue;
    const auto arrived = std::chrono::steady_clock::now();
    auto parsed = parse_skeleton_json(std::string_view(buffer.data(), static_cast<size_t>(n)));
    if (!parsed) {
      uint64_t bad = 0;
      {
        std::lock_guard lock(m.mutex);
        bad = ++m.stats.bad_datagrams;
      }
      if (bad <= 3)
        log::warn("{}: skeleton datagram skipped: {}{}", m.options.sensor, parsed.error().message,
                  bad == 3 ? " (further ones are counted only)" : "");
      continue;
    }
    {
      std::lock_guard lock(m.mutex);
      ++m.stats.frames;
    }
    const auto stamp = Timestamp::from_ns(
        std::chrono::duration_cast<std::chrono::nanoseconds>(arrived - m.options.clock_origin)
            .count());
    return make_frame(m.options.sensor, stamp, m.sequence++, std::move(parsed->skeleton));
  }
  return make_error(ErrorCode::kEndOfStream, "{}: skeleton input stopped", m.options.sensor);
}

SourceInfo UdpSkeletonSource::info() const {
  SourceInfo i;
  i.live = true;
  SensorDescription d;
  d.id = impl_->options.sensor;
  d.kind = SensorKind::kSkeleton;
  d.rate_hz = impl_->options.rate_hz;
  d.frame = impl_->options.sensor;
  i.sensors.push_back(d);
  return i;
}

void UdpSkeletonSource::stop() { impl_->stopped = true; }
int UdpSkeletonSource::port() const { return impl_->port; }
UdpSkeletonStats UdpSkeletonSource::stats() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->stats;
}

}  // namespace dreamsense::sources
