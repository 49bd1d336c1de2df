// A stand-in for libhwy's hwy::platform::TimerResolution(), preloaded (LD_PRELOAD) when femto
// runs under valgrind: libhwy (loaded with OpenImageIO) calls it from a static initializer,
// and it executes rdtscp, which valgrind 3.19 cannot decode on some CPUs ("unrecognised
// instruction"), killing the process before main. femto never uses libhwy's timers, so a
// constant does no harm. bench/common.sh builds it (valgrind_preload) for the scripts that run
// callgrind.
#include <cstdint>

namespace hwy::platform {
uint64_t TimerResolution() { return 1; }
}  // namespace hwy::platform
