// Names that arrive from outside (a message, a log, a command line) and name
// something on disk. A run id names the run's folder (logs/<run-id>/), the
// files in it and the viewer's frames, so one that could climb out of a folder
// or be mistaken for something else is refused wherever it arrives: at the
// edge (every message's run_id), in the runner, the logger, the predictors and
// the viewer. A safe run id is 1 to max_bytes bytes of letters, digits, '.',
// '_' and '-', and does not begin with '.' (so it is never "." or "..", never
// hidden) or '-' (never an option of a command it is given to).
#pragma once
#include <filesystem>
#include <string>

namespace afford {

// "" if `id` is a safe run id of at most `max_bytes` bytes, else why not.
std::string runIdProblem(const std::string& id, int max_bytes);
inline bool safeRunId(const std::string& id, int max_bytes) { return runIdProblem(id, max_bytes).empty(); }

// `text` for a log line or a terminal: bytes outside printable ASCII as \xNN,
// at most `max_bytes` of it (then "..."): a name from a message cannot move
// the cursor or hide what follows it.
std::string printable(const std::string& text, std::size_t max_bytes = 200);

// Is `path` (made absolute, with "." and ".." and symbolic links of the part
// that exists resolved) inside the folder `root` (resolved the same way)?
bool insideFolder(const std::filesystem::path& path, const std::filesystem::path& root);

// "1 step", "3 steps": a count and its noun (a regular plural) for a line a person reads.
inline std::string counted(long long n, const std::string& noun) {
  return std::to_string(n) + " " + noun + (n == 1 ? "" : "s");
}

}  // namespace afford
