// Atomic output files and output-directory resolution (fivebar/io.hpp).

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <stdexcept>

#include "fivebar/error.hpp"
#include "fivebar/io.hpp"

namespace fs = std::filesystem;
using fivebar::AtomicFile;
using fivebar::InputError;
using fivebar::IoError;
using fivebar::resolve_output_dir;
using fivebar::write_file_atomic;
using ::testing::HasSubstr;
using ::testing::StartsWith;

namespace {

/// A fresh directory per test, removed afterwards.
class TempDir : public ::testing::Test {
 protected:
  void SetUp() override {
    std::random_device rd;
    dir_ = fs::temp_directory_path() / ("fivebar_test_io_" + std::to_string(::getpid()) + "_" + std::to_string(rd()));
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    fs::permissions(dir_, fs::perms::owner_all, fs::perm_options::add, ec);
    fs::remove_all(dir_, ec);
  }
  std::string read(const fs::path& p) const {
    std::ifstream in(p, std::ios::binary);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
  }
  /// Names in the directory other than the ones given.
  std::vector<std::string> entries() const {
    std::vector<std::string> out;
    for (const auto& e : fs::directory_iterator(dir_)) out.push_back(e.path().filename().string());
    std::sort(out.begin(), out.end());
    return out;
  }
  fs::path dir_;
};

using WriteFileAtomic = TempDir;
using AtomicFileTest = TempDir;

TEST_F(WriteFileAtomic, WritesContentAndLeavesNoTemporary) {
  const fs::path p = dir_ / "summary.md";
  write_file_atomic(p, "hello\nworld\n");
  EXPECT_EQ(read(p), "hello\nworld\n");
  EXPECT_EQ(entries(), std::vector<std::string>{"summary.md"});
}

TEST_F(WriteFileAtomic, ReplacesAnExistingFile) {
  const fs::path p = dir_ / "a.json";
  write_file_atomic(p, "old");
  write_file_atomic(p, "new content");
  EXPECT_EQ(read(p), "new content");
  EXPECT_EQ(entries(), std::vector<std::string>{"a.json"});
}

TEST_F(WriteFileAtomic, WritesEmptyAndBinaryContent) {
  write_file_atomic(dir_ / "empty", "");
  EXPECT_EQ(read(dir_ / "empty"), "");
  std::string bytes(300000, '\0');
  for (std::size_t i = 0; i < bytes.size(); ++i) bytes[i] = static_cast<char>(i * 7);
  write_file_atomic(dir_ / "big.bin", bytes);  // larger than the stream buffer
  EXPECT_EQ(read(dir_ / "big.bin"), bytes);
}

TEST_F(WriteFileAtomic, MissingDirectoryThrowsIoErrorNamingThePath) {
  const fs::path p = dir_ / "no" / "such" / "dir" / "f.txt";
  EXPECT_THAT([&] { write_file_atomic(p, "x"); }, ::testing::ThrowsMessage<IoError>(HasSubstr(p.string())));
  EXPECT_TRUE(entries().empty());
}

TEST_F(WriteFileAtomic, TargetIsADirectoryThrowsAndRemovesTheTemporary) {
  fs::create_directory(dir_ / "taken");
  fs::create_directory(dir_ / "taken" / "child");  // a non-empty directory cannot be renamed over
  EXPECT_THROW(write_file_atomic(dir_ / "taken", "x"), IoError);
  EXPECT_EQ(entries(), std::vector<std::string>{"taken"});
  EXPECT_TRUE(fs::is_directory(dir_ / "taken" / "child"));
}

TEST_F(WriteFileAtomic, UnwritableDirectoryThrowsAndKeepsTheOldFile) {
  if (::geteuid() == 0) GTEST_SKIP() << "root ignores directory permissions";
  write_file_atomic(dir_ / "keep.txt", "old");
  fs::permissions(dir_, fs::perms::owner_write, fs::perm_options::remove);
  EXPECT_THROW(write_file_atomic(dir_ / "keep.txt", "new"), IoError);
  fs::permissions(dir_, fs::perms::owner_write, fs::perm_options::add);
  EXPECT_EQ(read(dir_ / "keep.txt"), "old");
  EXPECT_EQ(entries(), std::vector<std::string>{"keep.txt"});
}

TEST_F(WriteFileAtomic, RejectsAPathWithoutFileName) {
  EXPECT_THROW(write_file_atomic(dir_ / "", "x"), IoError);
  EXPECT_THROW(write_file_atomic(dir_ / "..", "x"), IoError);
}

TEST_F(AtomicFileTest, TemporaryIsAHiddenSiblingNamedAfterTheTarget) {
  AtomicFile f(dir_ / "rows.csv");
  const std::string temp = f.temp_path().filename().string();
  EXPECT_THAT(temp, StartsWith(".rows.csv.tmp." + std::to_string(::getpid()) + "."));
  EXPECT_EQ(f.temp_path().parent_path(), dir_);
  EXPECT_TRUE(fs::exists(f.temp_path()));
  EXPECT_FALSE(fs::exists(dir_ / "rows.csv"));
}

TEST_F(AtomicFileTest, CommitRenamesStreamedContent) {
  {
    AtomicFile f(dir_ / "rows.csv");
    f.stream() << "x_mm,y_mm\n";
    for (int i = 0; i < 10000; ++i) f.stream() << i << "," << i * 0.5 << "\n";
    EXPECT_FALSE(fs::exists(dir_ / "rows.csv"));  // nothing visible before commit
    f.commit();
    EXPECT_TRUE(f.temp_path().empty());
    EXPECT_THROW(f.commit(), std::logic_error);
  }
  const std::string text = read(dir_ / "rows.csv");
  EXPECT_THAT(text, StartsWith("x_mm,y_mm\n0,0\n1,0.5\n"));
  EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 10001);
  EXPECT_EQ(entries(), std::vector<std::string>{"rows.csv"});
}

