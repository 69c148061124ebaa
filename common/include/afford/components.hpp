// The registry of a component's kinds (motivation.kind, predictors.affordance.kind):
// the shipped kinds first, then those a process of one's own registers before
// it starts (docs/writing-a-component.md). Thread-safe: runs hosted in one
// process make their components side by side.
#pragma once
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "afford/config.hpp"  // ConfigError

namespace afford {

// Params: what a component is given of the run's configuration (its own section; motivation/component.hpp's
// MotivationParams, predictors/affordance.hpp's AffordanceParams).
template <class Component, class Params>
class ComponentRegistry {
 public:
  using Factory = std::function<std::unique_ptr<Component>(const Params&)>;

  // `key`: the config key that picks the kind; `process`: the process whose component it is.
  ComponentRegistry(std::string key, std::string process, std::vector<std::pair<std::string, Factory>> shipped)
      : key_(std::move(key)), process_(std::move(process)), kinds_(std::move(shipped)) {}

  // Make `kind` available (a kind registered again is replaced).
  void add(const std::string& kind, Factory factory) {
    std::lock_guard<std::mutex> lock(mutex_);
    for (auto& [name, f] : kinds_)
      if (name == kind) {
        f = std::move(factory);
        return;
      }
    kinds_.emplace_back(kind, std::move(factory));
  }

  std::vector<std::string> kinds() const {
    std::lock_guard<std::mutex> lock(mutex_);
    std::vector<std::string> out;
    for (const auto& [name, f] : kinds_) out.push_back(name);
    return out;
  }

  // The component of `kind`; throws ConfigError naming the key, the kinds known and how to run one's own.
  std::unique_ptr<Component> make(const Params& params, const std::string& kind) const {
    Factory factory;
    std::string known;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      for (const auto& [name, f] : kinds_) {
        known += (known.empty() ? "" : ", ") + name;
        if (name == kind) factory = f;
      }
    }
    if (!factory)
      throw ConfigError("config key '" + key_ + "': '" + kind + "' is not one of the kinds built into this process (" +
                        known + "); a component of one's own runs in a process of its own: --process " + process_ +
                        "='COMMAND' (docs/writing-a-component.md)");
    return factory(params);
  }

 private:
  mutable std::mutex mutex_;
  std::string key_, process_;
  std::vector<std::pair<std::string, Factory>> kinds_;
};

}  // namespace afford
