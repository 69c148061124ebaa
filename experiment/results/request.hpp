// What writes an experiment's results: its folder and what is said on the
// console.
#pragma once
#include <string>

namespace afford {

struct WriteRequest {
  std::string out_dir = "out";     // summary.json, the CSV files, the kept outcomes (DIR/runs/)
  bool quiet = false;              // no table at the end
  bool replace = false;            // a finished experiment in out_dir is removed first (else: refused)
  std::string program = "afford";  // how the command was called (in the resume command it prints)
};

}  // namespace afford
