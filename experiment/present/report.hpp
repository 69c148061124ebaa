// `afford report DIR... --out FILE`: a markdown report of any set of experiment
// output folders (each an `afford experiment --out`, plotted): what each ran,
// read from its summary.json and experiment.json; our tables and figures
// beside the paper's numbers. scripts/reproduce.sh writes docs/results.md with it.
#pragma once
#include <string>
#include <vector>

namespace afford {

struct ReportRequest {
  std::vector<std::string> dirs;  // experiment output folders, in the order of the report
  std::string out = "report.md";  // the markdown file
  std::string figures;            // where figures go; empty: beside `out`, named after it (report.md: report/)
  double wall_seconds = 0;        // the caller's wall time, reported when > 0
  std::string note;               // a paragraph on how the runs were made, as given
  std::string config_dir;         // holds reference.yaml (the paper's numbers)
  std::string docs_dir;           // the project's docs/, linked when it exists; empty: none linked
};

struct ReportWritten {
  std::string out;                  // the markdown file
  std::string figures;              // the figures folder
  std::vector<std::string> labels;  // per folder, in the order given: its heading and figure subfolder
};

// The figures folder for `out` when none is given: out's path without its
// extension (report.md: report; docs/results.md: docs/results).
std::string defaultFiguresDir(const std::string& out);

// One label per folder, unique: the experiment's name; folders that share an
// experiment add their folder's name (base-a, base-b), then -2, -3 in the order
// given if still equal. Only letters, digits, '.', '-' and '_' (a file name).
std::vector<std::string> folderLabels(const std::vector<std::string>& experiments, const std::vector<std::string>& dirs);

// Reads every folder's summary.json (and experiment.json, if there) and the
// reference file, and renders the report, before anything is written: a folder
// without summary.json, or with a broken one, throws naming the folder. Then
// copies each folder's fig_*.png (and its CSV) into <figures>/<label>/ and
// writes `out`; every path in it is relative to out's folder.
ReportWritten writeReport(const ReportRequest& request);

}  // namespace afford
