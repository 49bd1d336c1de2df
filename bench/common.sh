# Shared by the bench/run*.sh scripts (sourced, after `set -euo pipefail`): where things are,
# building one benchmark, and the header every run log starts with.

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${FEMTO_BENCH_BUILD_DIR:-$root/build-bench}"
results="$root/bench/results"
mkdir -p "$results"

# Configures build-bench/ (Release, benchmarks on, tests off) and builds TARGET (default: all).
# CMake finds plugin folders and benchmarks when it configures, so an existing build folder is
# reconfigured too (a few seconds) to pick up new ones.
bench_build() {
    if [[ ! -f "$build/build.ninja" ]]; then
        cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DFEMTO_BENCH=ON \
            -DFEMTO_TESTS=OFF
    else
        cmake "$build" >/dev/null
    fi
    ninja -C "$build" "$@"
}

# For scripts that compare two build folders (run_build_ab.sh, run_small_films.sh): exits 2
# with the script's usage (its header comment, lines 2 to LAST) unless at least 3 arguments
# were given, and with a message unless BUILD_A and BUILD_B each hold bin/femto.
#     two_builds_args LAST "$@"
two_builds_args() {
    local last=$1 script=${BASH_SOURCE[1]}
    shift
    if [[ $# -lt 3 ]]; then
        sed -n "2,${last}p" "$script"
        exit 2
    fi
    local dir
    for dir in "$2" "$3"; do
        [[ -x "$dir/bin/femto" ]] ||
            { echo "$(basename "$script"): $dir/bin/femto: no such program" >&2; exit 2; }
    done
}

# Writes the source revision, machine, date and load to LOG (and the terminal).
bench_log_header() {
    local log=$1
    {
        echo "source: git $(git -C "$root" rev-parse --short HEAD 2>/dev/null || echo unknown)" \
            "($(git -C "$root" status --porcelain 2>/dev/null | wc -l) uncommitted changes)"
        echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | sed 's/^ *//')"
        echo "date: $(date -u '+%Y-%m-%d %H:%M:%S UTC')"
        echo "load average before the benchmark: $(cat /proc/loadavg)"
    } | tee "$log"
}

# Prints scene file SCENE with its integrator's type replaced by INTEGRATOR and its
# time-sampling strategies dropped (steady sampling everywhere, which every integrator takes):
#     steady_scene_with INTEGRATOR SCENE > COPY   (COPY next to SCENE: scenes include by
#                                                  relative paths)
steady_scene_with() {
    sed -E -e "s/<integrator type=\"[^\"]+\"/<integrator type=\"$1\"/" \
        -e '/<(distance|connection|angular) type=|name="mis"/d' "$2"
}

# Reads `femto render`'s output on stdin and prints its render time and ray rate: "SECONDS
# MRAYS_PER_S" (fails, as grep does, when the summary line is missing).
render_seconds_and_rate() {
    grep -o "in [0-9.]* s ([0-9.]* M rays/s)" | sed -E 's/in ([0-9.]*) s \(([0-9.]*) M rays.*/\1 \2/'
}

# The scenes issue 11's ray rates are measured on (run_ray_rate.sh, run_build_ab.sh), each with
# its -D settings: the path tracer renders about a second, BDPT 2-5.
ray_rate_scenes=(
    "cornell-box|-D res=64 -D spp=256"
    "fog-object|-D res=32 -D spp=256"
    "caustic|-D res=64 -D spp=256"
)

# Renders scenes/SCENE with INTEGRATOR (a steady_scene_with copy, next to the scene since it
# includes files by relative paths, removed after) by the program FEMTO at THREADS threads into
# OUTBASE, and prints "SECONDS MRAYS_PER_S". Further arguments go to `femto render`. A run
# stopped midway leaves its copy: call remove_scene_copies from the script's EXIT trap.
#     ray_rate_render FEMTO SCENE INTEGRATOR THREADS OUTBASE [ARGS...]
ray_rate_render() {
    local femto=$1 scene=$2 integrator=$3 threads=$4 outbase=$5
    shift 5
    local xml="$root/scenes/$scene/.bench-$$-$integrator.xml"  # $$: the script's, in subshells too
    steady_scene_with "$integrator" "$root/scenes/$scene/scene.xml" > "$xml"
    local status=0  # the render's (or, with no summary line, grep's), as the caller's $(...) had it
    "$femto" render "$xml" "$@" --threads "$threads" -o "$outbase" 2>&1 | render_seconds_and_rate ||
        status=$?
    rm -f "$xml"
    return "$status"
}
remove_scene_copies() {
    rm -f "$root"/scenes/*/.bench-$$-*.xml
}

# Prints an LD_PRELOAD value for running femto under valgrind (empty when not needed): libhwy,
# loaded with OpenImageIO, runs an instruction valgrind 3.19 cannot decode on some CPUs in a
# static initializer; bench/tools/valgrind_hwy_shim.cpp stands in for that function. Built into
# DIR (default: the bench build folder).
valgrind_preload() {
    local dir=${1:-$build} lib
    lib=$(ldconfig -p 2>/dev/null | awk '/libhwy\.so/ {print $NF; exit}')
    [[ -n "$lib" ]] || return 0
    mkdir -p "$dir"
    if [[ ! -f "$dir/libvalgrind_hwy_shim.so" ]]; then
        c++ -O2 -shared -fPIC "$root/bench/tools/valgrind_hwy_shim.cpp" \
            -o "$dir/libvalgrind_hwy_shim.so"
    fi
    echo "$dir/libvalgrind_hwy_shim.so"
}
