// Where an afford build finds what it ships (afford/process_main.hpp): apart from the processes' main, so that
// what reads configurations (config.cpp, migrations.cpp) needs nothing else.
#include <cstdlib>
#include <filesystem>
#include <string>

#include "afford/process_main.hpp"

namespace afford {

std::string installedShareDir() {
  std::error_code ec;
  const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (ec) return "";
  const std::filesystem::path share = exe.parent_path().parent_path() / "share" / "afford";
  return std::filesystem::is_regular_file(share / "config" / "defaults.yaml", ec) ? share.string() : "";
}

std::string defaultConfigDir() {
  const std::string share = installedShareDir();
  return share.empty() ? std::string(AFFORD_SOURCE_DIR) + "/config" : share + "/config";
}

std::string defaultLogRoot() {
  const char* env = std::getenv("AFFORD_LOGS");
  return env && *env ? std::string(env) : std::string("logs");
}

}  // namespace afford
