// SPDX-License-Identifier: MIT
#include "scene/io/atomic_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>

#include "accel/core/check.h"

namespace bvhlab::scene {

void write_file_atomically(const std::string& path, const std::function<void(std::FILE*)>& write) {
    namespace fs = std::filesystem;
    fs::path target(path);
    struct stat st {};
    if (::stat(path.c_str(), &st) == 0) {
        if (S_ISDIR(st.st_mode)) throw Error("cannot write '" + path + "': it is a folder");
        if (!S_ISREG(st.st_mode))
            throw Error("cannot write '" + path + "': " + not_regular_reason(st.st_mode) +
                        "; bvhlab writes regular files only");
        std::error_code ec;
        if (fs::is_symlink(target, ec)) target = fs::canonical(target, ec);  // the link stays
        if (ec) throw Error("cannot write '" + path + "': " + ec.message());
    }
    // mkstemp in the target's folder, so that the rename stays on one file system.
    std::string tmpl = (target.parent_path().empty() ? fs::path(".") : target.parent_path()) /
                       ("." + target.filename().string() + ".tmp-XXXXXX");
    const int fd = ::mkstemp(tmpl.data());
    if (fd < 0) throw Error("cannot write '" + path + "': " + std::strerror(errno));
    // mkstemp makes the file 0600; give it what a plain fopen would (0666 less the umask).
    const mode_t mask = ::umask(0);
    ::umask(mask);
    ::fchmod(fd, 0666 & ~mask);
    std::FILE* f = ::fdopen(fd, "wb");
    int raw = f ? -1 : fd;  // the descriptor still to close when fdopen failed
    // Every failure from here: close what is open, remove the temporary, name the reason.
    auto discard = [&] {
        if (f) std::fclose(f);
        if (raw >= 0) ::close(raw);
        f = nullptr;
        raw = -1;
        ::unlink(tmpl.c_str());
    };
    auto fail = [&](int e) {
        discard();
        throw Error("cannot write '" + path + "': " + std::strerror(e ? e : EIO));
    };
    if (!f) fail(errno);
    try {
        write(f);
    } catch (...) {
        discard();
        throw;
    }
    if (std::ferror(f) || std::fflush(f) != 0 || ::fsync(::fileno(f)) != 0) fail(errno);
    const int closed = std::fclose(f);
    f = nullptr;
    if (closed != 0) fail(errno);
    if (std::rename(tmpl.c_str(), target.c_str()) != 0) fail(errno);
}

void refuse_overwriting_input(const std::string& out, const std::string& in, const std::string& what) {
    namespace fs = std::filesystem;
    std::error_code e1, e2, e3;
    bool same = fs::exists(out, e1) && fs::exists(in, e2) && fs::equivalent(out, in, e3) && !e3;
    if (!same) {
        const fs::path a = fs::weakly_canonical(out, e1), b = fs::weakly_canonical(in, e2);
        same = !e1 && !e2 && !a.empty() && a == b;
    }
    if (same) throw Error(what + " '" + out + "' is this command's input; choose another file");
}

std::string not_regular_reason(unsigned mode) {
    if (S_ISREG(mode)) return "";
    if (S_ISDIR(mode)) return "it is a directory";
    if (S_ISFIFO(mode)) return "it is a pipe (FIFO)";
    if (S_ISCHR(mode) || S_ISBLK(mode)) return "it is a device";
    if (S_ISSOCK(mode)) return "it is a socket";
    return "it is not a regular file";
}

std::string regular_file_problem(const std::string& path) {
    struct stat st {};
    if (::stat(path.c_str(), &st) != 0) return errno == ENOENT ? "does not exist" : std::string(std::strerror(errno));
    return not_regular_reason(st.st_mode);
}

}  // namespace bvhlab::scene
