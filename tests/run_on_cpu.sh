#!/usr/bin/env bash
# run_on_cpu.sh CPU PROGRAM [ARGS...]
# Runs PROGRAM under QEMU's user-mode emulation of the x86-64 CPU model CPU (`qemu-x86_64
# -cpu help` lists them), so that code dispatched by CPU features (ldsampler's SIMD clones)
# is tested on CPUs the machine is not. Exits 77 (ctest's skip) when qemu-x86_64 is missing.
set -euo pipefail
if ! command -v qemu-x86_64 > /dev/null; then
  echo "skipped: qemu-x86_64 is not installed (Debian's qemu-user; scripts/deps.sh installs it)"
  exit 77
fi
exec qemu-x86_64 -cpu "$1" "${@:2}"
