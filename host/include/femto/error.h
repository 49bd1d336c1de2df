// femto public API: error types. A SceneError means bad input (exit code 2); anything else
// escaping a render is an internal failure (exit code 1).
#pragma once

#include <stdexcept>
#include <string>

namespace femto {

/// Where something was written in a scene file; an empty file means "not from a file".
struct SourceLocation {
    std::string file;
    int line = 0;
    int column = 0;
    /// "file:line:col", or "" when unknown.
    std::string str() const {
        if (file.empty()) return {};
        return file + ":" + std::to_string(line) + ":" + std::to_string(column);
    }
};

/// Bad input: a scene, a parameter, a file or a command-line value. `what()` is the full
/// message, prefixed with the location when there is one.
class SceneError : public std::runtime_error {
public:
    SceneError(const SourceLocation& loc, const std::string& message)
        : std::runtime_error(loc.file.empty() ? message : loc.str() + ": " + message),
          location_(loc),
          message_(message) {}
    explicit SceneError(const std::string& message) : SceneError(SourceLocation{}, message) {}
    const SourceLocation& location() const { return location_; }
    const std::string& message() const { return message_; }

private:
    SourceLocation location_;
    std::string message_;
};

}  // namespace femto
