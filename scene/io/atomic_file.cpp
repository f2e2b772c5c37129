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

std::string output_target(const std::string& path) {
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
    return target.string();
}

TemporaryFile write_temporary(const std::string& path, const std::function<void(std::FILE*)>& write) {
    namespace fs = std::filesystem;
    const fs::path target(output_target(path));
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
    return {tmpl, target.string(), path};
}

void commit_temporaries(const std::vector<TemporaryFile>& files) {
    for (size_t i = 0; i < files.size(); ++i)
        if (std::rename(files[i].tmp.c_str(), files[i].target.c_str()) != 0) {
            const int e = errno;
            discard_temporaries({files.begin() + long(i), files.end()});
            throw Error("cannot write '" + files[i].path + "': " + std::strerror(e));
        }
}

void discard_temporaries(const std::vector<TemporaryFile>& files) {
    for (const TemporaryFile& f : files) ::unlink(f.tmp.c_str());
}

void write_file_atomically(const std::string& path, const std::function<void(std::FILE*)>& write) {
    commit_temporaries({write_temporary(path, write)});
}

namespace {

/// Whether paths a and b name one file: by device and inode when both exist, else by their
/// normalised absolute paths.
bool same_file(const std::string& a, const std::string& b) {
    namespace fs = std::filesystem;
    std::error_code e1, e2, e3;
    if (fs::exists(a, e1) && fs::exists(b, e2)) return fs::equivalent(a, b, e3) && !e3;
    const fs::path x = fs::weakly_canonical(a, e1), y = fs::weakly_canonical(b, e2);
    return !e1 && !e2 && !x.empty() && x == y;
}

}  // namespace

void refuse_clashing_files(const std::vector<NamedFile>& outputs, const std::vector<NamedFile>& inputs) {
    for (size_t i = 0; i < outputs.size(); ++i) {
        const NamedFile& out = outputs[i];
        if (out.path.empty()) continue;
        for (const NamedFile& in : inputs)
            if (!in.path.empty() && same_file(out.path, in.path))
                throw Error(out.what + " '" + out.path + "' is this command's input (" + in.what +
                            "); choose another file");
        for (size_t j = 0; j < i; ++j)
            if (!outputs[j].path.empty() && same_file(out.path, outputs[j].path))
                throw Error(out.what + " '" + out.path + "' is also " + outputs[j].what +
                            "; two outputs cannot share a file");
    }
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
    if (::stat(path.c_str(), &st) != 0) return errno == ENOENT ? kDoesNotExist : std::string(std::strerror(errno));
    return not_regular_reason(st.st_mode);
}

}  // namespace bvhlab::scene
