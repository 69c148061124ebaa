// The front door's shared parts: the registry of processes, the in-process
// host, and config/reference.yaml (the paper's numbers and thresholds).
#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>
#include <spdlog/sinks/null_sink.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <algorithm>
#include <iterator>
#include <map>
#include <regex>
#include <set>

#include "experiment/execute/agents.hpp"
#include "experiment/experiment.hpp"
#include "experiment/plan/plan.hpp"
#include "afford/protocol.hpp"
#include "afford/config.hpp"
#include "experiment/run/host.hpp"
#include "afford/processes.hpp"
#include "experiment/design/reference.hpp"
#include "experiment/plan/sweep.hpp"
#include "tests/support.hpp"

namespace afford {
namespace {

const std::string kConfigDir = std::string(AFFORD_SOURCE_DIR) + "/config";

// An agent stored without an after-N-actions checkpoint (a run that did not ask
// for one) gets it from a later run of the same agent that made it, and is
// then found by an experiment that needs it; the files it had stay as they were.
TEST(AgentStore, AKeptAgentGainsTheCheckpointsItLacked) {
  namespace fs = std::filesystem;
  const std::string dir = test::tempDir("store"), root = dir + "/agents";
  auto runWith = [&](const std::string& name, bool after) {
    fs::create_directories(dir + "/" + name);
    RunOutcome r;
    r.ok = true;
    r.weights_checksum = "0123456789abcdef";
    r.checkpoint = dir + "/" + name + "/predictors.ckpt";
    std::ofstream(r.checkpoint) << name;
    if (after) std::ofstream(actionsCheckpoint(r.checkpoint, 4000)) << name << " after 4000";
    return r;
  };
  AgentStore store(root);
  const std::uintmax_t most = 1 << 20;  // what its outcome may take
  store.keep("k", "first", "stochastic", runWith("first", false));
  ASSERT_TRUE(store.find("k", 0, most));
  EXPECT_FALSE(store.find("k", 4000, most)) << "it has no after-4000 checkpoint yet";
  store.keep("k", "second", "forward-models", runWith("second", true));
  const auto found = store.find("k", 4000, most);
  ASSERT_TRUE(found);
  EXPECT_EQ(found->reused_from, "first");
  std::ifstream whole(found->checkpoint), after(actionsCheckpoint(found->checkpoint, 4000));
  EXPECT_EQ(std::string(std::istreambuf_iterator<char>(whole), {}), "first");
  EXPECT_EQ(std::string(std::istreambuf_iterator<char>(after), {}), "second after 4000");
  for (const auto& f : fs::directory_iterator(root))
    EXPECT_EQ(f.path().filename(), "k") << "no temporary folder or file is left";
  for (const auto& f : fs::directory_iterator(root + "/k"))
    EXPECT_EQ(f.path().string().find(".part."), std::string::npos) << f.path();
}

TEST(Sweep, ValuesSplitAtTopLevelCommasOnly) {
  EXPECT_EQ(sweepValues("0.1,0.2,0.4"), (std::vector<std::string>{"0.1", "0.2", "0.4"}));
  EXPECT_EQ(sweepValues("[1, 2]"), (std::vector<std::string>{"[1, 2]"}));
  EXPECT_EQ(sweepValues("[1,2],[3,4]"), (std::vector<std::string>{"[1,2]", "[3,4]"}));
  EXPECT_EQ(sweepValues("{a: 1, b: 2},\"x,y\""), (std::vector<std::string>{"{a: 1, b: 2}", "\"x,y\""}));
  EXPECT_EQ(sweepValues("0.2"), (std::vector<std::string>{"0.2"}));
}

TEST(Sweep, ConditionsAreTheCrossProductLastKeyFastest) {
  const Sweep s = planSweep({"a.b=1,2", "c=x", "d.e=3,4,5"}, "");
  EXPECT_EQ(s.fixed, (std::vector<std::string>{"c=x"}));
  ASSERT_EQ(s.conditions.size(), 6u);
  EXPECT_EQ(s.conditions[0].name, "a.b=1,d.e=3");
  EXPECT_EQ(s.conditions[1].settings, (std::vector<std::string>{"a.b=1", "d.e=4"}));
  EXPECT_EQ(s.conditions[5].name, "a.b=2,d.e=5");
  EXPECT_TRUE(planSweep({"a=1", "b=[1,2]"}, "").conditions.empty());  // one value each: no sweep
  EXPECT_THROW(planSweep({"a=1,2", "a=3,4"}, ""), ConfigError);
  EXPECT_THROW(planSweep({"a=1,", "b=2"}, ""), ConfigError);  // an empty value
}

// A condition's folder is a file name: long ones keep their start and a hash
// of the whole name, so they stay distinct and within the file system's 255 bytes.
TEST(Sweep, LongConditionsGetShortDistinctFolders) {
  const std::string long_a(150, 'a'), long_b(150, 'b');
  const Sweep s = planSweep({"planner.x=[" + long_a + "1]," + "[" + long_a + "2]", "motivation.y=" + long_b + ",c"}, "");
  ASSERT_EQ(s.conditions.size(), 4u);
  std::set<std::string> folders;
  for (const auto& c : s.conditions) {
    EXPECT_LE(c.folder.size(), 160u) << c.folder;
    folders.insert(c.folder);
  }
  EXPECT_EQ(folders.size(), 4u);
  EXPECT_EQ(planSweep({"a.b=[1],[2]", "c=x,y"}, "").conditions[1].folder, "a.b=_1_,c=y");  // short ones: as they were
}

// A sweep file whose key is a list or a map is refused naming the file and the line.
TEST(Sweep, ASweepFileKeyThatIsNoNameIsRefusedNamingTheFile) {
  const std::string file = test::tempDir("sweep-key") + "/sweep.yaml";
  std::ofstream(file) << "motivation.leak: [0.1, 0.2]\n? [a, b]\n: [1, 2]\n";
  try {
    planSweep({}, file);
    FAIL() << "accepted";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("sweep file " + file), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("line 2"), std::string::npos) << e.what();
  }
}

// Every process drops messages of a run id that is not a safe name: the runner refuses one before anything runs.
TEST(Plan, ARunIdThatIsNoSafeNameIsRefusedBeforeAnythingRuns) {
  ExperimentRequest o;
  o.plan.experiment = "base";
  o.plan.systems = {"IMP"};
  o.plan.reps = 1;
  o.plan.steps = 10;
  for (const std::string& prefix : std::vector<std::string>{"a b", "../x", ".hidden", std::string(200, 'p')}) {
    o.plan.run_prefix = prefix;
    try {
      planExperiment(o.plan);
      ADD_FAILURE() << "run prefix '" << prefix << "' was taken";
    } catch (const ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find("--run-prefix"), std::string::npos) << e.what();
    }
  }
  o.plan.run_prefix = "fine-1.0_x";
  EXPECT_NO_THROW(planExperiment(o.plan));
  o.plan.run_prefix = "fine";
  o.plan.extrinsic_reps = 1;
  o.plan.scenarios = {"scenario1"};
  EXPECT_NO_THROW(planExperiment(o.plan));
}

