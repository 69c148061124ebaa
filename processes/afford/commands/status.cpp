// afford status: list the processes heard on a bus (pid, state, run, last step).
#include <lcm/lcm-cpp.hpp>

#include <chrono>
#include <cstdio>
#include <map>
#include <memory>
#include <sstream>

#include "afford/commands.hpp"
#include "afford/config.hpp"
#include "afford/edge.hpp"
#include "afford/logging.hpp"
#include "afford/process_status_t.hpp"

namespace afford {

Command statusCommand(CLI::App& app, const FrontDoor& door) {
  struct Args {
    std::string url = "udpm://239.255.76.67:7667?ttl=0", wait, state;
    double seconds = 1.5;
  };
  auto a = std::make_shared<Args>();
  auto* status = app.add_subcommand("status", "list the processes heard on a bus: pid, state, run, last step");
  status->add_option("--lcm-url", a->url, "the bus")->capture_default_str();
  status->add_option("--seconds", a->seconds, "how long to listen (processes report every 0.5 s)")
      ->capture_default_str();
  status->add_option("--wait-for", a->wait,
                     "processes, comma-separated: list as soon as each has been heard (with --state: in that "
                     "state); --seconds is then the deadline, and missing it exits 1");
  status->add_option("--state", a->state, "with --wait-for: the state to wait for")
      ->check(CLI::IsMember({"waiting", "ready", "running", "done", "failed"}));
  return {status, [a, &door] {
            lcm::LCM bus(a->url);
            if (!bus.good()) throw std::runtime_error("cannot open LCM at " + a->url);
            std::map<std::string, process_status_t> heard;  // process#pid -> its last STATUS
            Edge edge(bus, makeLogger("status", "warn"), "status", loadProtocol(door.config_dir));
            edge.subscribe<process_status_t>(
                "STATUS",
                [&heard](const process_status_t& m) {
                  heard[m.process + "#" + std::to_string(m.pid)] = m;
                  return Turn::take();
                },
                Scope::Any, Order::None);
            const char* states[] = {"waiting", "ready", "running", "done", "failed"};
            std::vector<std::string> awaited;
            std::stringstream names(a->wait);
            for (std::string p; std::getline(names, p, ',');)
              if (!p.empty()) awaited.push_back(p);
            auto allHeard = [&] {  // each awaited process's latest STATUS (any pid) says the state asked for
              for (const auto& p : awaited) {
                bool ok = false;
                for (const auto& [key, m] : heard)
                  ok = ok || (m.process == p && (a->state.empty() || a->state == states[m.state]));
                if (!ok) return false;
              }
              return true;
            };
            const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(a->seconds);
            while (std::chrono::steady_clock::now() < until && !(awaited.size() && allHeard())) bus.handleTimeout(50);
            std::printf("%-12s %8s  %-8s %10s  %s\n", "process", "pid", "state", "last step", "run");
            for (const auto& [key, m] : heard)
              std::printf("%-12s %8d  %-8s %10lld  %s%s%s\n", m.process.c_str(), m.pid, states[m.state],
                          static_cast<long long>(m.step), m.run_id.empty() ? "-" : m.run_id.c_str(),
                          m.detail.empty() ? "" : "  ", m.detail.c_str());
            if (heard.empty()) std::printf("(no process heard on %s in %.1f s)\n", a->url.c_str(), a->seconds);
            if (!awaited.empty() && !allHeard()) {
              std::fprintf(stderr, "afford status: not every one of %s was heard%s within %.1f s on %s\n",
                           a->wait.c_str(), a->state.empty() ? "" : (" " + a->state).c_str(), a->seconds,
                           a->url.c_str());
              return 1;
            }
            return 0;
          }};
}

}  // namespace afford
