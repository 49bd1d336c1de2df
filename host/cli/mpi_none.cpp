// femto built without MPI: every render is a single process.
#include "bench/runner.h"
#include "distributed.h"

namespace femto::cli {

std::unique_ptr<Distributed> start_distributed(int&, char**&) { return nullptr; }
std::unique_ptr<bench::StudyGroup> make_study_group(Distributed&, int) { return nullptr; }
void finish_distributed(std::unique_ptr<Distributed>) {}
std::string distributed_support() {
    return "distributed rendering: no (built without MPI; install libopenmpi-dev and rebuild)";
}

}  // namespace femto::cli
