// What a logger said, line by line, for tests of what is logged (the edge's drops, the key hints, the runner's
// silences): a logger whose lines are the messages alone, kept in memory.
#pragma once
#include <spdlog/sinks/ostream_sink.h>
#include <spdlog/spdlog.h>

#include <cstdint>
#include <memory>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

namespace afford::test {

struct Said {
  std::ostringstream text;
  std::shared_ptr<spdlog::logger> log = [this] {
    auto l = std::make_shared<spdlog::logger>("said", std::make_shared<spdlog::sinks::ostream_sink_st>(text));
    l->set_pattern("%v");
    return l;
  }();
  std::vector<std::string> lines() const {
    std::vector<std::string> out;
    std::istringstream in(text.str());
    for (std::string line; std::getline(in, line);) out.push_back(line);
    return out;
  }
  int count(const std::string& part) const {  // lines holding `part`
    int n = 0;
    for (const auto& l : lines()) n += l.find(part) != std::string::npos;
    return n;
  }
  int starting(const std::string& part) const {  // lines beginning with `part`
    int n = 0;
    for (const auto& l : lines()) n += l.rfind(part, 0) == 0;
    return n;
  }
  // The drops counted in the summaries of drops ("dropped N more message(s) ...", afford/drop_log.hpp).
  std::int64_t summarised() const {
    std::int64_t n = 0;
    const std::regex summary(R"(^dropped (\d+) more message)");
    for (const auto& line : lines()) {
      std::smatch m;
      if (std::regex_search(line, m, summary)) n += std::stoll(m[1]);
    }
    return n;
  }
  // The drops the lines account for: one each said alone, and the counts of the summaries.
  std::int64_t accounted() const { return summarised() + count(": dropped message: "); }
};

}  // namespace afford::test