// afford experiment --process NAME='CMD ARGS': each name once, a process of the registry, a command.
TEST(Plan, ProcessSwapsAreCheckedNamingTheOption) {
  EXPECT_EQ(parseProcessSwaps({"motivation=  ./mine --x 1"}, "--process"),
            (std::map<std::string, std::string>{{"motivation", "./mine --x 1"}}));
  for (const std::string& bad : std::vector<std::string>{"motivation", "brain=./x", "=./x", "motivation=  ",
                                                         "../x=./y"}) {
    try {
      parseProcessSwaps({bad}, "--process");
      ADD_FAILURE() << "'" << bad << "' was taken";
    } catch (const ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find("--process"), std::string::npos) << e.what();
    }
  }
  EXPECT_THROW(parseProcessSwaps({"eye=./a", "eye=./b"}, "--process"), ConfigError);
}

// docs/processes-and-channels.md shows the protocol's own table (afford processes --protocol).
TEST(Protocol, TheDocsChannelTableIsTheProtocols) {
  std::ifstream in(std::string(AFFORD_SOURCE_DIR) + "/docs/processes-and-channels.md");
  const std::string docs((std::istreambuf_iterator<char>(in)), {});
  EXPECT_NE(docs.find(protocolTable()), std::string::npos)
      << "docs/processes-and-channels.md's channel table is not `afford processes --protocol`'s:\n" << protocolTable();
}

