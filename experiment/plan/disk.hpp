// What an experiment will write to the disk, said before it runs (`afford
// experiment`, docs/operating.md "Disk"): the logs it keeps, the predictors'
// checkpoints, and the snapshots its runs hold while they go (each run's are
// removed at its end). Estimated from the messages of a step at the run's
// configuration (its image sizes, its first scene compressed), with an action
// at every step: an upper estimate, since a pass publishes no scene and no
// effect.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "experiment/plan/plan.hpp"

namespace afford {

struct DiskNeed {
  std::uint64_t logs = 0;          // every kept log
  std::uint64_t checkpoints = 0;   // the predictors' checkpoints kept (their plain size: deflated, far less)
  std::uint64_t snapshots = 0;     // while `jobs` runs go at once
  std::uint64_t log_step = 0;      // bytes a step adds to a log, at most (the largest run's)
  std::size_t kept_logs = 0;       // runs that keep their log
  std::int64_t longest = 0;        // steps of the longest run
  std::uint64_t total() const { return logs + checkpoints + snapshots; }
};

DiskNeed diskNeed(const std::vector<PlannedRun>& runs, int jobs);
// "4.4 GB", "120 MB", "310 KB".
std::string bytesText(std::uint64_t bytes);
// The line `afford experiment` says, and a warning if `free_bytes` is less than the need (else "").
std::string diskLine(const DiskNeed& need);
std::string diskWarning(const DiskNeed& need, std::uint64_t free_bytes, const std::string& where);

}  // namespace afford
