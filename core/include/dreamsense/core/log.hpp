#pragma once
// The one logging facade (spdlog underneath), to stderr. Libraries log through these functions
// only; executables set the level once. No names of participants in logs: ids only.

#include <spdlog/spdlog.h>

namespace dreamsense::log {

enum class Level { kDebug, kInfo, kWarn, kError, kOff };

void set_level(Level level);
spdlog::logger& logger();

template <typename... Args>
void debug(fmt::format_string<Args...> f, Args&&... args) {
  logger().debug(f, std::forward<Args>(args)...);
}
template <typename... Args>
void info(fmt::format_string<Args...> f, Args&&... args) {
  logger().info(f, std::forward<Args>(args)...);
}
template <typename... Args>
void warn(fmt::format_string<Args...> f, Args&&... args) {
  logger().warn(f, std::forward<Args>(args)...);
}
template <typename... Args>
void error(fmt::format_string<Args...> f, Args&&... args) {
  logger().error(f, std::forward<Args>(args)...);
}

}  // namespace dreamsense::log
