// SPDX-License-Identifier: MIT
// Output files are written whole or not at all, and never over the command's own input.
#include "scene/io/atomic_file.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <stdexcept>

#include "accel/core/check.h"
#include "tests/support/test_support.h"

namespace bvhlab::scene {
namespace {

namespace fs = std::filesystem;

/// Files in `dir` whose name starts with `prefix` (leftover temporaries).
size_t count_with_prefix(const fs::path& dir, const std::string& prefix) {
    size_t n = 0;
    for (const auto& e : fs::directory_iterator(dir)) n += e.path().filename().string().rfind(prefix, 0) == 0;
    return n;
}

TEST(AtomicFile, ReplacesWholeAndLeavesNoTemporary) {
    test::TempFile f("atomic.txt", "old contents");
    write_file_atomically(f.path(), [](std::FILE* out) { std::fputs("new contents", out); });
    EXPECT_EQ(test::read_file_bytes(f.path()), "new contents");
    const fs::path p(f.path());
    EXPECT_EQ(count_with_prefix(p.parent_path(), "." + p.filename().string() + ".tmp-"), 0u);
}

TEST(AtomicFile, AFailedWriteKeepsTheOldFile) {
    test::TempFile f("atomic_fail.txt", "the good file");
    EXPECT_THROW(write_file_atomically(f.path(),
                                       [](std::FILE* out) {
                                           std::fputs("half of a new", out);
                                           throw std::runtime_error("killed half-way");
                                       }),
                 std::runtime_error);
    EXPECT_EQ(test::read_file_bytes(f.path()), "the good file");
    const fs::path p(f.path());
    EXPECT_EQ(count_with_prefix(p.parent_path(), "." + p.filename().string() + ".tmp-"), 0u);
}

TEST(AtomicFile, UnwritablePlacesAreErrorsNamingThePath) {
    const std::string missing = "/nonexistent-bvhlab-dir/x.bin";
    try {
        write_file_atomically(missing, [](std::FILE*) {});
        FAIL() << "no error";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find(missing), std::string::npos) << e.what();
    }
    const std::string dir = fs::temp_directory_path().string();
    EXPECT_THROW(write_file_atomically(dir, [](std::FILE*) {}), Error);  // a folder
    EXPECT_TRUE(fs::is_directory(dir));
}

// A symbolic link is written through (the link stays, its target gets the contents); a
// device or a pipe is refused and left as it is, never replaced by a regular file.
TEST(AtomicFile, LinksAreWrittenThroughAndSpecialFilesRefused) {
    test::TempFile target("atomic_target.txt", "old");
    const fs::path link = fs::path(target.path()).parent_path() / "atomic_link.txt";
    fs::remove(link);
    fs::create_symlink(target.path(), link);
    write_file_atomically(link.string(), [](std::FILE* out) { std::fputs("through the link", out); });
    EXPECT_TRUE(fs::is_symlink(link));
    EXPECT_EQ(test::read_file_bytes(target.path()), "through the link");
    fs::remove(link);
    try {
        write_file_atomically("/dev/null", [](std::FILE*) {});
        FAIL() << "no error";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("it is a device"), std::string::npos) << e.what();
    }
    EXPECT_TRUE(fs::is_character_file("/dev/null"));
    EXPECT_EQ(regular_file_problem("/dev/null"), "it is a device");
    EXPECT_EQ(regular_file_problem(fs::temp_directory_path().string()), "it is a directory");
    EXPECT_EQ(regular_file_problem("/nonexistent-bvhlab-dir/x"), "does not exist");
    EXPECT_EQ(regular_file_problem(target.path()), "");
}

TEST(AtomicFile, OutputThatIsAnInputIsRefused) {
    test::TempFile f("input.obj", "v 0 0 0\n");
    const fs::path p(f.path());
    EXPECT_THROW(refuse_clashing_files({{"--out", f.path()}}, {{"the scene", f.path()}}), Error);
    // The same file spelled differently, and through a hard link.
    const std::string dotted = (p.parent_path() / "." / p.filename()).string();
    EXPECT_THROW(refuse_clashing_files({{"--out", dotted}}, {{"the scene", f.path()}}), Error);
    const std::string link = f.path() + ".link";
    fs::create_hard_link(f.path(), link);
    EXPECT_THROW(refuse_clashing_files({{"--out", link}}, {{"the scene", f.path()}}), Error);
    fs::remove(link);
    EXPECT_NO_THROW(refuse_clashing_files({{"--out", f.path() + ".tree"}}, {{"the scene", f.path()}}));
    EXPECT_NO_THROW(refuse_clashing_files({{"--out", f.path()}}, {{"the scene", "gen:soup:100"}}));
}

}  // namespace
}  // namespace bvhlab::scene
