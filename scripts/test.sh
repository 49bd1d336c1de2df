#!/usr/bin/env bash
# Installs what is missing, builds femto (and a sanitizer build for the bad-input tests) and
# runs every test through ctest.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/deps.sh
JOBS=$(nproc)
# The benchmarks are built (not run) so that they keep compiling as the API moves.
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release -DFEMTO_TESTS=ON -DFEMTO_BENCH=ON
cmake --build build -j "$JOBS"
ctest --test-dir build --output-on-failure -j "$JOBS"
# AddressSanitizer + UBSan build (clang): the mutation test, the loader's bad-input tests, the PLY
# reader's corruption tests, the image texture's and environment map's bad files, the peer
# transient formats, instancing, the cylinder, the mask, the BTF reader's corrupt files and the
# btf material, the direction triangulation, the surface tangents, the CLI's error cases, the
# temporal filters (the kernel's pilot and bin arithmetic, the films' spill accounting) and the
# media (the .vol reader's corrupt files, volumetric paths, the connection and angular
# strategies' sampling routines), every plugin built with its defaults (the schema test), the
# transport toolkit, and libfemto_io's readers and writers (cube EXRs and .npy files, images,
# output sets) with `femto viz`'s computations run under it.
# Leak detection stays off: LeakSanitizer's tracer crashes at exit in some tests (e.g.
# ShadowConnection.ThroughANullBoundedSlab: "Tracer caught signal 11"), and the one leak it
# reports in these tests is OpenImageIO 2.4's (31 bytes per corrupt PNG, lost in its PNG
# reader), which scripts/lsan-suppressions.txt suppresses for runs with detect_leaks=1.
# The same build holds the libFuzzer harnesses (FEMTO_FUZZ: clang, ASan + UBSan and libFuzzer's
# coverage everywhere), so the sanitizer tests and the fuzzers share one compilation of the
# library and plugins: with a separate GCC sanitizer build and fuzz build the CI run took
# 28.7-29.7 minutes on 2 cores (the design's gate: well under 30). -O1 with line tables: half
# the compile time of -O2 -g, and enough for the sanitizers' stack traces. A build-sanitize
# left by the earlier GCC configuration is configured afresh.
if [ -f build-sanitize/CMakeCache.txt ] && ! grep -q '^FEMTO_FUZZ:BOOL=ON$' build-sanitize/CMakeCache.txt; then
  rm -rf build-sanitize
fi
CC=clang CXX=clang++ cmake -S . -B build-sanitize -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -gline-tables-only -DNDEBUG" -DFEMTO_TESTS=ON -DFEMTO_FUZZ=ON
cmake --build build-sanitize -j "$JOBS"
ASAN_OPTIONS=detect_leaks=0 ctest --test-dir build-sanitize --output-on-failure -j "$JOBS" \
  -R '^(AliasTable|Mutation|Loader|BtfFile|BtfMaterial|AdaptiveSampling|LightCone|DirectionMesh|VGroove|HitTangent|PeerTransient|Instancing|ShapeCylinder|MaskErrors|MaskRender|EmitterCollimated|Scale|Serialized|Ply|Compat|TextureBitmap|KernelFilter|TemporalFilterEnergy|Heterogeneous|Media|MeasurementSensors|Stress|ConnectionSampling|AngularSampling|PluginSchemas|PathClock|Throughput|ShadowConnection|DistanceMixture|ConnectionReach|Viz|VizAttributes|CubeLayout|Npy|ImageRead|OutputSet)\.|^(LightTracer|Bdpt)\.(BadInput|BitIdentical|TofPlaneArrival|GlassSlab|SplatsConserve|EachStrategyAloneEstimatesTheSameImage$)|^DistantLight\.(BadInput|EnvmapMapsPixels|MitsubaFiles)|^StreakFilm\.EqualsTransientRowsKernel|^WarpChi2\.AliasTable|^cli\.(bad|unknown|missing|unwritable|compat)' 
# Fuzzing (fuzz/, docs/fuzzing.md): each libFuzzer harness (the scene loader, the PLY, OBJ,
# serialized, .vol, BTF and EXR readers, `femto viz`'s cube readers and `femto bench`'s
# experiment files) for 20 s on its seed corpus, in the sanitizer build above.
FEMTO_FUZZ_BUILD=build-sanitize scripts/fuzz.sh 20
