// Files written whole or not at all, read with a bound (io/), and the JSON
// nesting bound every reader applies (spec/json.h).

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "pidlab/io/files.h"
#include "pidlab/spec/json.h"
#include "test_status.h"

namespace {

namespace fs = std::filesystem;
using pidlab::StatusCode;
namespace io = pidlab::io;

class IoTest : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string pattern = (fs::temp_directory_path() / "pidlab-io-test-XXXXXX").string();
    ASSERT_NE(mkdtemp(pattern.data()), nullptr);
    dir_ = pattern;
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string Path(const std::string& name) const { return dir_ + "/" + name; }
  static std::string Read(const std::string& path) {
    std::ifstream f(path, std::ios::binary);
    std::ostringstream os;
    os << f.rdbuf();
    return os.str();
  }
  static void Write(const std::string& path, const std::string& text) { std::ofstream(path) << text; }
  // The folder's entries, names only.
  std::vector<std::string> Entries() const {
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(dir_)) names.push_back(e.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
  }
  std::string dir_;
};

TEST_F(IoTest, WriteFileReplacesTheOldFileWhole) {
  Write(Path("a.txt"), "old");
  ASSERT_TRUE(io::WriteFile(Path("a.txt"), "new content").ok());
  EXPECT_EQ(Read(Path("a.txt")), "new content");
  EXPECT_EQ(Entries(), std::vector<std::string>{"a.txt"});  // no temporary left
}

TEST_F(IoTest, AnUncommittedFileLeavesTheOldOneAndNoTemporary) {
  Write(Path("a.txt"), "old");
  {
    std::unique_ptr<io::AtomicFile> f;
    ASSERT_TRUE(io::AtomicFile::Open(Path("a.txt"), &f).ok());
    f->Write(std::string(200000, 'x'));  // beyond the buffer: some bytes reach the temporary
    EXPECT_EQ(Read(Path("a.txt")), "old");
  }
  EXPECT_EQ(Read(Path("a.txt")), "old");
  EXPECT_EQ(Entries(), std::vector<std::string>{"a.txt"});
}

TEST_F(IoTest, ADirectoryInTheWayIsRefusedAsBadInputBeforeAnythingIsWritten) {
  fs::create_directory(Path("out.c"));
  const pidlab::Status s = io::WriteFiles({{Path("out.h"), "h"}, {Path("out.c"), "c"}});
  EXPECT_EQ(s.code(), StatusCode::kInvalidInput);
  EXPECT_NE(s.message().find("is a directory"), std::string::npos) << s.message();
  EXPECT_FALSE(fs::exists(Path("out.h")));
  EXPECT_EQ(Entries(), std::vector<std::string>{"out.c"});
}

TEST_F(IoTest, AReadOnlyOldFileIsRefusedEvenForRootAndNothingIsWritten) {
  Write(Path("out.h"), "old header");
  ASSERT_EQ(chmod(Path("out.h").c_str(), 0444), 0);
  const pidlab::Status s = io::WriteFiles({{Path("out.h"), "h"}, {Path("out.c"), "c"}});
  EXPECT_EQ(s.code(), StatusCode::kInvalidInput);
  EXPECT_NE(s.message().find("read-only"), std::string::npos) << s.message();
  EXPECT_EQ(Read(Path("out.h")), "old header");
  EXPECT_FALSE(fs::exists(Path("out.c")));
}

TEST_F(IoTest, WriteFilesReplacesEveryFileOfThePair) {
  Write(Path("out.h"), "old h");
  Write(Path("out.c"), "old c");
  ASSERT_TRUE(io::WriteFiles({{Path("out.h"), "new h"}, {Path("out.c"), "new c"}}).ok());
  EXPECT_EQ(Read(Path("out.h")), "new h");
  EXPECT_EQ(Read(Path("out.c")), "new c");
  EXPECT_EQ(Entries(), (std::vector<std::string>{"out.c", "out.h"}));
}

TEST_F(IoTest, AMissingFolderIsBadInputNamingThePath) {
  const pidlab::Status s = io::WriteFile(Path("no/such/a.txt"), "x");
  EXPECT_EQ(s.code(), StatusCode::kInvalidInput);
  EXPECT_NE(s.message().find("no/such"), std::string::npos) << s.message();
}

