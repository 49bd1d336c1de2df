// Watching one process of a distributed render (docs/distributed.md, "A process that dies"):
// the process mpirun or srun started waits for the femto that renders, its child, and passes on
// how it ended. Used by femto-watch (cli/watch_main.cpp, a small program, so that a watcher
// holds ~1 MB, not femto's libraries) and by femto itself where femto-watch is missing.
#pragma once

#include <signal.h>
#include <sys/wait.h>

#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "stop_signals.h"

namespace femto::cli {

/// Waits for `render` and exits as it did; if a signal other than a stop signal killed it, says
/// which process of the job died and exits 1, so that the launcher ends the job with femto's
/// status (not 128 + the signal) and a message about the render. Stop signals reach `render`
/// through the process group (mpirun, srun and scancel signal the group), so the watcher
/// ignores them and outlives the render.
[[noreturn]] inline void watch_render_process(pid_t render) {
    // Ignored, then unblocked (femto blocks them across the fork and the exec, and passes on
    // to the render process one that arrived before the fork): dropped here.
    sigset_t stop_signals;
    sigemptyset(&stop_signals);
    for (int sig : kStopSignals) {
        std::signal(sig, SIG_IGN);
        sigaddset(&stop_signals, sig);
    }
    sigprocmask(SIG_UNBLOCK, &stop_signals, nullptr);
    int status = 0;
    while (waitpid(render, &status, 0) < 0)
        if (errno != EINTR) {
            std::fprintf(stderr, "femto-watch: error: cannot wait for process %d (%s)\n",
                         int(render), std::strerror(errno));
            std::_Exit(1);
        }
    if (WIFEXITED(status)) std::_Exit(WEXITSTATUS(status));
    const int sig = WTERMSIG(status);
    // A second Ctrl-C aborts the render on purpose: the job ends as a single process would.
    for (int stop : kStopSignals)
        if (sig == stop) std::_Exit(128 + sig);
    const char* rank = std::getenv("OMPI_COMM_WORLD_RANK");
    if (!rank) rank = std::getenv("PMIX_RANK");
    if (!rank) rank = std::getenv("PMI_RANK");
    std::fprintf(stderr,
                 "femto: error: process %s of the MPI job (pid %d) died (%s, signal %d): the job "
                 "fails and nothing is written\n",
                 rank ? rank : "?", int(render), strsignal(sig), sig);
    std::_Exit(1);
}

}  // namespace femto::cli
