// Names from outside that name things on disk (afford/names.hpp): a run id is
// letters, digits, '.', '_' and '-', bounded, never "." or ".." or hidden;
// a path is inside a folder only if it stays there once resolved.
#include <gtest/gtest.h>

#include <filesystem>

#include "afford/names.hpp"
#include "tests/support.hpp"

namespace afford {
namespace {

namespace fs = std::filesystem;

TEST(Names, ARunIdOfTheRunnerIsSafe) {
  EXPECT_TRUE(safeRunId("20261126-101500-base-IMP-s1", 200));
  EXPECT_TRUE(safeRunId("ex-base-IMP-s2-scenario3-e0", 200));
  EXPECT_TRUE(safeRunId("t03-leak_0.2-IMP-s7", 200));
}

TEST(Names, ARunIdThatCouldNameAnotherPlaceIsRefusedSayingWhy) {
  for (const std::string id : {"../../x", "a/b", "/etc", "..", ".", ".hidden", "-rf", "a b", "a\nb", "x\\y", "é"})
    EXPECT_FALSE(safeRunId(id, 200)) << id;
  EXPECT_EQ(runIdProblem("", 200), "is empty");
  EXPECT_NE(runIdProblem("a/b", 200).find("'/'"), std::string::npos);
  EXPECT_NE(runIdProblem("a\x01", 200).find("\\x01"), std::string::npos);
  EXPECT_NE(runIdProblem(std::string(201, 'a'), 200).find("201 bytes"), std::string::npos);
  EXPECT_TRUE(safeRunId(std::string(200, 'a'), 200));
}

TEST(Names, PrintableShowsControlBytesAsEscapes) {
  EXPECT_EQ(printable("ok"), "ok");
  EXPECT_EQ(printable("a\x1b[2Jb"), "a\\x1b[2Jb");
  EXPECT_EQ(printable(std::string(10, 'x'), 4), "xxxx...");
}

TEST(Names, APathIsInsideAFolderOnlyIfItStaysThereResolved) {
  const fs::path root = test::tempDir("names");
  fs::create_directories(root / "run");
  EXPECT_TRUE(insideFolder(root / "run" / "predictors.ckpt", root));
  EXPECT_TRUE(insideFolder(root / "not-yet" / "x.ckpt", root));
  EXPECT_FALSE(insideFolder(root, root));
  EXPECT_FALSE(insideFolder(root / ".." / "elsewhere.ckpt", root));
  EXPECT_FALSE(insideFolder(root / "run" / ".." / ".." / "x", root));
  EXPECT_FALSE(insideFolder("/etc/passwd", root));
  fs::create_directory_symlink("/tmp", root / "link");
  EXPECT_FALSE(insideFolder(root / "link" / "x.ckpt", root)) << "a symbolic link out of the folder";
}

TEST(Names, ACountSaysItsNounInTheSingularForOneAlone) {
  // The console's "solved in 1 step" (it said "1 steps").
  EXPECT_EQ(counted(1, "step"), "1 step");
  EXPECT_EQ(counted(0, "action"), "0 actions");
  EXPECT_EQ(counted(12, "step"), "12 steps");
}

}  // namespace
}  // namespace afford
