// io/output_transaction.h and io/temp_files.h: grouped writes land together or not at all, and
// the temporary files in flight are listed where a signal handler can remove them.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "io/file_util.h"
#include "io/output_transaction.h"
#include "io/temp_files.h"
#include "tests/support/test_support.h"

namespace voxplan {
namespace {

namespace fs = std::filesystem;

std::string Read(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

size_t CountFiles(const fs::path& dir) {
  size_t n = 0;
  for (const auto& e : fs::recursive_directory_iterator(dir)) n += e.is_regular_file();
  return n;
}

TEST(OutputTransactionTest, NothingLandsBeforeCommitThenEverything) {
  const test::TempDir dir("voxplan-tx");
  ASSERT_TRUE(WriteFileAtomically((dir / "a.txt").string(), "old a").ok());
  {
    OutputTransaction tx;
    ASSERT_TRUE(WriteFileAtomically((dir / "a.txt").string(), "new a").ok());
    ASSERT_TRUE(WriteFileAtomically((dir / "b.txt").string(), "new b").ok());
    EXPECT_EQ(tx.staged(), 2u);
    EXPECT_EQ(Read(dir / "a.txt"), "old a");
    EXPECT_FALSE(fs::exists(dir / "b.txt"));
    EXPECT_EQ(TempFilesInFlight(), 2);
    ASSERT_TRUE(tx.Commit().ok());
  }
  EXPECT_EQ(Read(dir / "a.txt"), "new a");
  EXPECT_EQ(Read(dir / "b.txt"), "new b");
  EXPECT_EQ(CountFiles(dir.path()), 2u);
  EXPECT_EQ(TempFilesInFlight(), 0);
}

TEST(OutputTransactionTest, AnUncommittedOneLeavesNothingAndRemovesTheFoldersItMade) {
  const test::TempDir dir("voxplan-tx");
  ASSERT_TRUE(WriteFileAtomically((dir / "a.txt").string(), "old a").ok());
  const fs::path made = dir / "made" / "deeper";
  {
    OutputTransaction tx;
    tx.WatchFolder(made.string());
    fs::create_directories(made);
    ASSERT_TRUE(WriteFileAtomically((made / "c.txt").string(), "c").ok());
    ASSERT_TRUE(WriteFileAtomically((dir / "a.txt").string(), "new a").ok());
  }  // a failure returned here: no Commit
  EXPECT_EQ(Read(dir / "a.txt"), "old a");
  EXPECT_FALSE(fs::exists(dir / "made"));
  EXPECT_EQ(CountFiles(dir.path()), 1u);
  EXPECT_EQ(TempFilesInFlight(), 0);
  // Without a transaction, writes land at once again.
  ASSERT_TRUE(WriteFileAtomically((dir / "a.txt").string(), "newer a").ok());
  EXPECT_EQ(Read(dir / "a.txt"), "newer a");
}

TEST(OutputTransactionTest, AFolderInATargetsPlaceFailsTheCommitBeforeAnyRename) {
  const test::TempDir dir("voxplan-tx");
  fs::create_directory(dir / "b.txt");
  OutputTransaction tx;
  ASSERT_TRUE(WriteFileAtomically((dir / "a.txt").string(), "a").ok());
  ASSERT_TRUE(WriteFileAtomically((dir / "b.txt").string(), "b").ok());
  const Status s = tx.Commit();
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("b.txt"), std::string::npos) << s.message();
  EXPECT_FALSE(fs::exists(dir / "a.txt"));
  EXPECT_EQ(CountFiles(dir.path()), 0u);
}

TEST(TempFilesTest, WriteAtomicallyListsItsTemporaryFileWhileWriting) {
  const test::TempDir dir("voxplan-tx");
  std::string seen;
  int in_flight = -1;
  ASSERT_TRUE(WriteAtomically((dir / "x.ply").string(), [&](const std::string& tmp) {
                seen = tmp;
                in_flight = TempFilesInFlight();
                return WriteStringToFile(tmp, "x");
              }).ok());
  EXPECT_EQ(in_flight, 1);
  EXPECT_EQ(TempFilesInFlight(), 0);
  EXPECT_NE(seen.find("x.ply.tmp-"), std::string::npos) << seen;
  EXPECT_TRUE(seen.ends_with(".ply")) << seen;
}

// What the CLI's signal handler does: every listed file and folder goes. (Last in this file:
// from then on the table keeps its copies, as a process about to exit would.)
TEST(TempFilesTest, RemoveTempFilesUnlinksEveryListedFileAndEmptiedFolder) {
  const test::TempDir dir("voxplan-tx");
  fs::create_directory(dir / "made");
  const fs::path a = dir / "made" / "a.tmp-1", b = dir / "b.tmp-2", kept = dir / "kept.txt";
  for (const fs::path& p : {a, b, kept}) std::ofstream(p) << "x";
  const int sa = RememberTempFile(a.string()), sb = RememberTempFile(b.string());
  const int sd = RememberTempFolder((dir / "made").string());
  ASSERT_GE(sa, 0);
  ASSERT_GE(sb, 0);
  ASSERT_GE(sd, 0);
  RemoveTempFiles();
  EXPECT_FALSE(fs::exists(a));
  EXPECT_FALSE(fs::exists(b));
  EXPECT_FALSE(fs::exists(dir / "made"));
  EXPECT_TRUE(fs::exists(kept));
  ForgetTempFile(sa);
  ForgetTempFile(sb);
  ForgetTempFolder(sd);
  EXPECT_EQ(TempFilesInFlight(), 0);
}

}  // namespace
}  // namespace voxplan