// docs/processes-and-channels.md shows every process's input rules (afford processes --rules).
TEST(Protocol, TheDocsRulesTableIsTheProcesses) {
  std::ifstream in(std::string(AFFORD_SOURCE_DIR) + "/docs/processes-and-channels.md");
  const std::string docs((std::istreambuf_iterator<char>(in)), {});
  const std::string rules = inputRulesTable(kConfigDir);
  EXPECT_NE(docs.find(rules), std::string::npos)
      << "docs/processes-and-channels.md's rules table is not `afford processes --rules`'s:\n" << rules;
}

// Each channel's registry entry agrees with the protocol: its publisher in a phase publishes it then.
TEST(Protocol, TheRegistryPublishesWhatTheProtocolSays) {
  forEachChannel([](const ChannelInfo& c) {
    for (const auto& [phase_name, phase] : kPhaseNames) {
      const std::string p = c.publisher(phase);
      if (!c.serial || !isProcessName(p)) continue;
      EXPECT_EQ(publisherOf(c.name, phase), p) << c.name << " in " << phase_name;
      const auto mine = channelsOf(p, phase);
      EXPECT_NE(std::find(mine.begin(), mine.end(), c.name), mine.end()) << c.name << " of " << p;
    }
  });
}

TEST(Registry, EachRunChannelHasOnePublisherPerPhase) {
  for (const auto& [phase_name, phase] : kPhaseNames) {
    std::set<std::string> published;
    for (const std::string& p : runProcesses(phase, true))
      for (const std::string& ch : channelsOf(p, phase)) {
        if (ch == ch::status.name) continue;
        EXPECT_TRUE(published.insert(ch).second) << ch << " published twice in " << phase_name;
        EXPECT_EQ(publisherOf(ch, phase), p) << ch;
      }
    // Every channel with a serial is published by someone of the phase, or belongs to another phase.
    for (const std::string& ch : channelNames(/*serial_only=*/true))
      if (!published.count(ch)) {
        EXPECT_EQ(publisherOf(ch, phase), "") << ch << " in " << phase_name;
      }
  }
  EXPECT_EQ(publisherOf(ch::decision.name, Phase::Intrinsic), "motivation");
  EXPECT_EQ(publisherOf(ch::decision.name, Phase::Extrinsic), "planner");
  EXPECT_EQ(publisherOf(ch::decision.name, Phase::Goals), "planner");
  EXPECT_EQ(publisherOf(ch::goal.name, Phase::Goals), "motivation");
  EXPECT_EQ(publisherOf(ch::goal.name, Phase::Intrinsic), "");
  EXPECT_EQ(publisherOf(ch::runConfig.name, Phase::Intrinsic), "");  // the runner's
}

TEST(Registry, ThePhasesTakeTheirDeciderAndTheLoggerOnlyWhenRecorded) {
  EXPECT_EQ(runProcesses(Phase::Intrinsic, false),
            (std::vector<std::string>{"environment", "eye", "predictors", "motivation"}));
  EXPECT_EQ(runProcesses(Phase::Extrinsic, true),
            (std::vector<std::string>{"environment", "eye", "predictors", "planner", "logger"}));
  EXPECT_EQ(runProcesses(Phase::Goals, false),
            (std::vector<std::string>{"environment", "eye", "predictors", "motivation", "planner"}));
  EXPECT_TRUE(isProcessName("logger"));
  EXPECT_FALSE(isProcessName("runner"));
  EXPECT_TRUE(channelsOf("runner", Phase::Intrinsic).empty());
}

