// Shared by the libFuzzer harnesses: running one input and classifying its outcome, the
// tallies printed at exit, and the scratch file the binary readers' inputs are written to.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>

#include "femto/object.h"

namespace femto::fuzz {

/// Runs `load` on one input. The expected outcomes are: it returns (the input is accepted),
/// or it throws a femto::SceneError whose message has a file:line:col location (the CLI's
/// exit 2). Anything else, a SceneError without a location or another exception type, is a
/// finding: it is printed and the process aborts, so libFuzzer keeps the input as a crash.
void run(const std::function<void()>& load);

/// As run(), for a reader of files that are not scenes (a cube for `femto viz`): its errors
/// name the file instead of a line and column, so a SceneError counts as located when its
/// message holds `path`. SceneErrors thrown by `then` (computations on what was read, which the
/// CLI reports with exit 2 as well) count as located whatever they say.
void run_file(const std::string& path, const std::function<void()>& read,
              const std::function<void()>& then = {});

/// This process's scratch folder (created on first use, removed at exit).
const std::string& scratch_dir();

/// Writes `size` bytes to a file named `name` in a scratch folder of this process (removed
/// at exit) and returns its absolute path: femto's readers take files, not memory.
std::string write_scratch(const std::string& name, const uint8_t* data, size_t size);

/// One input of a binary reader: writes the bytes to the scratch file `file_name` and, under
/// run(), creates plugin `type` of `kind` (as the loader does, schema checked) with its
/// parameter `parameter` naming that file at a location, so that errors are located.
void read_plugin_file(PluginKind kind, const std::string& type, const std::string& parameter,
                      const std::string& file_name, const uint8_t* data, size_t size);

}  // namespace femto::fuzz