TEST_F(AtomicFileTest, DestructionWithoutCommitRemovesTheTemporaryAndKeepsTheTarget) {
  write_file_atomic(dir_ / "rows.csv", "previous\n");
  try {
    AtomicFile f(dir_ / "rows.csv");
    f.stream() << "partial row";
    throw std::runtime_error("bad input row");
  } catch (const std::runtime_error&) {
  }
  EXPECT_EQ(read(dir_ / "rows.csv"), "previous\n");
  EXPECT_EQ(entries(), std::vector<std::string>{"rows.csv"});
}

TEST_F(AtomicFileTest, DiscardAndMove) {
  AtomicFile a(dir_ / "a.txt");
  a.stream() << "moved";
  AtomicFile b(std::move(a));
  b.commit();
  EXPECT_EQ(read(dir_ / "a.txt"), "moved");

  AtomicFile c(dir_ / "c.txt");
  c.discard();
  EXPECT_TRUE(c.temp_path().empty());
  EXPECT_EQ(entries(), std::vector<std::string>{"a.txt"});
}

TEST_F(AtomicFileTest, TwoWritersGetDistinctTemporaries) {
  AtomicFile a(dir_ / "same.txt");
  AtomicFile b(dir_ / "same.txt");
  EXPECT_NE(a.temp_path(), b.temp_path());
  a.stream() << "a";
  b.stream() << "b";
  a.commit();
  b.commit();  // last rename wins, both complete files
  EXPECT_EQ(read(dir_ / "same.txt"), "b");
}

TEST_F(AtomicFileTest, MakeDirectoriesCreatesParentsAndRefusesFiles) {
  fivebar::make_directories(dir_ / "x" / "y");
  EXPECT_TRUE(fs::is_directory(dir_ / "x" / "y"));
  fivebar::make_directories(dir_ / "x" / "y");  // idempotent
  write_file_atomic(dir_ / "file", "");
  EXPECT_THROW(fivebar::make_directories(dir_ / "file"), IoError);
  EXPECT_THROW(fivebar::make_directories(dir_ / "file" / "sub"), IoError);
}

// --- resolve_output_dir ---------------------------------------------------------------------------

struct Resolved {
  const char* root;
  const char* name;
  const char* expected;
};

class ResolveInside : public ::testing::TestWithParam<Resolved> {};

TEST_P(ResolveInside, StaysUnderTheRoot) {
  const auto& c = GetParam();
  SCOPED_TRACE(std::string("root='") + c.root + "' name='" + c.name + "'");
  EXPECT_EQ(resolve_output_dir(c.root, c.name), fs::path(c.expected));
}

INSTANTIATE_TEST_SUITE_P(Names, ResolveInside,
                         ::testing::Values(Resolved{"outputs", "iros2022", "outputs/iros2022"},
                                           Resolved{"outputs/", "iros2022", "outputs/iros2022"},
                                           Resolved{"./outputs/./", "iros2022", "outputs/iros2022"},
                                           Resolved{"/tmp/x", "a/b", "/tmp/x/a/b"},
                                           Resolved{"/tmp/x", "a/../b", "/tmp/x/b"},
                                           Resolved{"/tmp/x", "../x/y", "/tmp/x/y"},  // lexically inside
                                           Resolved{"/tmp/x", "name/", "/tmp/x/name"},
                                           Resolved{"../elsewhere", "n", "../elsewhere/n"},
                                           Resolved{".", "n", "n"},
                                           Resolved{"", "n", "n"},
                                           Resolved{"/", "n", "/n"},
                                           Resolved{"outputs", "v1.2-rc_3", "outputs/v1.2-rc_3"}));

class ResolveEscaping : public ::testing::TestWithParam<Resolved> {};

TEST_P(ResolveEscaping, IsRefusedWithInputError) {
  const auto& c = GetParam();
  SCOPED_TRACE(std::string("root='") + c.root + "' name='" + c.name + "'");
  EXPECT_THAT([&] { (void)resolve_output_dir(c.root, c.name); },
              ::testing::ThrowsMessage<InputError>(HasSubstr(std::string("'") + c.name + "'")));
}

INSTANTIATE_TEST_SUITE_P(Names, ResolveEscaping,
                         ::testing::Values(Resolved{"outputs", "..", ""}, Resolved{"outputs", "../x", ""},
                                           Resolved{"outputs", "a/../../x", ""}, Resolved{"outputs", "/etc", ""},
                                           Resolved{"outputs", "/", ""}, Resolved{"outputs", "", ""},
                                           Resolved{"outputs", ".", ""}, Resolved{"outputs", "a/..", ""},
                                           Resolved{"/tmp/x", "../xx/y", ""}, Resolved{".", "..", ""},
                                           Resolved{"/", "..", ""}));

TEST(ResolveOutputDir, TouchesNoFile) {
  const fs::path root = fs::temp_directory_path() / "fivebar_test_io_never_created";
  EXPECT_EQ(resolve_output_dir(root, "n"), root / "n");
  EXPECT_FALSE(fs::exists(root));
}

}  // namespace
