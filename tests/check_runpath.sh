#!/usr/bin/env bash
# check_runpath.sh ROOT FILE...: every ELF file among FILE has a RUNPATH (or RPATH) whose
# entries are all non-empty (the loader reads an empty one as the current folder) and name
# folders inside ROOT ($ORIGIN resolved against the file's own folder): a femto binary never
# looks for libraries outside its build or installation folder, or in the folder it runs from.
# Prints the number of files checked; exits 1 naming the first offender.
set -uo pipefail
root=$(realpath -m "$1")
shift
checked=0
for f in "$@"; do
  readelf -h "$f" >/dev/null 2>&1 || continue  # not an ELF file
  path=$(readelf -d "$f" | sed -n 's/.*(\(RUNPATH\|RPATH\)).*\[\(.*\)\]$/\2/p')
  [ -n "$path" ] || continue
  case ":$path:" in *::*) echo "$f: RUNPATH \"$path\" has an empty entry"; exit 1;; esac
  IFS=: read -r -a entries <<< "$path"
  for entry in "${entries[@]}"; do
    dir=${entry/#\$ORIGIN/$(dirname "$(realpath "$f")")}
    dir=$(realpath -m "$dir")
    case "$dir/" in "$root"/*) ;; *) echo "$f: RUNPATH entry \"$entry\" ($dir) lies outside $root"; exit 1;; esac
  done
  checked=$((checked + 1))
done
echo "$checked"
