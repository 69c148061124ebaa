// summary-roundtrip DIR...: each folder's summary.json (a sweep's, and each
// of its conditions') read through the structure of summary.json
// (experiment/schema/summary.hpp) and written back gives the same JSON, key
// for key and number for number (an integer stays an integer). Exit 1 naming
// what differs, or what the structure refused.
#include <cstdio>
#include <filesystem>
#include <string>

#include "experiment/schema/summary.hpp"

namespace {

using nlohmann::json;

bool same(const json& original, const json& again, const std::string& what) {
  if (original.dump() == again.dump()) return true;
  for (const auto& op : json::diff(original, again)) {
    std::printf("%s: written back differs at %s (%s)\n", what.c_str(), op["path"].get<std::string>().c_str(),
                op["op"].get<std::string>().c_str());
    break;
  }
  return false;
}

}  // namespace

int main(int argc, char** argv) {
  int failed = 0;
  for (int i = 1; i < argc; ++i) {
    const std::string dir = argv[i];
    try {
      const json j = afford::readSummaryJson(dir);
      const std::string file = (std::filesystem::path(dir) / "summary.json").string();
      const json again = afford::isSweepSummary(j) ? afford::toJson(afford::sweepSummaryFromJson(j, file))
                                                   : afford::toJson(afford::summaryFromJson(j, file));
      if (!same(j, again, file)) failed = 1;
    } catch (const afford::SummaryError& e) {
      std::printf("%s\n", e.what());
      failed = 1;
    }
  }
  return failed;
}
