#include "femto/input_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace femto {

namespace {

std::string open_error(int error) {
    if (error == ENOENT) return "no such file";
    if (error == EACCES) return "permission denied";
    return std::strerror(error);
}

// Opens `path` for reading if it is a regular file: returns the descriptor and its size, or -1
// and the reason. O_NONBLOCK because opening a FIFO that has no writer blocks in open() itself.
int open_regular_file(const std::string& path, uint64_t& size, std::string& problem) {
    const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) {
        const int error = errno;
        struct stat link {};
        problem = error == ENOENT && ::lstat(path.c_str(), &link) == 0 && S_ISLNK(link.st_mode)
                      ? "it is a symbolic link to a file that does not exist"
                      : open_error(error);
        return -1;
    }
    struct stat st {};
    if (::fstat(fd, &st) != 0)
        problem = open_error(errno);
    else if (S_ISDIR(st.st_mode))
        problem = "it is a directory";
    else if (!S_ISREG(st.st_mode))
        problem =
            "it is not a regular file (a FIFO, a device or a socket could block or never end)";
    if (!problem.empty()) {
        ::close(fd);
        return -1;
    }
    size = uint64_t(st.st_size);
    return fd;
}

}  // namespace

InputFile::InputFile(const std::string& path, const SourceLocation& where)
    : path_(path), where_(where) {
    std::string problem;
    fd_ = open_regular_file(path, size_, problem);
    if (fd_ < 0) throw SceneError(where_, "cannot open \"" + path + "\": " + problem);
}

InputFile::~InputFile() {
    if (fd_ >= 0) ::close(fd_);
}

size_t InputFile::read(void* out, size_t count) {
    if (uint64_t(count) > size_ - offset_) count = size_t(size_ - offset_);
    size_t done = 0;
    while (done < count) {
        const ssize_t n = ::read(fd_, static_cast<char*>(out) + done, count - done);
        if (n < 0 && errno == EINTR) continue;
        if (n < 0)
            throw SceneError(where_,
                             "cannot read \"" + path_ + "\": " + std::string(std::strerror(errno)));
        if (n == 0) break;  // the file shrank meanwhile
        done += size_t(n);
    }
    offset_ += done;
    return done;
}

std::string InputFile::read_rest() {
    std::string data(size_t(size_ - offset_), '\0');
    data.resize(read(data.data(), data.size()));
    return data;
}

std::string input_file_problem(const std::string& path) {
    uint64_t size = 0;
    std::string problem;
    const int fd = open_regular_file(path, size, problem);
    if (fd >= 0) ::close(fd);
    return problem;
}

}  // namespace femto
