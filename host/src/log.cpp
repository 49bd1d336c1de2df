#include "femto/log.h"

#include <atomic>
#include <cstdio>
#include <mutex>

namespace femto {

namespace {
std::mutex g_log_mutex;
std::atomic<int> g_warnings{0};
std::atomic<bool> g_silent{false};
}  // namespace

void log_warning(const SourceLocation& loc, const std::string& message) {
    std::lock_guard<std::mutex> lock(g_log_mutex);
    ++g_warnings;
    if (g_silent.load()) return;
    if (loc.file.empty())
        std::fprintf(stderr, "warning: %s\n", message.c_str());
    else
        std::fprintf(stderr, "warning: %s: %s\n", loc.str().c_str(), message.c_str());
}

void log_note(const SourceLocation& loc, const std::string& message) {
    std::lock_guard<std::mutex> lock(g_log_mutex);
    if (g_silent.load()) return;
    if (loc.file.empty())
        std::fprintf(stderr, "note: %s\n", message.c_str());
    else
        std::fprintf(stderr, "note: %s: %s\n", loc.str().c_str(), message.c_str());
}

void silence_log(bool silent) { g_silent.store(silent); }

int warning_count() { return g_warnings.load(); }

}  // namespace femto
