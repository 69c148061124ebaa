// What the report's files share (experiment/present/report.cpp, the paper's
// and our experiments' sections; report_sections.cpp, the sections beyond the
// paper and of its section 3.2): the folders read, links to the docs, numbers
// as shown. Not for use outside present/.
#pragma once
#include <filesystem>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "experiment/design/reference.hpp"
#include "experiment/schema/summary.hpp"
#include "experiment/stored/state_file.hpp"

namespace afford::report {
namespace fs = std::filesystem;

std::string num(double v, int digits = 2);
// A path in a markdown link: what would end or break the link, percent-encoded.
std::string linkPath(const std::string& path);
// `target` as seen from folder `from` ('/'-separated; absolute only if no relative path exists).
std::string relativeTo(const fs::path& target, const fs::path& from);
std::string pValue(const Nullable<double>& p);

// One experiment output folder, as read.
struct Folder {
  std::string dir;    // as given
  Summary summary;    // summary.json
  std::optional<ExperimentState> state;  // experiment.json, if the folder has one
  std::string label;  // unique among the report's folders: headings and figure subfolder
  std::string shown;  // the folder's path relative to the report's folder
  std::string sweep;  // a sweep's condition: the sweep's folder (its comparison figures), else ""
};

// The paper's systems, in its order.
inline const std::vector<std::string> kPaperSystems{"FIX", "IGN", "IMP"};
// The systems the folders ran: the paper's in their order (FIX, IGN, IMP), then any other (GOALS, a
// motivation of one's own) by name. Every table of systems has a column or row for each.
std::vector<std::string> systemsOf(const std::vector<Folder>& folders);

// The paper's claim for a shipped experiment (reference.yaml: <experiment>_claims).
std::string claim(const Reference& ref, const Summary& s);
// " (label)" after a heading named by the paper, when the label is not the experiment's name.
std::string labelled(const Folder& f);

// Links to the project's documentation, relative to the report's folder.
struct Docs {
  fs::path dir;       // the project's docs/; empty: not linked
  fs::path from;      // the report's folder
  // "[name](path#anchor)", or `name` alone when the file is not there.
  std::string link(const std::string& name, const std::string& anchor = "") const {
    if (dir.empty() || !fs::exists(dir / name)) return "`docs/" + name + "`";
    return "[" + name + "](" + linkPath(relativeTo(dir / name, from)) + (anchor.empty() ? "" : "#" + anchor) + ")";
  }
  bool has(const std::string& name) const { return !dir.empty() && fs::exists(dir / name); }
};

// An experiment with the authors' eye (issue 28): NAME-true-centre, shown
// beside NAME in its own section (authorsEyeSections).
inline const std::string kAuthorsEyeSuffix = "-true-centre";
inline bool withTheAuthorsEye(const std::string& experiment) {
  return experiment.size() > kAuthorsEyeSuffix.size() &&
         experiment.compare(experiment.size() - kAuthorsEyeSuffix.size(), kAuthorsEyeSuffix.size(), kAuthorsEyeSuffix) == 0;
}

// The sections of report_sections.cpp, each "" when no folder is of it.
// Completion steps by number of sub-goals and their fit (paper Figure 6): a table.
void completionSection(std::ostream& md, const std::vector<Folder>& folders);
// Section 3.2 of the paper: stochastic affordances (Figure 11) and the planner tests (Figures 12-14).
std::string stochasticSections(const std::vector<Folder>& folders, const Reference& ref);
// An experiment with the authors' eye (NAME-true-centre) beside the same experiment with ours.
std::string authorsEyeSections(const std::vector<Folder>& folders, const Docs& docs);
// Random tables, and the late-object tests with the memory options.
std::string memorySections(const std::vector<Folder>& folders, const Docs& docs);
// Designs of generated scenarios, per condition and point, with the floors of reference.yaml.
std::string generatedSections(const std::vector<Folder>& folders, const Reference& reference, const Docs& docs);
// GOALS agents beside IMP: affordance error, actions, extrinsic success, competence per module (report_goals.cpp).
std::string goalsSections(const std::vector<Folder>& folders, const Docs& docs);

}  // namespace afford::report
