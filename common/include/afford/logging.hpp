// One spdlog logger per process, not registered globally so
// that several runs can host the same cores in one process (memq).
#pragma once
#include <spdlog/spdlog.h>

#include <memory>
#include <mutex>
#include <string>

namespace afford {

std::shared_ptr<spdlog::logger> makeLogger(const std::string& name, const std::string& level = "info");
// Parses "trace|debug|info|warn|error|off"; throws std::invalid_argument otherwise.
spdlog::level::level_enum parseLevel(const std::string& level);
// What the loggers' console sink holds while it writes a line (in several pieces): another writer of
// the console that must not land inside a line holds it too.
std::mutex& consoleMutex();

}  // namespace afford