TEST_F(IoTest, AStagedFolderLandsWholeOnCommitAndMergesSubfolders) {
  fs::create_directories(Path("out/data"));
  Write(Path("out/old.md"), "kept");
  Write(Path("out/data/a.dat"), "old a");
  Write(Path("out/report.md"), "old report");
  {
    std::unique_ptr<io::StagedFolder> stage;
    ASSERT_TRUE(io::StagedFolder::Create(Path("out"), &stage).ok());
    fs::create_directories(stage->path() + "/data");
    ASSERT_TRUE(io::WriteFile(stage->path() + "/report.md", "new report").ok());
    ASSERT_TRUE(io::WriteFile(stage->path() + "/data/b.dat", "new b").ok());
    EXPECT_EQ(Read(Path("out/report.md")), "old report");  // nothing lands before Commit
    ASSERT_TRUE(stage->Commit().ok());
  }
  EXPECT_EQ(Read(Path("out/report.md")), "new report");
  EXPECT_EQ(Read(Path("out/old.md")), "kept");
  EXPECT_EQ(Read(Path("out/data/a.dat")), "old a");
  EXPECT_EQ(Read(Path("out/data/b.dat")), "new b");
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(Path("out"))) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  EXPECT_EQ(names, (std::vector<std::string>{"data", "old.md", "report.md"}));  // no stage left
}

TEST_F(IoTest, AStagedFolderNotCommittedLeavesTheFolderAsItWas) {
  fs::create_directories(Path("out"));
  Write(Path("out/report.md"), "old report");
  {
    std::unique_ptr<io::StagedFolder> stage;
    ASSERT_TRUE(io::StagedFolder::Create(Path("out"), &stage).ok());
    ASSERT_TRUE(io::WriteFile(stage->path() + "/report.md", "new report").ok());
    EXPECT_EQ(stage->Unstaged("cannot write '" + stage->path() + "/x.png': No space left on device"),
              "cannot write '" + Path("out") + "/x.png': No space left on device");
  }
  EXPECT_EQ(Read(Path("out/report.md")), "old report");
  EXPECT_EQ(std::distance(fs::directory_iterator(Path("out")), fs::directory_iterator()), 1);
}

TEST_F(IoTest, ReadFileRefusesAFileBeyondItsBoundAndNamesTheMissingOnesCause) {
  Write(Path("big.json"), std::string(2000, ' '));
  std::string text;
  pidlab::Status s = io::ReadFile(Path("big.json"), 1024, &text);
  EXPECT_EQ(s.code(), StatusCode::kInvalidInput);
  EXPECT_NE(s.message().find("is larger than 1 KiB"), std::string::npos) << s.message();
  ASSERT_TRUE(io::ReadFile(Path("big.json"), 2000, &text).ok());
  EXPECT_EQ(text.size(), 2000u);
  s = io::ReadFile(Path("none.json"), 1024, &text);
  EXPECT_EQ(s.code(), StatusCode::kInvalidInput);
  EXPECT_NE(s.message().find("cannot be read: No such file or directory"), std::string::npos) << s.message();
  s = io::ReadFile(dir_, 1024, &text);
  EXPECT_EQ(s.code(), StatusCode::kInvalidInput);
}

TEST(JsonNesting, ADocumentDeeperThanTheBoundIsRefusedBeforeParsing) {
  const int depth = 1000000;
  const std::string deep = "{\"a\":" + std::string(depth, '[') + std::string(depth, ']') + "}";
  nlohmann::json j;
  std::string error;
  EXPECT_FALSE(OkInto(pidlab::spec::ParseJsonText(deep, &j), &error));
  EXPECT_EQ(error, "is nested deeper than 64 levels (at byte 68)");
}

TEST(JsonNesting, BracketsInsideStringsAndEscapedQuotesDoNotCount) {
  const std::string text = R"({"a": "[[[[\"[[[[", "b": [[1]]})";
  EXPECT_TRUE(IsOk(pidlab::spec::CheckJsonNesting(text, 3)));
  EXPECT_FALSE(OkInto(pidlab::spec::CheckJsonNesting(text, 2), nullptr));
  nlohmann::json j;
  std::string error;
  const std::string at_bound = std::string(64, '[') + std::string(64, ']');
  EXPECT_TRUE(IsOk(pidlab::spec::ParseJsonText(at_bound, &j)));
  EXPECT_FALSE(OkInto(pidlab::spec::ParseJsonText("[" + at_bound + "]", &j), &error));
}

}  // namespace
