// femto public API: reading the files a scene names (included scene files, meshes, grid
// volumes, images) so that bad input cannot hang the host or exhaust its memory.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "femto/error.h"

namespace femto {

/// An input file open for reading. Only regular files are accepted: a FIFO would block its
/// reader forever and a device such as /dev/zero never ends. The file is opened without
/// blocking and checked on the open descriptor, before anything is read, and reads stop at the
/// size it had then (a file that grows meanwhile cannot make a reader run on).
class InputFile {
public:
    /// Throws a SceneError located at `where`: "cannot open "PATH": REASON" (see
    /// input_file_problem()).
    InputFile(const std::string& path, const SourceLocation& where);
    ~InputFile();
    InputFile(const InputFile&) = delete;
    InputFile& operator=(const InputFile&) = delete;

    const std::string& path() const { return path_; }
    /// Size in bytes when the file was opened.
    uint64_t size() const { return size_; }
    /// Reads up to `count` bytes into `out`, never past size(); returns how many were read
    /// (fewer only at the end). A read error is a SceneError located at `where`.
    size_t read(void* out, size_t count);
    /// The rest of the file, up to size().
    std::string read_rest();

private:
    std::string path_;
    SourceLocation where_;
    int fd_ = -1;
    uint64_t size_ = 0, offset_ = 0;
};

/// Why `path` cannot be an input file: "no such file", "it is a directory", "it is not a
/// regular file (...)", "permission denied", ...; "" when it is a readable regular file. For
/// readers that open files themselves (OpenImageIO), checked just before they do.
std::string input_file_problem(const std::string& path);

}  // namespace femto
