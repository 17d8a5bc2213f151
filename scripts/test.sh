#!/usr/bin/env bash
# Sets up, builds and runs every test through ctest.
#   scripts/test.sh                 all tests (unit + end-to-end)
#   scripts/test.sh --sanitize      under AddressSanitizer + UBSan (clang): the
#                                   unit tests and the end-to-end tests that
#                                   build makes (tests/CMakeLists.txt's
#                                   SANITIZE: the temple pipeline, bad input,
#                                   concurrent writers)
#   scripts/test.sh --record_costs  after the run, keep its test times in
#                                   tests/ctest_costs*.txt (see below)
#   scripts/test.sh -- -R Camera    extra arguments after -- go to ctest
# ctest -j starts the tests it expects to take longest first, by the times of
# earlier runs in the build folder. A fresh clone has none, so the times of a
# recorded run are copied in first: without them the longest tests could
# start last and leave one core idle at the end.
set -euo pipefail
cd "$(dirname "$0")/.."

setup_args=()
ctest_args=()
build_dir=build
costs=tests/ctest_costs.txt
record_costs=0
while [ $# -gt 0 ]; do
  case "$1" in
    --sanitize) setup_args+=(--sanitize); build_dir=build-asan
                costs=tests/ctest_costs_sanitize.txt ;;
    --record_costs) record_costs=1 ;;
    --) shift; ctest_args=("$@"); break ;;
    *) echo "test.sh: unknown option '$1'" >&2; exit 2 ;;
  esac
  shift
done

scripts/setup.sh "${setup_args[@]}"
cost_data="$build_dir/Testing/Temporary/CTestCostData.txt"
if [ ! -f "$cost_data" ] && [ -f "$costs" ]; then
  mkdir -p "$(dirname "$cost_data")"
  cp "$costs" "$cost_data"
fi
cd "$build_dir"
if [ "$build_dir" = build-asan ]; then
  # Any finding fails the test that made it, with a stack trace; bayon's
  # child processes inherit these.
  export ASAN_OPTIONS="detect_leaks=1:abort_on_error=1:strict_string_checks=1"
  export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
  # Leaks inside third-party libraries, each with its reason.
  export LSAN_OPTIONS="suppressions=$PWD/../tests/sanitizers/lsan.supp:print_suppressions=0"
fi
ctest --output-on-failure -j"$(nproc)" "${ctest_args[@]}"
if [ "$record_costs" = 1 ]; then
  cd ..
  cp "$cost_data" "$costs"
  echo "test.sh: test times recorded in $costs"
fi
