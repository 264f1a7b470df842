// Atomic outputs (io/atomic_file.h): a reader never sees a half-written file, a failed write leaves the previous
// file as it was and no temporary behind, and temporaries of writers that died are found and removed.
#include "io/atomic_file.h"
#include "support/test_support.h"

#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <fstream>
#include <iterator>

namespace ff::io {
namespace {
namespace fs = std::filesystem;

std::string read_text(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

std::vector<std::string> names_in(const fs::path& dir) {
  std::vector<std::string> out;
  for (const auto& e : fs::recursive_directory_iterator(dir)) out.push_back(fs::relative(e.path(), dir).string());
  std::sort(out.begin(), out.end());
  return out;
}

std::span<const std::uint8_t> bytes_of(const std::string& s) {
  return {reinterpret_cast<const std::uint8_t*>(s.data()), s.size()};
}

TEST(AtomicFile, WritesAndReplacesWholeFilesWithNoTemporaryLeft) {
  const auto dir = test::temp_dir("atomic");
  ASSERT_TRUE(write_file_atomic(dir / "a.txt", std::string("first")).ok());
  EXPECT_EQ(read_text(dir / "a.txt"), "first");
  ASSERT_TRUE(write_file_atomic(dir / "a.txt", std::string("second, longer")).ok());
  EXPECT_EQ(read_text(dir / "a.txt"), "second, longer");
  ASSERT_TRUE(write_file_atomic(dir / "a.txt", std::string()).ok());
  EXPECT_EQ(read_text(dir / "a.txt"), "");
  EXPECT_EQ(names_in(dir), std::vector<std::string>{"a.txt"});
}

TEST(AtomicFile, AFailedWriteNamesThePathAndLeavesWhatWasThere) {
  const auto dir = test::temp_dir("atomic_fail");
  // The target is a folder: the temporary is written, the rename fails, the temporary is removed.
  fs::create_directories(dir / "out" / "keep");
  ASSERT_TRUE(write_file_atomic(dir / "out" / "keep" / "old.txt", std::string("old")).ok());
  const Status st = write_file_atomic(dir / "out" / "keep", std::string("new"));
  ASSERT_FALSE(st.ok());
  EXPECT_EQ(st.error().kind, Error::Kind::Io);
  EXPECT_NE(st.error().message.find((dir / "out" / "keep").string()), std::string::npos) << st.error().message;
  EXPECT_EQ(read_text(dir / "out" / "keep" / "old.txt"), "old");
  EXPECT_EQ(names_in(dir / "out"), (std::vector<std::string>{"keep", "keep/old.txt"}));
  // The parent is a file: nothing can be created at all.
  ASSERT_TRUE(write_file_atomic(dir / "plain", std::string("x")).ok());
  EXPECT_FALSE(write_file_atomic(dir / "plain" / "child.txt", std::string("y")).ok());
  EXPECT_EQ(read_text(dir / "plain"), "x");
}

TEST(AtomicFile, AWriterWithoutCommitLeavesTheOldFileAndNoTemporary) {
  const auto dir = test::temp_dir("atomic_writer");
  const fs::path p = dir / "cache.pc2";
  ASSERT_TRUE(write_file_atomic(p, std::string("previous")).ok());
  {
    AtomicFileWriter w;
    ASSERT_TRUE(w.open(p).ok());
    ASSERT_TRUE(w.write(bytes_of("partial data")).ok());
    EXPECT_EQ(read_text(p), "previous");  // nothing published before commit
    EXPECT_EQ(names_in(dir).size(), 2u);  // the file and the writer's temporary
  }  // destroyed without commit: an error path or an exception
  EXPECT_EQ(read_text(p), "previous");
  EXPECT_EQ(names_in(dir), std::vector<std::string>{"cache.pc2"});
}

TEST(AtomicFile, AWriterPatchesItsHeaderAndPublishesOnCommit) {
  const auto dir = test::temp_dir("atomic_commit");
  const fs::path p = dir / "out.bin";
  AtomicFileWriter w;
  ASSERT_TRUE(w.open(p).ok());
  EXPECT_FALSE(w.open(p).ok());  // one file at a time
  ASSERT_TRUE(w.write(bytes_of("count=?;")).ok());
  ASSERT_TRUE(w.write(bytes_of("abc")).ok());
  ASSERT_TRUE(w.write_at(6, bytes_of("3")).ok());
  EXPECT_FALSE(fs::exists(p));
  ASSERT_TRUE(w.commit().ok());
  EXPECT_EQ(read_text(p), "count=3;abc");
  EXPECT_EQ(names_in(dir), std::vector<std::string>{"out.bin"});
  EXPECT_FALSE(w.write(bytes_of("late")).ok());  // closed by the commit
  EXPECT_FALSE(w.commit().ok());
}

TEST(AtomicFile, RemovesOnlyTheTemporariesOfWritersThatAreGone) {
  const auto dir = test::temp_dir("atomic_stale");
  // A process id that has exited: a child that ends at once, reaped.
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) ::_exit(0);
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  fs::create_directories(dir / "particles");
  const std::string dead = std::to_string(child), alive = std::to_string(::getppid()), self = std::to_string(::getpid());
  for (const std::string& name : std::vector<std::string>{"report.json.tmp." + dead, "particles/frame_00007.ply.tmp." + dead,
                           "metrics.csv.tmp." + alive, "state.tmp." + self, "notes.tmp.12ab", "report.json"})
    std::ofstream(dir / name) << "x";
  EXPECT_EQ(remove_stale_temp_files(dir), 2u);
  EXPECT_EQ(names_in(dir), (std::vector<std::string>{"metrics.csv.tmp." + alive, "notes.tmp.12ab", "particles",
                                                     "report.json", "state.tmp." + self}));
  EXPECT_EQ(remove_stale_temp_files(dir / "no_such_folder"), 0u);
}

TEST(AtomicFile, EnsureWritableDirCreatesFoldersAndRefusesFiles) {
  const auto dir = test::temp_dir("atomic_dirs");
  EXPECT_TRUE(ensure_writable_dir(dir / "a" / "b" / "c").ok());
  EXPECT_TRUE(fs::is_directory(dir / "a" / "b" / "c"));
  EXPECT_TRUE(ensure_writable_dir(dir / "a").ok());  // already there
  ASSERT_TRUE(write_file_atomic(dir / "file", std::string("x")).ok());
  const Status st = ensure_writable_dir(dir / "file");
  ASSERT_FALSE(st.ok());
  EXPECT_NE(st.error().message.find("is not a folder"), std::string::npos) << st.error().message;
  EXPECT_FALSE(ensure_writable_dir(dir / "file" / "sub").ok());
}

}  // namespace
}  // namespace ff::io
