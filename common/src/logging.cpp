#include "afford/logging.hpp"

#include <spdlog/sinks/stdout_color_sinks.h>

#include <stdexcept>

namespace afford {

spdlog::level::level_enum parseLevel(const std::string& level) {
  for (int l = spdlog::level::trace; l <= spdlog::level::off; ++l) {
    const auto e = static_cast<spdlog::level::level_enum>(l);
    if (spdlog::level::to_string_view(e) == level) return e;
  }
  if (level == "warn") return spdlog::level::warn;
  throw std::invalid_argument("unknown log level \"" + level + "\" (trace, debug, info, warn, error, off)");
}

std::mutex& consoleMutex() { return spdlog::details::console_mutex::mutex(); }

std::shared_ptr<spdlog::logger> makeLogger(const std::string& name, const std::string& level) {
  static auto sink = std::make_shared<spdlog::sinks::stderr_color_sink_mt>();
  auto logger = std::make_shared<spdlog::logger>(name, sink);
  logger->set_level(parseLevel(level));
  logger->set_pattern("[%H:%M:%S.%e] [%n] [%^%l%$] %v");
  return logger;
}

}  // namespace afford
