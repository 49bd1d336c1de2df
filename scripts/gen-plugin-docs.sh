#!/usr/bin/env bash
# Regenerates docs/plugins.md from the plugins' own parameter schemas (a test fails when the
# committed file is stale).
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
"$build/bin/femto" plugins --markdown > docs/plugins.md
echo "wrote docs/plugins.md"
