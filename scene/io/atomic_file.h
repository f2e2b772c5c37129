// SPDX-License-Identifier: MIT
// Output files written whole or not at all: into a temporary file in the same folder, flushed
// to disk, then renamed over the final name. A killed run or a full disk leaves the old file
// (or none), never a half-written one under the final name. Also the checks of what a path
// is, for the one-line messages about inputs and outputs that are not regular files.
#pragma once

#include <cstdio>
#include <functional>
#include <string>
#include <vector>

namespace bvhlab::scene {

/// Calls `write(f)` on a temporary file beside `path` and renames it to `path` when `write`
/// returns and every byte reached the disk. A `path` that is a symbolic link is written
/// through it (the link stays, its target is replaced); one that is (or links to) a folder,
/// pipe, device or socket is refused, never replaced. On any failure (the temporary cannot be created,
/// `write` throws, a write, flush, sync or the rename fails) the temporary is removed, `path`
/// is left as it was, and bvhlab::Error names `path` and the reason (strerror). `write`
/// reports its own failures by throwing, or by a failed stdio call (checked with ferror).
void write_file_atomically(const std::string& path, const std::function<void(std::FILE*)>& write);

/// The file that writing `path` replaces: `path`, or what it links to. Throws bvhlab::Error
/// when it is a folder, a pipe, a device or a socket.
std::string output_target(const std::string& path);

/// A written, synced temporary file and the file it is to replace.
struct TemporaryFile {
    std::string tmp;     ///< beside the target
    std::string target;  ///< `path`, or what it links to
    std::string path;    ///< as the caller named it, for messages
};

/// write_file_atomically() in two halves, for outputs that must all appear or none: first
/// every temporary (the half that fails on a full disk; on failure its temporary is removed
/// and bvhlab::Error names `path`), then commit_temporaries() renames them all. A caller that
/// stops between the halves removes them with discard_temporaries().
TemporaryFile write_temporary(const std::string& path, const std::function<void(std::FILE*)>& write);
/// Renames every temporary over its target (a rename within one folder: it fails only when the
/// folder changes meanwhile; then the rest are removed and bvhlab::Error names the file).
void commit_temporaries(const std::vector<TemporaryFile>& files);
/// Removes the temporaries (never the targets).
void discard_temporaries(const std::vector<TemporaryFile>& files);

/// A file of a command and the option that names it ("--env", "texture of material 'wood'").
struct NamedFile {
    std::string what;
    std::string path;  ///< empty: no file, skipped
};

/// Throws bvhlab::Error when an output is the same file as an input, or as another output:
/// by device and inode when both exist (through links and other names), else by normalised
/// path. The message names both roles: "--cost-image 'a.pfm' is also --env; choose another
/// file". Called before anything is written.
void refuse_clashing_files(const std::vector<NamedFile>& outputs, const std::vector<NamedFile>& inputs);

/// Why a file of stat mode `mode` cannot be read or written as a file: "it is a directory",
/// "it is a pipe (FIFO)", "it is a device", "it is a socket"; "" for a regular file.
std::string not_regular_reason(unsigned mode);

/// regular_file_problem()'s answer for a path that does not exist (callers that treat a missing
/// file apart from a folder or a device compare with it).
inline constexpr const char* kDoesNotExist = "does not exist";

/// "" when `path` is a regular file (through links); otherwise why it cannot be read, as a
/// phrase for "'path' ...": kDoesNotExist, "it is a directory", "it is a pipe (FIFO)", ...
std::string regular_file_problem(const std::string& path);

}  // namespace bvhlab::scene
