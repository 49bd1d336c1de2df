// `femto render` over MPI: passes shared round-robin (the renderer's PassGroup), films combined
// into rank 0 with point-to-point messages in a fixed order (render/combine.h), so that a job
// of N processes gives the same image on every run.
#include <fmt/format.h>
#include <mpi.h>
#include <sched.h>
#include <sys/prctl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>
#include <thread>
#include <utility>
#include <vector>

#include "bench/runner.h"
#include "distributed.h"
#include "render/combine.h"
#include "watch.h"

namespace femto::cli {

namespace {

constexpr int kTotalsTag = 7;
// Chunks of 4 MiB: large enough that latency is negligible, small enough that rank 0 holds
// little beyond its own film (one chunk of doubles and one receive buffer).
constexpr size_t kChunkBytes = size_t(4) << 20;

// The launchers' environment: Open MPI's mpirun, PMIx (srun --mpi=pmix, Open MPI 4+), PMI-1/2
// (MPICH, srun --mpi=pmi2).
int launched_size() {
    for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMIX_SIZE", "PMI_SIZE", "MPI_LOCALNRANKS"})
        if (const char* v = std::getenv(name)) return std::atoi(v);
    if (std::getenv("PMIX_RANK") || std::getenv("PMI_RANK")) return 2;  // size unknown: ask MPI
    return 0;
}

void check(int rc, const char* what) {
    if (rc != MPI_SUCCESS) throw std::runtime_error(fmt::format("MPI: {} failed ({})", what, rc));
}

// Waits for a non-blocking operation without spinning: Open MPI's blocking calls poll at full
// speed, which would take a core from the processes still rendering on the same machine (a
// process that finished its pass early, a study's idle processes beside a timed run).
void wait_politely(MPI_Request& request) {
    for (int done = 0;;) {
        check(MPI_Test(&request, &done, MPI_STATUS_IGNORE), "MPI_Test");
        if (done) return;
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
}

void broadcast_bytes(void* data, size_t bytes) {
    constexpr size_t kMaxMessage = size_t(1) << 30;  // MPI counts are ints
    for (size_t offset = 0; offset < bytes; offset += kMaxMessage) {
        MPI_Request request;
        check(MPI_Ibcast(static_cast<char*>(data) + offset,
                         int(std::min(kMaxMessage, bytes - offset)), MPI_BYTE, 0, MPI_COMM_WORLD,
                         &request),
              "MPI_Ibcast");
        wait_politely(request);
    }
}

// A process of the job that dies (killed for memory, a crash) would leave mpirun to end the
// job with its own status (128 + the signal) and a message about a rank, not a render. So the
// process the launcher started becomes a watcher (cli/watch.h): it runs femto again as its
// child (exec'd, not just forked: libraries' threads do not survive a fork), which is the MPI
// process and renders, and then turns itself into the small femto-watch program beside femto
// (exec keeps the child), or, if that is missing, waits as femto.
constexpr const char* kWatchedVariable = "FEMTO_MPI_WATCHED";

void watch_the_render_process(char** argv) {
    if (const char* value = std::getenv(kWatchedVariable); value && value == std::string("1"))
        return;  // this is the watched process (or the user asked for no watcher)
    std::error_code error;
    const std::filesystem::path self = std::filesystem::read_symlink("/proc/self/exe", error);
    // The program's own path, so that the child is named femto in ps and top (not "exe").
    const std::string femto = error ? "/proc/self/exe" : self.string();
    const std::string watch = (self.parent_path() / "femto-watch").string();
    // The child's environment, made before the fork (the child only calls exec).
    const std::string watched = std::string(kWatchedVariable) + "=";
    std::vector<std::string> environment{watched + "1"};
    for (char** variable = environ; *variable; ++variable)
        if (!std::string_view(*variable).starts_with(watched)) environment.emplace_back(*variable);
    std::vector<char*> envp;
    for (std::string& variable : environment) envp.push_back(variable.data());
    envp.push_back(nullptr);
    std::signal(SIGCHLD, SIG_DFL);  // an inherited SIG_IGN would reap the child before waitpid
    std::fflush(nullptr);           // buffered output must not be written twice
    // Stop signals wait until the watcher ignores them (a Ctrl-C in between must not end it);
    // one that arrives meanwhile is passed on to the render process below.
    sigset_t stop_signals, before;
    sigemptyset(&stop_signals);
    for (int sig : kStopSignals) sigaddset(&stop_signals, sig);
    sigprocmask(SIG_BLOCK, &stop_signals, &before);
    const pid_t watcher = getpid();
    const pid_t render = fork();
    if (render <= 0) sigprocmask(SIG_SETMASK, &before, nullptr);
    if (render < 0) return;  // cannot fork: render unwatched
    if (render == 0) {
        // Where the launcher signals only the process it started, killing the watcher must
        // not leave the render running on its own.
        prctl(PR_SET_PDEATHSIG, SIGKILL);
        if (getppid() != watcher) std::_Exit(1);
        execve(femto.c_str(), argv, envp.data());
        static const char message[] = "femto: error: cannot run femto again\n";
        [[maybe_unused]] auto n = write(STDERR_FILENO, message, sizeof(message) - 1);
        std::_Exit(1);
    }
    sigset_t pending;
    if (sigpending(&pending) == 0)
        for (int sig : kStopSignals)
            if (sigismember(&pending, sig)) kill(render, sig);
    const std::string pid = std::to_string(render);
    char* watch_argv[] = {const_cast<char*>(watch.c_str()), const_cast<char*>(pid.c_str()),
                          nullptr};
    execv(watch.c_str(), watch_argv);
    prctl(PR_SET_NAME, "femto-watch");
    watch_render_process(render);
}

class MpiGroup final : public Distributed {
public:
    MpiGroup() {
        check(MPI_Comm_rank(MPI_COMM_WORLD, &rank_), "MPI_Comm_rank");
        check(MPI_Comm_size(MPI_COMM_WORLD, &size_), "MPI_Comm_size");
    }
    int rank() const override { return rank_; }
    int size() const override { return size_; }

    bool any(bool stop) override {
        int flag = stop ? 1 : 0;
        MPI_Request request;
        check(MPI_Iallreduce(MPI_IN_PLACE, &flag, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD, &request),
              "MPI_Iallreduce");
        wait_politely(request);
        return flag != 0;
    }

    uint64_t combine(const std::vector<Accumulator>& totals) override {
        check_same_layout(totals);
        uint64_t sent = 0;
        if (rank_ == 0) {
            combine_accumulators(totals, size_, kChunkBytes, [](int r, void* buffer, size_t n) {
                check(MPI_Recv(buffer, int(n), MPI_BYTE, r, kTotalsTag, MPI_COMM_WORLD,
                               MPI_STATUS_IGNORE),
                      "MPI_Recv");
            });
        } else {
            send_accumulators(totals, kChunkBytes, [&](const void* data, size_t n) {
                check(MPI_Send(data, int(n), MPI_BYTE, 0, kTotalsTag, MPI_COMM_WORLD), "MPI_Send");
                sent += n;
            });
        }
        return sent;
    }

    RenderStats combine_stats(const RenderStats& mine) override {
        RenderStats all = mine;
        uint64_t counts[4] = {mine.rays, mine.rejected.nan, mine.rejected.infinite,
                              mine.rejected.negative};
        uint64_t sums[4] = {0, 0, 0, 0};
        check(MPI_Reduce(counts, sums, 4, MPI_UINT64_T, MPI_SUM, 0, MPI_COMM_WORLD), "MPI_Reduce");
        check(MPI_Reduce(&mine.seconds, &all.seconds, 1, MPI_DOUBLE, MPI_MAX, 0, MPI_COMM_WORLD),
              "MPI_Reduce");
        if (rank_ != 0) return mine;
        all.rays = sums[0];
        all.rejected = {sums[1], sums[2], sums[3]};
        return all;
    }

    int default_threads() const override {
        MPI_Comm node;
        int local = 1;
        if (MPI_Comm_split_type(MPI_COMM_WORLD, MPI_COMM_TYPE_SHARED, rank_, MPI_INFO_NULL,
                                &node) == MPI_SUCCESS) {
            MPI_Comm_size(node, &local);
            MPI_Comm_free(&node);
        }
        cpu_set_t mask;
        const int machine = int(std::max(1u, std::thread::hardware_concurrency()));
        const int allowed =
            sched_getaffinity(0, sizeof(mask), &mask) == 0 ? CPU_COUNT(&mask) : machine;
        // Bound by mpirun (fewer cores than the machine's): those cores are this process's.
        if (allowed < machine) return std::max(1, allowed);
        return std::max(1, machine / std::max(1, local));
    }

    [[noreturn]] void abort(int exit_code) override {
        MPI_Abort(MPI_COMM_WORLD, exit_code);
        std::_Exit(exit_code);  // MPI_Abort does not return; this keeps the promise if it did
    }

private:
    // Every process must list the same arrays (the same scene): a mismatch would pair the
    // wrong elements.
    void check_same_layout(const std::vector<Accumulator>& totals) {
        unsigned long long bytes = 0;
        for (const Accumulator& a : totals) bytes = bytes * 31 + a.count * a.element_bytes() + 1;
        unsigned long long lo = bytes, hi = bytes;
        check(MPI_Allreduce(MPI_IN_PLACE, &lo, 1, MPI_UNSIGNED_LONG_LONG, MPI_MIN, MPI_COMM_WORLD),
              "MPI_Allreduce");
        check(MPI_Allreduce(MPI_IN_PLACE, &hi, 1, MPI_UNSIGNED_LONG_LONG, MPI_MAX, MPI_COMM_WORLD),
              "MPI_Allreduce");
        if (lo != hi)
            throw std::runtime_error(
                "the processes of this MPI job built different films (did they load different "
                "scene files?)");
    }

    int rank_ = 0, size_ = 1;
};

// A distributed `femto bench`: the lowest ranks of each machine take runs (by default one, so
// that no two timed runs share a machine), rank 0 among them; the others only help render
// references.
class MpiStudy final : public bench::StudyGroup {
public:
    MpiStudy(MpiGroup& group, int runs_per_machine) : group_(group) {
        MPI_Comm node;
        check(MPI_Comm_split_type(MPI_COMM_WORLD, MPI_COMM_TYPE_SHARED, group.rank(), MPI_INFO_NULL,
                                  &node),
              "MPI_Comm_split_type");
        int local = 0;
        MPI_Comm_rank(node, &local);
        MPI_Comm_free(&node);
        const bool worker = local < runs_per_machine;
        MPI_Comm workers;
        check(MPI_Comm_split(MPI_COMM_WORLD, worker ? 0 : MPI_UNDEFINED, group.rank(), &workers),
              "MPI_Comm_split");
        if (workers != MPI_COMM_NULL) {
            MPI_Comm_rank(workers, &worker_index_);
            MPI_Comm_free(&workers);
        }
        int is_worker = worker ? 1 : 0;
        check(MPI_Allreduce(&is_worker, &workers_, 1, MPI_INT, MPI_SUM, MPI_COMM_WORLD),
              "MPI_Allreduce");
    }
    int rank() const override { return group_.rank(); }
    int workers() const override { return workers_; }
    int worker_index() const override { return worker_index_; }
    int default_threads() const override { return group_.default_threads(); }
    PassGroup& everyone() override { return group_; }
    void combine(const std::vector<Accumulator>& totals) override { group_.combine(totals); }

    void broadcast(std::string& text) override {
        uint64_t size = text.size();
        broadcast_bytes(&size, sizeof(size));
        text.resize(size);
        broadcast_bytes(text.data(), size);
    }
    void broadcast(std::vector<float>& values) override {
        uint64_t size = values.size();
        broadcast_bytes(&size, sizeof(size));
        values.resize(size);
        broadcast_bytes(values.data(), size * sizeof(float));
    }

    std::vector<std::string> gather_from_workers(const std::string& mine) override {
        const std::string text = worker_index_ >= 0 ? mine : std::string();
        const int size = int(text.size());
        std::vector<int> sizes(size_t(group_.size())), offsets(size_t(group_.size()));
        MPI_Request request;
        check(MPI_Igather(&size, 1, MPI_INT, sizes.data(), 1, MPI_INT, 0, MPI_COMM_WORLD, &request),
              "MPI_Igather");
        wait_politely(request);
        int total = 0;
        for (size_t r = 0; r < sizes.size(); ++r)
            offsets[r] = std::exchange(total, total + sizes[r]);
        std::string all(size_t(total), '\0');
        check(MPI_Igatherv(text.data(), size, MPI_CHAR, all.data(), sizes.data(), offsets.data(),
                           MPI_CHAR, 0, MPI_COMM_WORLD, &request),
              "MPI_Igatherv");
        wait_politely(request);
        std::vector<std::string> texts;
        if (group_.rank() != 0) return texts;
        // Workers are numbered in rank order (MPI_Comm_split keyed by rank).
        for (size_t r = 0; r < sizes.size(); ++r)
            if (sizes[r] > 0) texts.push_back(all.substr(size_t(offsets[r]), size_t(sizes[r])));
        return texts;
    }

    void send_run(const std::string& text) override {
        check(MPI_Send(text.data(), int(text.size()), MPI_CHAR, 0, kRunTag, MPI_COMM_WORLD),
              "MPI_Send");
    }
    void receive_runs(bool until_done,
                      const std::function<void(const std::string&)>& receive) override {
        while (!until_done || finished_ < workers_ - 1) {
            int pending = 0;
            MPI_Status status;
            check(MPI_Iprobe(MPI_ANY_SOURCE, kRunTag, MPI_COMM_WORLD, &pending, &status),
                  "MPI_Iprobe");
            if (!pending) {
                if (!until_done) return;
                std::this_thread::sleep_for(std::chrono::milliseconds(5));
                continue;
            }
            int size = 0;
            MPI_Get_count(&status, MPI_CHAR, &size);
            std::string text(size_t(size), '\0');
            check(MPI_Recv(text.data(), size, MPI_CHAR, status.MPI_SOURCE, kRunTag, MPI_COMM_WORLD,
                           MPI_STATUS_IGNORE),
                  "MPI_Recv");
            if (text.empty())
                ++finished_;  // that worker has no more runs
            else
                receive(text);
        }
    }

private:
    static constexpr int kRunTag = 8;
    MpiGroup& group_;
    int workers_ = 1, worker_index_ = -1, finished_ = 0;
};

}  // namespace

std::unique_ptr<bench::StudyGroup> make_study_group(Distributed& group, int runs_per_machine) {
    return std::make_unique<MpiStudy>(static_cast<MpiGroup&>(group), runs_per_machine);
}

std::unique_ptr<Distributed> start_distributed(int& argc, char**& argv) {
    if (launched_size() < 2) return nullptr;
    watch_the_render_process(argv);
    int provided = 0;
    // TBB's worker threads never call MPI: the main thread alone does.
    check(MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided), "MPI_Init_thread");
    auto group = std::make_unique<MpiGroup>();
    if (group->size() < 2) {
        MPI_Finalize();
        return nullptr;
    }
    return group;
}

void finish_distributed(std::unique_ptr<Distributed> group) {
    if (group) MPI_Finalize();
}

std::string distributed_support() {
    char text[MPI_MAX_LIBRARY_VERSION_STRING];
    int length = 0;
    MPI_Get_library_version(text, &length);
    std::string library(text, size_t(length));
    if (const size_t comma = library.find(','); comma != std::string::npos) library.resize(comma);
    while (!library.empty() && (library.back() == '\n' || library.back() == ' '))
        library.pop_back();
    return "distributed rendering: yes (" + library + "; mpirun -np N femto render ...)";
}

}  // namespace femto::cli