TEST(Host, HostsEveryRegisteredProcessAndRefusesOthersByName) {
  lcm::LCM lcm("memq://");
  const auto null = [](const std::string& n) {
    return std::make_shared<spdlog::logger>(n, std::make_shared<spdlog::sinks::null_sink_mt>());
  };
  InProcessHost host(lcm, loadProtocol(kConfigDir), null, HostOptions{true, test::tempDir("host-logs"), nullptr, ""});
  for (const ProcessInfo& p : processRegistry()) {
    host.start(p.name);
    EXPECT_EQ(host.node(p.name).runId(), "") << p.name;
  }
  host.tick();
  EXPECT_FALSE(host.inRun());
  try {
    host.start("runner");
    FAIL() << "an unknown process was hosted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("unknown process \"runner\""), std::string::npos) << e.what();
  }
}

std::string referenceError(const std::string& text, const std::string& key = "") {
  const std::string dir = test::tempDir("reference");
  std::ofstream(dir + "/reference.yaml") << text;
  try {
    const Reference r(dir);
    if (!key.empty()) r.required(key);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

TEST(Reference, TheShippedFileHoldsThePapersThresholds) {
  const Reference r(kConfigDir);
  EXPECT_DOUBLE_EQ(r.required("thresholds.table_metric.solved_share"), 0.9);
  EXPECT_DOUBLE_EQ(r.required("thresholds.stochastic_checks.turn_blue"), 0.8);
  EXPECT_DOUBLE_EQ(r.required("thresholds.stochastic_checks.move_red"), 0.6);
  EXPECT_EQ(r.numbers(r.entry("base_extrinsic")["table_metric"]["FIX"], "x").size(), 5u);
}

TEST(Reference, ABrokenFileIsAnErrorNamingItAndTheKey) {
  EXPECT_NE(referenceError("base: [unclosed\n").find("reference.yaml: cannot be read"), std::string::npos);
  EXPECT_NE(referenceError("- a list\n").find("reference.yaml: expected a map"), std::string::npos);
  EXPECT_NE(referenceError("thresholds: {}\n", "thresholds.table_metric.solved_share")
                .find("key thresholds.table_metric.solved_share is missing"),
            std::string::npos);
  EXPECT_NE(referenceError("thresholds: {table_metric: {solved_share: most}}\n", "thresholds.table_metric.solved_share")
                .find("key thresholds.table_metric.solved_share: expected a number"),
            std::string::npos);
  EXPECT_NE(referenceError("", "x").find("expected a map"), std::string::npos);
  const std::string missing = test::tempDir("reference-missing");
  try {
    Reference r(missing);
    FAIL() << "a missing reference.yaml was read";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find(missing + "/reference.yaml"), std::string::npos) << e.what();
  }
}

// The map of files in docs/processes-and-channels.md names every file of the
// command line (apps/afford) and of the experiment engine (experiment/).
TEST(Docs, TheMapOfFilesNamesEveryFileOfTheFrontDoorAndTheEngine) {
  const std::filesystem::path root = AFFORD_SOURCE_DIR;
  std::ifstream doc(root / "docs" / "processes-and-channels.md");
  const std::string text((std::istreambuf_iterator<char>(doc)), std::istreambuf_iterator<char>());
  const auto from = text.find("```text\ncommon/ ");
  ASSERT_NE(from, std::string::npos) << "no map of files (beginning with common/) in docs/processes-and-channels.md";
  ASSERT_NE(text.find("\napps/afford/ ", from), std::string::npos) << "the map of files has no apps/afford/";
  const std::string map = text.substr(from, text.find("```", from + 3) - from);
  int files = 0;
  for (const char* folder : {"apps/afford", "experiment"})
    for (const auto& e : std::filesystem::recursive_directory_iterator(root / folder)) {
      if (!e.is_regular_file()) continue;
      ++files;
      const std::string stem = e.path().stem().string();
      const bool named = std::regex_search(map, std::regex("(^|[^a-z_])" + stem + "\\."));
      EXPECT_TRUE(named) << std::filesystem::relative(e.path(), root).string() << " is not in the map of files";
    }
  EXPECT_GT(files, 40);
}

// The layers, lowest first: common/ (what every process needs), the
// processes, the experiment engine (itself in layers), the command line
// (apps/) and the tools beside it, the Python package. A file includes
// headers of its own folder or of a lower layer, never of a higher one or of
// a sibling (no process includes another's); and there is no include cycle.
TEST(Layers, NoFileIncludesAHeaderOfAHigherLayerOrASiblingAndThereIsNoCycle) {
  namespace fs = std::filesystem;
  const fs::path root = AFFORD_SOURCE_DIR;
  const auto folderOf = [&](const fs::path& file) {  // "experiment/plan", "processes/eye", "apps/afford", "common", ...
    const fs::path rel = fs::relative(file, root);
    auto it = rel.begin();
    const std::string top = (it++)->string();
    if (top == "common" || top == "third_party") return top;
    const std::string second = (it != rel.end() && std::next(it) != rel.end()) ? it->string() : std::string();
    return second.empty() ? top : top + "/" + second;
  };
  const std::map<std::string, int> rank = {
      {"common", 0},           {"experiment/schema", 2},  {"experiment/design", 3},  {"experiment/run", 3},
      {"experiment/plan", 4},  {"experiment/execute", 5}, {"experiment/replay", 5},  {"experiment/results", 6},
      {"experiment/export", 6}, {"experiment/watch", 6},
      {"experiment/stored", 7}, {"experiment/present", 8}, {"experiment", 9},       {"apps/afford", 10},
      {"python/src", 11}};
  const auto rankOf = [&](const std::string& folder) {
    if (const auto r = rank.find(folder); r != rank.end()) return r->second;
    if (folder.rfind("processes/", 0) == 0) return 1;
    if (folder.rfind("tools/", 0) == 0 || folder.rfind("examples/", 0) == 0) return 10;
    ADD_FAILURE() << "no layer for the folder " << folder;
    return -1;
  };
  // Where an include resolves: the including file's folder, common's afford/x.hpp, a process's <name>/x.hpp, or
  // a path from the top (experiment/..., apps/...).
  const auto resolve = [&](const fs::path& from, const std::string& inc) -> fs::path {
    for (const fs::path& base : {from.parent_path(), root / "common" / "include", root / "processes", root})
      if (fs::exists(base / inc)) return fs::weakly_canonical(base / inc);
    return {};
  };
  std::map<fs::path, std::vector<fs::path>> graph;
  const std::regex include_re("#include \"([^\"]+)\"");
  int checked = 0;
  for (const char* top : {"common", "processes", "experiment", "apps", "python/src", "tools", "examples"})
    for (const auto& e : fs::recursive_directory_iterator(root / top)) {
      const std::string ext = e.path().extension().string();
      if (!e.is_regular_file() || (ext != ".hpp" && ext != ".cpp")) continue;
      const fs::path file = fs::weakly_canonical(e.path());
      std::ifstream in(file);
      const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
      for (std::sregex_iterator m(text.begin(), text.end(), include_re), end; m != end; ++m) {
        const fs::path target = resolve(file, (*m)[1]);
        if (target.empty()) continue;  // generated (lcmtypes) or system
        ++checked;
        graph[file].push_back(target);
        const std::string from = folderOf(file), to = folderOf(target);
        if (from == to) continue;
        EXPECT_LT(rankOf(to), rankOf(from))
            << fs::relative(file, root).string() << " (layer " << from << ") includes " << (*m)[1] << " (layer "
            << to << "): a layer includes only lower ones, and no sibling";
      }
    }
  EXPECT_GT(checked, 300);
  // Cycles: a depth-first walk over the headers.
  std::map<fs::path, int> mark;  // 1: on the path, 2: done
  std::vector<fs::path> path;
  std::function<void(const fs::path&)> visit = [&](const fs::path& f) {
    mark[f] = 1;
    path.push_back(f);
    for (const fs::path& g : graph[f]) {
      if (mark[g] == 1) {
        std::string cycle;
        for (auto it = std::find(path.begin(), path.end(), g); it != path.end(); ++it)
          cycle += fs::relative(*it, root).string() + " -> ";
        ADD_FAILURE() << "include cycle: " << cycle << fs::relative(g, root).string();
      } else if (mark[g] == 0) {
        visit(g);
      }
    }
    path.pop_back();
    mark[f] = 2;
  };
  for (const auto& [f, _] : graph)
    if (mark[f] == 0) visit(f);
}

}  // namespace
}  // namespace afford
