#include "experiment/schema/summary.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <type_traits>

namespace afford {

double meanAbsError(const SummaryTable& a, const SummaryTable& b) {
  double sum = 0;
  int n = 0;
  if (a.size() != b.size()) return std::nan("");
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (a[i].size() != b[i].size()) return std::nan("");
    for (std::size_t j = 0; j < a[i].size(); ++j, ++n) sum += std::abs(a[i][j] - b[i][j]);
  }
  return n ? sum / n : 0.0;
}
using nlohmann::json;

// The two types summary.json spells its own way (found by argument-dependent lookup from the codec).
json out(const MultiStep& m) { return m.all ? json("all") : json(m.count); }

json out(const CompletionSteps& c) {
  json j = json::object();
  for (const auto& [scenario, steps] : c.scenarios) j[scenario] = codec::out(steps);
  if (c.fit) j["fit"] = codec::out(*c.fit);
  return j;
}

void in(const json& j, const std::string& path, const codec::Context& c, MultiStep& m) {
  if (j.is_string() && j.get<std::string>() == "all") {
    m = {true, 0};
  } else if (j.is_number_integer()) {
    m = {false, j.get<std::int64_t>()};
  } else {
    c.fail(path, "expected an integer or \"all\", got " + codec::kindOf(j));
  }
}

void in(const json& j, const std::string& path, const codec::Context& c, CompletionSteps& s) {
  if (!j.is_object()) c.fail(path, "expected a map, got " + codec::kindOf(j));
  for (const auto& [key, v] : j.items()) {
    if (key == "fit")
      codec::in(v, codec::join(path, key), c, s.fit.emplace());
    else
      codec::in(v, codec::join(path, key), c, s.scenarios[key]);
  }
}

namespace {

using codec::Context;

// Every table is objects x actions, and random tables' lists are one per table: what the readers index by.
void checkShapes(const Summary& s, const std::string& path, const Context& c) {
  const std::string at = path.empty() ? "" : path + ".";
  const auto table = [&](const SummaryTable& t, const std::string& key) {
    if (t.size() != s.objects.size())
      c.fail(at + key, std::to_string(t.size()) + " rows, not one per object (" + std::to_string(s.objects.size()) + ")");
    for (std::size_t i = 0; i < t.size(); ++i)
      if (t[i].size() != s.actions.size())
        c.fail(at + key + "[" + std::to_string(i) + "]",
               std::to_string(t[i].size()) + " entries, not one per action (" + std::to_string(s.actions.size()) + ")");
  };
  for (const auto& [sys, js] : s.systems) {
    const std::string sp = "systems." + sys + ".";
    for (const auto* t : {&js.target, &js.affordance, &js.affordance_min, &js.affordance_max})
      if (*t) table(**t, sp + (t == &js.target ? "target" : t == &js.affordance ? "affordance"
                                                          : t == &js.affordance_min ? "affordance_min" : "affordance_max"));
    for (std::size_t r = 0; r < js.runs.size(); ++r) {
      const std::string rp = sp + "runs[" + std::to_string(r) + "].";
      table(js.runs[r].affordance, rp + "affordance");
      if (js.runs[r].target) table(*js.runs[r].target, rp + "target");
    }
    if (js.curves) {
      if (js.curves->steps.size() != js.curves->mean.size())
        c.fail(at + sp + "curves.mean", "not one table per step of curves.steps");
      for (std::size_t k = 0; k < js.curves->mean.size(); ++k)
        table(js.curves->mean[k], sp + "curves.mean[" + std::to_string(k) + "]");
    }
  }
  if (s.random_tables) {
    const RandomTables& rt = *s.random_tables;
    const auto count = static_cast<std::size_t>(std::max<std::int64_t>(rt.count, 0));
    if (rt.tables.size() != count) c.fail(at + "random_tables.tables", "not one table per random_tables.count");
    if (rt.one_way_looks.size() != count) c.fail(at + "random_tables.one_way_looks", "not one list per table");
    for (std::size_t k = 0; k < rt.tables.size(); ++k) table(rt.tables[k], "random_tables.tables[" + std::to_string(k) + "]");
    for (const auto& [condition, systems] : rt.mae)
      for (const auto& [sys, e] : systems)
        if (e.per_table.size() != count)
          c.fail(at + "random_tables.mae." + condition + "." + sys + ".per_table", "not one value per table");
  }
}

template <class T>
T parse(const json& j, const std::string& what) {
  T value = fromJsonOf<T>(j, what);
  const Context c{what};
  if constexpr (std::is_same_v<T, Summary>) {
    checkShapes(value, "", c);
  } else {
    for (const auto& [name, condition] : value.conditions) checkShapes(condition, "conditions." + name, c);
  }
  return value;
}

}  // namespace

json toJson(const Summary& s) { return toJsonOf(s); }
json toJson(const SweepSummary& s) { return toJsonOf(s); }
json toJson(const Interruption& i) { return toJsonOf(i); }
Summary summaryFromJson(const json& j, const std::string& what) { return parse<Summary>(j, what); }
SweepSummary sweepSummaryFromJson(const json& j, const std::string& what) { return parse<SweepSummary>(j, what); }
bool isSweepSummary(const json& j) { return j.is_object() && j.contains("sweep"); }

json readSummaryJson(const std::string& dir, std::uintmax_t max_bytes) {
  const std::filesystem::path file = std::filesystem::path(dir) / "summary.json";
  // Checked before it is opened: opening a FIFO would wait for a writer.
  std::error_code ec;
  if (!std::filesystem::exists(file, ec))
    throw SummaryError("no summary.json in " + dir + " (is it an `afford experiment --out` folder?)");
  if (!std::filesystem::is_regular_file(file, ec)) throw SummaryError(file.string() + ": not a regular file");
  const std::uintmax_t size = std::filesystem::file_size(file, ec);
  if (ec) throw SummaryError(file.string() + ": cannot read its size (" + ec.message() + ")");
  if (size > max_bytes)
    throw SummaryError(file.string() + ": " + std::to_string(size) + " bytes, more than a summary holds (at most " +
                       std::to_string(max_bytes) + ")");
  std::ifstream f(file);
  if (!f) throw SummaryError(file.string() + ": cannot be read");
  json j;
  try {
    j = json::parse(f);
  } catch (const json::parse_error& e) {
    throw SummaryError(file.string() + ": not JSON (" + e.what() + ")");
  }
  if (!j.is_object()) throw SummaryError(file.string() + ": expected a map at the top, got " + codec::kindOf(j));
  return j;
}

Summary readSummary(const std::string& dir) {
  const json j = readSummaryJson(dir);
  const std::string file = (std::filesystem::path(dir) / "summary.json").string();
  if (isSweepSummary(j)) throw SummaryError(file + ": a sweep's summary (each condition's is in its own folder)");
  return summaryFromJson(j, file);
}

}  // namespace afford
