// The files afford's commands write (afford/file_lock.hpp, prepareOutput): each name checked before any work
// (a kind its writer writes: export --mcap .mcap, render --out .mp4 or .gif, scenario --png .png), and its
// folder made when it is missing, as every output folder of afford is (experiment --out, report --out);
// a folder that cannot be made is named, with the option.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "tests/support.hpp"

namespace afford {
namespace {

namespace fs = std::filesystem;

// A stored extrinsic test's log, unzipped into dir.
fs::path storedLog(const fs::path& dir) {
  const fs::path log = dir / "base-scenario3.lcm";
  const auto unzip = test::runCommand("gzip -dc '" + std::string(AFFORD_SOURCE_DIR) +
                                      "/tests/data/explain/base-scenario3.lcm.gz' > '" + log.string() + "'");
  EXPECT_EQ(unzip.exit_code, 0) << unzip.output;
  return log;
}

bool says(const test::CommandResult& r, const std::vector<std::string>& words) {
  for (const std::string& w : words)
    if (r.output.find(w) == std::string::npos) return false;
  return true;
}

// Refused before any work: the log named does not exist, and the error is about the file's name.
TEST(OutputFiles, ANameOfAnotherKindIsRefusedBeforeAnyWorkNamingTheOption) {
  const fs::path dir = test::tempDir("output-names");
  const std::string none = (dir / "no-such-log").string();
  struct Case {
    std::string args;
    fs::path file;
    std::vector<std::string> words;
  };
  const std::vector<Case> cases = {
      {"export " + none + " --mcap " + (dir / "run.mp4").string(), dir / "run.mp4", {"--mcap", "must end in .mcap"}},
      {"export " + none + " --mcap " + (dir / "run").string(), dir / "run", {"--mcap", "must end in .mcap"}},
      {"render " + none + " --out " + (dir / "run.avi").string(), dir / "run.avi",
       {"--out", "must end in .mp4 or .gif"}},
      {"scenario scenario1 --png " + (dir / "s.jpg").string(), dir / "s.jpg", {"--png", "must end in .png"}}};
  for (const Case& c : cases) {
    SCOPED_TRACE(c.args);
    const auto r = test::runAfford(c.args);
    EXPECT_NE(r.exit_code, 0);
    EXPECT_TRUE(says(r, c.words)) << r.output;
    EXPECT_EQ(r.output.find("no-such-log"), std::string::npos) << r.output;  // (the log was not read)
    EXPECT_FALSE(fs::exists(c.file));
    EXPECT_FALSE(fs::exists(c.file.string() + ".partial"));
  }
  // The name's case does not matter.
  EXPECT_TRUE(says(test::runAfford("export " + none + " --mcap " + (dir / "RUN.MCAP").string()),
                   {"no-such-log"}));
}

TEST(OutputFiles, AMissingFolderIsMadeForEveryOutputFile) {
  const fs::path dir = test::tempDir("output-folders");
  const fs::path log = storedLog(dir);
  const std::vector<std::pair<std::string, fs::path>> cases = {
      {"export " + log.string() + " --mcap ", dir / "a" / "b" / "run.mcap"},
      {"render " + log.string() + " --max-frames 2 --out ", dir / "c" / "d" / "run.gif"},
      {"scenario scenario1 --png ", dir / "e" / "f" / "scenario1.png"},
      {"bus-key ", dir / "g" / "h" / "bus.key"}};
  for (const auto& [args, file] : cases) {
    SCOPED_TRACE(args);
    const auto r = test::runAfford(args + file.string());
    EXPECT_EQ(r.exit_code, 0) << r.output;
    EXPECT_TRUE(fs::is_regular_file(file) && fs::file_size(file) > 0) << file;
  }
}

TEST(OutputFiles, AFolderThatCannotBeMadeIsNamedWithTheOption) {
  const fs::path dir = test::tempDir("output-blocked");
  std::ofstream(dir / "blocker") << "a file where a folder would be";
  const std::string none = (dir / "no-such-log").string(), folder = (dir / "blocker" / "x").string();
  for (const auto& [args, option] : std::vector<std::pair<std::string, std::string>>{
           {"export " + none + " --mcap " + folder + "/run.mcap", "--mcap"},
           {"render " + none + " --out " + folder + "/run.mp4", "--out"},
           {"scenario scenario1 --png " + folder + "/s.png", "--png"},
           {"bus-key " + folder + "/bus.key", "afford bus-key FILE"}}) {
    SCOPED_TRACE(args);
    const auto r = test::runAfford(args);
    EXPECT_NE(r.exit_code, 0);
    EXPECT_TRUE(says(r, {option, "cannot make its folder " + folder})) << r.output;
  }
}

}  // namespace
}  // namespace afford
