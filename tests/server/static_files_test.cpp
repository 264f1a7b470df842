// The static file server refuses every path outside its folders: "..", encoded "..", backslashes, NUL, and symlinks
// that leave the folder; it serves what is inside (index.html for a folder) with a content type.
#include "server/static_files.h"
#include "support/test_support.h"

#include <gtest/gtest.h>

#include <fstream>

namespace ff::server {
namespace {
namespace fs = std::filesystem;

class StaticFilesTest : public ::testing::Test {
 protected:
  void SetUp() override {
    base_ = test::temp_dir("static-files");
    fs::create_directories(base_ / "web" / "src");
    fs::create_directories(base_ / "three" / "build");
    std::ofstream(base_ / "web" / "index.html") << "<html>";
    std::ofstream(base_ / "web" / "src" / "main.js") << "x";
    std::ofstream(base_ / "three" / "build" / "three.module.js") << "y";
    std::ofstream(base_ / "secret.txt") << "secret";
    fs::create_symlink(base_ / "secret.txt", base_ / "web" / "link.txt");
  }
  void TearDown() override { fs::remove_all(base_); }
  StaticFiles files() const { return StaticFiles({{"/", base_ / "web"}, {"/vendor/three/", base_ / "three"}}); }
  fs::path base_;
};

TEST_F(StaticFilesTest, ServesInsideItsFolders) {
  const auto f = files();
  auto r = f.resolve("/");
  EXPECT_EQ(r.status, 200);
  EXPECT_EQ(r.file.filename(), "index.html");
  EXPECT_EQ(r.mime, "text/html; charset=utf-8");
  r = f.resolve("/src/main.js?v=3#x");
  EXPECT_EQ(r.status, 200);
  EXPECT_EQ(r.mime, "text/javascript; charset=utf-8");
  EXPECT_EQ(f.resolve("/vendor/three/build/three.module.js").status, 200);
  EXPECT_EQ(f.resolve("/src/%6Dain.js").status, 200);  // an encoded ordinary letter is fine
  EXPECT_EQ(f.resolve("/./src//main.js").status, 200);
  EXPECT_EQ(f.resolve("/missing.js").status, 404);
}

TEST_F(StaticFilesTest, RefusesEverythingOutside) {
  const auto f = files();
  for (const char* bad : {"/../secret.txt", "/../../etc/passwd", "/src/../../secret.txt", "/%2e%2e/secret.txt",
                          "/%2E%2E/%2e%2e/etc/passwd", "/..%2fsecret.txt", "/..%2F..%2Fetc%2Fpasswd", "/src/..%5c..%5csecret.txt",
                          "/vendor/three/../../secret.txt", "/vendor/three/%2e%2e/%2e%2e/secret.txt", "/link.txt",
                          "/%00/../secret.txt", "/..\\secret.txt", "/src/main.js%00.html"}) {
    const int s = f.resolve(bad).status;
    EXPECT_TRUE(s == 403 || s == 404 || s == 400) << bad << " -> " << s;
  }
  // Double encoding is decoded once: "%252e%252e" is a file literally named "%2e%2e", which does not exist.
  EXPECT_EQ(f.resolve("/%252e%252e/secret.txt").status, 404);
  EXPECT_EQ(f.resolve("/%zz").status, 400);
  EXPECT_EQ(f.resolve("/%2").status, 400);
  EXPECT_EQ(f.resolve("relative").status, 400);
}

TEST(PercentDecode, OnePass) {
  EXPECT_EQ(percent_decode("/a%20b"), "/a b");
  EXPECT_EQ(percent_decode("%252e"), "%2e");
  EXPECT_FALSE(percent_decode("%g0"));
  EXPECT_FALSE(percent_decode("abc%"));
}

}  // namespace
}  // namespace ff::server
