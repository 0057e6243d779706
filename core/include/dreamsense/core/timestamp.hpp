#pragma once
// Time in dreamsense: int64 nanoseconds on the session clock (from the sensor or the recording,
// never the wall clock during replay). Duration and Timestamp are distinct strong types so that
// "stamp + stamp" does not compile.

#include <compare>
#include <cstdint>
#include <limits>
#include <string>

namespace dreamsense {

class Duration {
 public:
  constexpr Duration() = default;
  static constexpr Duration from_ns(int64_t ns) { return Duration(ns); }
  static constexpr Duration from_us(int64_t us) { return Duration(us * 1000); }
  static constexpr Duration from_ms(int64_t ms) { return Duration(ms * 1000000); }
  // Rounds to the nearest nanosecond.
  static constexpr Duration from_seconds(double s) {
    return Duration(static_cast<int64_t>(s * 1e9 + (s >= 0 ? 0.5 : -0.5)));
  }
  constexpr int64_t ns() const { return ns_; }
  constexpr double seconds() const { return static_cast<double>(ns_) * 1e-9; }
  constexpr double ms() const { return static_cast<double>(ns_) * 1e-6; }

  constexpr auto operator<=>(const Duration&) const = default;
  constexpr Duration operator+(Duration o) const { return Duration(ns_ + o.ns_); }
  constexpr Duration operator-(Duration o) const { return Duration(ns_ - o.ns_); }
  constexpr Duration operator-() const { return Duration(-ns_); }
  constexpr Duration operator*(int64_t k) const { return Duration(ns_ * k); }
  constexpr Duration operator/(int64_t k) const { return Duration(ns_ / k); }
  constexpr int64_t operator/(Duration o) const { return ns_ / o.ns_; }
  constexpr Duration& operator+=(Duration o) {
    ns_ += o.ns_;
    return *this;
  }
  constexpr Duration& operator-=(Duration o) {
    ns_ -= o.ns_;
    return *this;
  }
  constexpr Duration abs() const { return Duration(ns_ < 0 ? -ns_ : ns_); }

 private:
  constexpr explicit Duration(int64_t ns) : ns_(ns) {}
  int64_t ns_ = 0;
};

class Timestamp {
 public:
  // A default-constructed Timestamp is unset(); comparisons with it are well defined (it is the
  // smallest value) but callers should test is_set() first.
  constexpr Timestamp() = default;
  static constexpr Timestamp from_ns(int64_t ns) { return Timestamp(ns); }
  static constexpr Timestamp from_seconds(double s) {
    return Timestamp(Duration::from_seconds(s).ns());
  }
  // Named specials (MediaPipe's idea): before/after every real stamp of a stream.
  static constexpr Timestamp unset() { return Timestamp(kUnsetNs); }
  static constexpr Timestamp pre_stream() { return Timestamp(kUnsetNs + 1); }
  static constexpr Timestamp post_stream() {
    return Timestamp(std::numeric_limits<int64_t>::max());
  }

  constexpr int64_t ns() const { return ns_; }
  constexpr double seconds() const { return static_cast<double>(ns_) * 1e-9; }
  constexpr bool is_set() const { return ns_ != kUnsetNs; }
  constexpr bool is_special() const {
    return ns_ == kUnsetNs || ns_ == kUnsetNs + 1 || ns_ == std::numeric_limits<int64_t>::max();
  }

  constexpr auto operator<=>(const Timestamp&) const = default;
  constexpr Timestamp operator+(Duration d) const { return Timestamp(ns_ + d.ns()); }
  constexpr Timestamp operator-(Duration d) const { return Timestamp(ns_ - d.ns()); }
  constexpr Duration operator-(Timestamp o) const { return Duration::from_ns(ns_ - o.ns_); }
  constexpr Timestamp& operator+=(Duration d) {
    ns_ += d.ns();
    return *this;
  }

  // "12.345678901s", or "unset" / "pre_stream" / "post_stream".
  std::string to_string() const;

 private:
  static constexpr int64_t kUnsetNs = std::numeric_limits<int64_t>::min();
  constexpr explicit Timestamp(int64_t ns) : ns_(ns) {}
  int64_t ns_ = kUnsetNs;
};

// Period of a stream at `hz` frames per second, rounded to the nanosecond.
constexpr Duration period_from_rate(double hz) { return Duration::from_seconds(1.0 / hz); }

}  // namespace dreamsense
