// femto-watch PID: waits for femto's rendering process PID, its child, and passes on how it
// ended (cli/watch.h). femto execs it in the process that mpirun or srun started; it is not
// meant to be run by hand.
#include <cstdio>
#include <cstdlib>

#include "watch.h"

int main(int argc, char** argv) {
    char* end = nullptr;
    const long pid = argc == 2 ? std::strtol(argv[1], &end, 10) : 0;
    if (pid <= 0 || *end != '\0') {
        std::fprintf(stderr,
                     "femto-watch: femto runs this for each process of a distributed render; "
                     "usage: femto-watch PID\n");
        return 2;
    }
    femto::cli::watch_render_process(pid_t(pid));
}
