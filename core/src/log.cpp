#include "dreamsense/core/log.hpp"

#include <spdlog/sinks/stdout_color_sinks.h>

namespace dreamsense::log {

spdlog::logger& logger() {
  static std::shared_ptr<spdlog::logger> instance = [] {
    auto l = spdlog::stderr_color_mt("dreamsense");
    l->set_pattern("%^[%l]%$ %v");
    l->set_level(spdlog::level::info);
    return l;
  }();
  return *instance;
}

void set_level(Level level) {
  switch (level) {
    case Level::kDebug:
      logger().set_level(spdlog::level::debug);
      break;
    case Level::kInfo:
      logger().set_level(spdlog::level::info);
      break;
    case Level::kWarn:
      logger().set_level(spdlog::level::warn);
      break;
    case Level::kError:
      logger().set_level(spdlog::level::err);
      break;
    case Level::kOff:
      logger().set_level(spdlog::level::off);
      break;
  }
}

}  // namespace dreamsense::log
