#!/usr/bin/env bash
# Sets up, builds and runs every test through ctest.
#   scripts/test.sh                 all tests (unit + end-to-end)
#   scripts/test.sh --sanitize      the same under AddressSanitizer + UBSan
#   scripts/test.sh -- -R Camera    extra arguments after -- go to ctest
set -euo pipefail
cd "$(dirname "$0")/.."

setup_args=()
ctest_args=()
build_dir=build
while [ $# -gt 0 ]; do
  case "$1" in
    --sanitize) setup_args+=(--sanitize); build_dir=build-asan ;;
    --) shift; ctest_args=("$@"); break ;;
    *) echo "test.sh: unknown option '$1'" >&2; exit 2 ;;
  esac
  shift
done

scripts/setup.sh "${setup_args[@]}"
cd "$build_dir"
ctest --output-on-failure -j"$(nproc)" "${ctest_args[@]}"
