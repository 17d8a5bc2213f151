#!/usr/bin/env bash
# Benchmarks, printed as tables (runtime, accuracy, peak memory).
#   scripts/bench.sh <name>        names: see the list below
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh >/dev/null
bench_dir=build/bench

usage() {
  echo "usage: scripts/bench.sh <name>"
  echo "available:"
  for f in scripts/bench/*.sh; do
    [ -e "$f" ] && echo "  $(basename "$f" .sh)"
  done
  exit 2
}
[ $# -ge 1 ] || usage
script="scripts/bench/$1.sh"
[ -f "$script" ] || { echo "bench.sh: unknown benchmark '$1'" >&2; usage; }
shift
export BAYON="$PWD/build/tools/bayon" BAYON_BUILD="$PWD/build"
export BAYON_DATA_DIR="${BAYON_DATA_DIR:-$PWD/../shared/data}"
mkdir -p "$bench_dir"
exec bash "$script" "$@"
