// `femto render` under MPI (docs/distributed.md): the processes started by mpirun or srun
// share one render's passes and combine their films into rank 0's, which alone writes.
// Built from cli/mpi.cpp when FEMTO_MPI is on, else from cli/mpi_none.cpp.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "femto/accumulator.h"
#include "femto/host.h"

namespace femto::cli {

class Distributed : public PassGroup {
public:
    /// Adds every process's totals into rank 0's `totals` (the same list, in the same order,
    /// in every process), in chunks: rank 0 holds one chunk more than its own film. Returns
    /// the bytes this process sent (0 on rank 0).
    virtual uint64_t combine(const std::vector<Accumulator>& totals) = 0;
    /// The render's statistics over every process (rays and refused contributions added, the
    /// longest time), on rank 0.
    virtual RenderStats combine_stats(const RenderStats& mine) = 0;
    /// Worker threads for this process when the user named none: the cores it may run on,
    /// shared with the other processes of the job on the same machine (unless mpirun bound
    /// each process to cores of its own).
    virtual int default_threads() const = 0;
    /// Ends the job with `exit_code` from any process (a process that fails alone must not
    /// leave the others waiting for it).
    [[noreturn]] virtual void abort(int exit_code) = 0;
};

}  // namespace femto::cli

namespace femto::bench {
class StudyGroup;
}

namespace femto::cli {

/// The processes of `group` as a distributed `femto bench` study sees them: the first
/// `runs_per_machine` processes of each machine take runs.
std::unique_ptr<bench::StudyGroup> make_study_group(Distributed& group, int runs_per_machine);

/// Starts MPI when this process was launched by an MPI launcher (mpirun, srun) as part of a
/// job of more than one process; otherwise returns null and femto renders alone.
std::unique_ptr<Distributed> start_distributed(int& argc, char**& argv);
/// Ends MPI after a successful run (every process must call it).
void finish_distributed(std::unique_ptr<Distributed> group);
/// What `femto --version` says about distributed rendering.
std::string distributed_support();

}  // namespace femto::cli
