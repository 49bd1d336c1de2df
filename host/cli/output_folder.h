// The output folders of femto's commands (render, viz, btf synth): made before any work and
// checked writable, so that nothing is computed only to fail when it is written.
#pragma once

#include <fmt/format.h>
#include <unistd.h>

#include <filesystem>

#include "femto/error.h"

namespace femto::cli {

/// Creates `dir` and its parents ("" is the current folder) and checks that it is writable;
/// throws SceneError naming the folder.
inline void prepare_output_folder(std::filesystem::path dir) {
    if (dir.empty()) dir = ".";
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    if (ec || !std::filesystem::is_directory(dir))
        throw SceneError(fmt::format("cannot create the output folder \"{}\"{}", dir.string(),
                                     ec ? ": " + ec.message() : ""));
    if (access(dir.c_str(), W_OK) != 0)
        throw SceneError(fmt::format("the output folder \"{}\" is not writable", dir.string()));
}

}  // namespace femto::cli
