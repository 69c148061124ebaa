// afford status: list the processes heard on a bus (pid, state, run, last step).
#include <lcm/lcm-cpp.hpp>

#include <spdlog/fmt/fmt.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <map>
#include <memory>
#include <sstream>

#include "afford/bus.hpp"
#include "apps/afford/commands.hpp"
#include "afford/config.hpp"
#include "afford/edge.hpp"
#include "afford/edge_peers.hpp"
#include "afford/logging.hpp"
#include "afford/names.hpp"
#include "afford/process_status_t.hpp"
#include "experiment/run/runners.hpp"

namespace afford {

namespace {

using Heard = std::map<std::string, std::pair<process_status_t, std::uint64_t>>;  // process#instance -> STATUS, order

// A process expected on the bus (--expect NAME[:PID]): pid 0 for any.
struct Expected {
  std::string process;
  int pid = 0;
};

// "NAME[:PID],...", as --wait-for and --expect take them.
std::vector<Expected> expectedOf(const std::string& list, const char* option) {
  std::vector<Expected> out;
  std::stringstream names(list);
  for (std::string e; std::getline(names, e, ',');) {
    if (e.empty()) continue;
    const auto colon = e.find(':');
    Expected x{e.substr(0, colon), 0};
    if (colon != std::string::npos) {
      try {
        std::size_t used = 0;
        x.pid = std::stoi(e.substr(colon + 1), &used);
        if (used != e.size() - colon - 1 || x.pid <= 0) throw std::invalid_argument("pid");
      } catch (const std::exception&) {
        throw ConfigError(std::string(option) + " '" + e + "': give NAME or NAME:PID (a pid above 0)");
      }
    }
    out.push_back(x);
  }
  return out;
}

// Expected processes not heard: silent (paused, stuck, or on another bus).
std::vector<Expected> silentOnes(const std::vector<Expected>& expected, const Heard& heard) {
  std::vector<Expected> silent;
  for (const Expected& e : expected) {
    bool found = false;
    for (const auto& [id, entry] : heard)
      found = found || (entry.first.process == e.process && (e.pid == 0 || entry.first.pid == e.pid));
    if (!found) silent.push_back(e);
  }
  return silent;
}

// Copies of one program heard (the same name from two or more pids or hosts, each saying its host), and whom
// each names: the later of two copies that hear each other refuses to serve (a runner: is refused). A few lines
// at most, each naming a few: a flood of made-up STATUS is counted, not listed.
void printCopies(const Heard& heard) {
  constexpr std::size_t kLines = 8, kNames = 4;
  std::map<std::string, std::vector<const process_status_t*>> by_name;
  for (const auto& [id, entry] : heard)
    if (!entry.first.host.empty()) by_name[entry.first.process].push_back(&entry.first);
  std::vector<std::string> lines;
  const auto some = [&](const std::vector<std::string>& names) {
    std::string said;
    for (std::size_t i = 0; i < names.size() && i < kNames; ++i) said += (i ? ", " : "") + names[i];
    return names.size() > kNames ? said + " and " + std::to_string(names.size() - kNames) + " more" : said;
  };
  for (const auto& [name, all] : by_name) {
    if (all.size() < 2) continue;
    std::vector<std::string> who;
    for (const process_status_t* m : all) who.push_back(printable(Instance::of(*m).text(), 300));
    lines.push_back(fmt::format("{} copies of {} heard: {}; of two that hear each other, the later started {}",
                                all.size(), printable(name, 64), some(who),
                                name == kRunnerName ? "is refused" : "refuses to serve"));
    for (std::size_t k = 0; k < all.size(); ++k) {
      if (all[k]->copies.empty()) continue;
      std::vector<std::string> named;
      for (const std::string& copy : all[k]->copies) named.push_back(printable(instanceText(copy), 300));
      lines.push_back(fmt::format("  {} ({}) names: {}", printable(name, 64), who[k], some(named)));
    }
  }
  for (std::size_t i = 0; i < lines.size() && i < kLines; ++i) std::printf("%s\n", lines[i].c_str());
  if (lines.size() > kLines) std::printf("(and %zu more lines about copies)\n", lines.size() - kLines);
}

// The table of processes heard, and of those expected but not heard. Columns as wide as what they hold; "detail":
// what a process adds (the logger: its log's state; the runner: what it waits for). What a message says is
// printed as text only: no byte of it reaches the terminal as a control.
void printHeard(const Heard& heard, const std::vector<Expected>& silent, double seconds) {
  const char* states[] = {"waiting", "ready", "running", "done", "failed"};
  int run_width = 3;
  bool any_detail = !silent.empty();
  for (const auto& [id, entry] : heard) {
    run_width = std::max(run_width, static_cast<int>(printable(entry.first.run_id, 200).size()));
    any_detail = any_detail || !entry.first.detail.empty();
  }
  const auto line = [&](std::string text) {  // without trailing blanks
    text.erase(text.find_last_not_of(' ') + 1);
    std::printf("%s\n", text.c_str());
  };
  line(fmt::format("{:<12} {:>8}  {:<8} {:>10}  {:<{}}  {}", "process", "pid", "state", "last step", "run",
                   run_width, any_detail ? "detail" : ""));
  for (const auto& [id, entry] : heard) {
    const process_status_t& m = entry.first;
    line(fmt::format("{:<12} {:>8}  {:<8} {:>10}  {:<{}}  {}", printable(m.process, 64), m.pid,
                     states[m.state], m.step, m.run_id.empty() ? "-" : printable(m.run_id, 200), run_width,
                     printable(m.detail, 400)));
  }
  for (const Expected& e : silent)
    line(fmt::format("{:<12} {:>8}  {:<8} {:>10}  {:<{}}  {}", e.process, e.pid ? std::to_string(e.pid) : "-",
                     "silent", "-", "-", run_width,
                     fmt::format("not heard in {:.1f} s (paused, stuck, or on another bus)", seconds)));
}

// What the table does not say: what stands in a process's way, copies, what was not listed or was dropped.
void printNotes(const Heard& heard, std::int64_t forgotten, int peers, const EdgeDrops& drops) {
  // What stands in a process's way, if it said (its next message refused since it last took one: a stall's cause).
  for (const auto& [id, entry] : heard)
    if (!entry.first.stuck.empty())
      std::printf("%s (pid %d) cannot take %s\n", printable(entry.first.process, 64).c_str(), entry.first.pid,
                  printable(entry.first.stuck, 400).c_str());
  printCopies(heard);
  if (forgotten > 0)
    std::printf("(and %lld more process ids heard, beyond protocol.limits.peers = %d: not listed)\n",
                static_cast<long long>(forgotten), peers);
  if (const std::string key = drops.key.said(); !key.empty()) std::printf("(%s)\n", key.c_str());
  if (const std::int64_t other = drops.untagged - drops.key.untagged - drops.key.other_key; other > 0)
    std::printf("(%lld messages without a valid tag of the bus's key dropped)\n", static_cast<long long>(other));
  if (drops.replayed > 0)
    std::printf("(%lld messages said again dropped: taken already, or a recording's)\n",
                static_cast<long long>(drops.replayed));
}

}  // namespace

Command statusCommand(CLI::App& app, const FrontDoor& door) {
  struct Args {
    std::string url = "udpm://239.255.76.67:7667?ttl=0", wait, state, bus_key, expect;
    double seconds = 1.5;
    std::int64_t step = -1;
  };
  auto a = std::make_shared<Args>();
  auto* status = app.add_subcommand("status", "list the processes heard on a bus: pid, state, run, last step");
  status->add_option("--lcm-url", a->url, "the bus")->capture_default_str();
  status->add_option("--seconds", a->seconds, "how long to listen (processes report every 0.5 s)")
      ->capture_default_str();
  status->add_option("--wait-for", a->wait,
                     "processes, comma-separated, each NAME or NAME:PID (that pid's STATUS only): list as soon as "
                     "each has been heard (with --state: in that state); --seconds is then the deadline, and "
                     "missing it exits 1");
  status->add_option("--state", a->state, "with --wait-for: the state to wait for")
      ->check(CLI::IsMember({"waiting", "ready", "running", "done", "failed"}));
  status->add_option("--step", a->step, "with --wait-for: until each has handled this step (or a later one)");
  status->add_option("--expect", a->expect,
                     "processes expected on the bus, comma-separated, each NAME or NAME:PID: one not heard is "
                     "listed as silent");
  status->add_option("--bus-key", a->bus_key,
                     "key file of a keyed bus (default: the file $AFFORD_BUS_KEY names; none: untagged)");
  return {status, [a, &door] {
            const ProtocolConfig protocol = loadProtocol(door.config_dir);
            const std::shared_ptr<const BusKey> key = busKeyFrom(a->bus_key);
            const std::unique_ptr<lcm::LCM> lcm = openBus(a->url, protocol.bus);
            lcm::LCM& bus = *lcm;
            // process#pid -> its last STATUS, and when it was heard; at most protocol.limits.peers of them
            // (the one heard from longest ago is forgotten: forged pids cannot grow it).
            Heard heard;
            std::uint64_t order = 0;
            std::int64_t forgotten = 0;
            Edge edge(bus, makeLogger("status", "warn"), "status", protocol);
            edge.useKey(key);
            edge.subscribe(
                ch::status,
                [&](const process_status_t& m) {
                  const std::string id = m.process + "#" + Instance::of(m).id();
                  if (!heard.count(id) && heard.size() >= static_cast<std::size_t>(protocol.limits.peers)) {
                    heard.erase(std::min_element(heard.begin(), heard.end(), [](const auto& x, const auto& y) {
                      return x.second.second < y.second.second;
                    }));
                    ++forgotten;
                  }
                  heard[id] = {m, ++order};
                  return Turn::take();
                },
                Scope::Any, Order::None);
            const char* states[] = {"waiting", "ready", "running", "done", "failed"};
            const std::vector<Expected> awaited = expectedOf(a->wait, "--wait-for");
            auto allHeard = [&] {  // each awaited process's latest STATUS (any pid, or its) says the state asked for
              for (const Expected& p : awaited) {
                bool ok = false;
                for (const auto& [id, entry] : heard) {
                  const process_status_t& m = entry.first;
                  ok = ok || (m.process == p.process && (a->state.empty() || a->state == states[m.state]) &&
                              m.step >= a->step && (p.pid == 0 || m.pid == p.pid));
                }
                if (!ok) return false;
              }
              return true;
            };
            const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(a->seconds);
            while (std::chrono::steady_clock::now() < until && !(awaited.size() && allHeard())) pumpBus(bus, 50);
            printHeard(heard, silentOnes(expectedOf(a->expect, "--expect"), heard), a->seconds);
            printNotes(heard, forgotten, protocol.limits.peers, edge.drops());
            if (heard.empty()) std::printf("(no process heard on %s in %.1f s)\n", a->url.c_str(), a->seconds);
            if (!awaited.empty() && !allHeard()) {
              std::fprintf(stderr, "afford status: not every one of %s was heard%s%s within %.1f s on %s\n",
                           a->wait.c_str(), a->state.empty() ? "" : (" " + a->state).c_str(),
                           a->step < 0 ? "" : (" at step " + std::to_string(a->step)).c_str(), a->seconds,
                           a->url.c_str());
              return 1;
            }
            return 0;
          }};
}

}  // namespace afford
