// The signals that stop femto and keep what was rendered (main.cpp's handler). The MPI watcher
// (watch.h) ignores the same ones: they reach the render process through its process group.
#pragma once

#include <csignal>

namespace femto::cli {

inline constexpr int kStopSignals[] = {SIGINT, SIGTERM, SIGUSR1};

}  // namespace femto::cli
