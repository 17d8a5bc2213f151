#!/usr/bin/env bash
# Runs the libFuzzer harnesses of tests/fuzz (ASan + UBSan build, clang).
#   scripts/fuzz.sh TARGET SECONDS [LIBFUZZER_FLAG...]
#   scripts/fuzz.sh all SECONDS [LIBFUZZER_FLAG...]
# TARGET is a harness name without its fuzz_ prefix or with it (database_file
# or fuzz_database_file); `scripts/fuzz.sh list 0` lists them. Builds
# build-asan/ if needed (scripts/setup.sh --sanitize) and the harnesses
# themselves. Each target runs one process (no -jobs), as many targets at a
# time as there are cores (BAYON_FUZZ_JOBS), on a working corpus
# build-asan/fuzz/<target>/corpus seeded from tests/fuzz/corpus/<target>,
# also reading tests/fuzz/regressions/<target>; crash, leak, timeout and
# out-of-memory inputs go to build-asan/fuzz/<target>/artifacts. Prints one
# line per target and exits 1 if any target produced such an input (or did
# not run). A finding: fix the reader, then copy the input into
# tests/fuzz/regressions/<target>/ so that the replay test keeps it.
set -euo pipefail
cd "$(dirname "$0")/.."

if [ $# -lt 2 ]; then
  echo "usage: scripts/fuzz.sh TARGET|all SECONDS [LIBFUZZER_FLAG...]" >&2
  exit 2
fi
what=$1
seconds=$2
shift 2
case "$seconds" in
  '' | *[!0-9]*) echo "fuzz: SECONDS must be a whole number" >&2; exit 2 ;;
esac

all_targets=()
for source in tests/fuzz/fuzz_*.cc; do
  name=$(basename "$source" .cc)
  name=${name#fuzz_}
  [ "$name" = util ] && continue
  all_targets+=("$name")
done
if [ "$what" = list ]; then
  printf '%s\n' "${all_targets[@]}"
  exit 0
fi
if [ "$what" = all ]; then
  targets=("${all_targets[@]}")
else
  target=${what#fuzz_}
  if [ ! -f "tests/fuzz/fuzz_$target.cc" ]; then
    echo "fuzz: no target '$what' (known: ${all_targets[*]})" >&2
    exit 2
  fi
  targets=("$target")
fi

build=build-asan
lock=${BAYON_BUILD_LOCK:-/tmp/bayon-build.lock}
if [ ! -f "$build/build.ninja" ]; then
  # The full sanitizer build; the harnesses below need only part of it.
  scripts/setup.sh --sanitize ||
    echo "fuzz: scripts/setup.sh --sanitize failed; building the harnesses only" >&2
fi
if ! grep -q "build tests/fuzz/fuzz_${targets[0]}:" "$build/build.ninja"; then
  echo "fuzz: $build/ is not a clang sanitizer build with BAYON_FUZZ" >&2
  exit 2
fi
executables=()
for target in "${targets[@]}"; do executables+=("tests/fuzz/fuzz_$target"); done
if ! output=$(flock "$lock" ninja -C "$build" -j2 "${executables[@]}" 2>&1); then
  tail -n 40 <<<"$output" >&2
  echo "fuzz: building ${executables[*]} failed" >&2
  exit 2
fi

# fuzz_one TARGET: one harness for $seconds; its line in $build/fuzz/TARGET/result,
# and status 1 on a finding or a failed run.
fuzz_one() {
  local target=$1
  local dir=$build/fuzz/$target
  mkdir -p "$dir/corpus" "$dir/artifacts"
  rm -rf "$dir/tmp" "$dir/result"
  mkdir -p "$dir/tmp"
  # The seeds join the working corpus (which keeps what earlier runs found).
  cp -n tests/fuzz/corpus/"$target"/* "$dir/corpus/" 2>/dev/null || true
  local inputs=("$dir/corpus")
  if [ -d "tests/fuzz/regressions/$target" ]; then
    inputs+=("tests/fuzz/regressions/$target")
  fi
  local new_artifacts findings executions last cov exec_s corpus result rc=0
  find "$dir/artifacts" -type f ! -name 'slow-unit-*' | sort >"$dir/artifacts.before"
  local log=$dir/fuzz.log
  # OpenCV allocates what an image header claims, up to 2^30 pixels by
  # default: 2^22 keeps forged headers under the memory limit.
  TMPDIR=$PWD/$dir/tmp \
  OPENCV_IO_MAX_IMAGE_PIXELS=4194304 \
  ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:allocator_may_return_null=0} \
  UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1} \
    "$build/tests/fuzz/fuzz_$target" "${inputs[@]}" \
      -max_total_time="$seconds" -rss_limit_mb=2560 -timeout=30 \
      -artifact_prefix="$dir/artifacts/" -print_final_stats=1 "${flags[@]}" \
      >"$log" 2>&1 || rc=$?
  rm -rf "$dir/tmp"
  new_artifacts=$(find "$dir/artifacts" -type f ! -name 'slow-unit-*' | sort |
    comm -13 "$dir/artifacts.before" -)
  findings=$(grep -c . <<<"$new_artifacts" || true)
  executions=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  last=$(grep -a -E '^#[0-9]+' "$log" | tail -1 || true)
  cov=$(sed -n 's/.* cov: \([0-9]*\).*/\1/p' <<<"$last")
  exec_s=$(sed -n 's/.* exec\/s: \([0-9]*\).*/\1/p' <<<"$last")
  corpus=$(find "$dir/corpus" -type f | wc -l)
  result=ok
  local status=0
  if [ "$findings" -gt 0 ]; then
    result="FINDING: $(grep -a -m1 -E '^==[0-9]+==ERROR|runtime error|deadly signal|out-of-memory|timeout after|detected memory leaks|malloc\(' "$log" || echo "see $log")"
    status=1
  elif [ "$rc" -ne 0 ]; then
    result="ERROR: exit code $rc, see $log"
    status=1
  fi
  printf 'fuzz_%s: %ss, %s executions (%s/s), corpus %s, cov %s, findings %s: %s\n' \
    "$target" "$seconds" "${executions:-0}" "${exec_s:-0}" "$corpus" \
    "${cov:-?}" "$findings" "$result" >"$dir/result"
  # The input itself, so that a finding in a CI run whose build folder is gone
  # can be replayed: base64 -d it into tests/fuzz/regressions/TARGET/.
  if [ "$findings" -gt 0 ]; then
    local artifact bytes
    while read -r artifact; do
      bytes=$(stat -c %s "$artifact")
      if [ "$bytes" -le 8192 ]; then
        printf '  %s (%s bytes), base64: %s\n' "$artifact" "$bytes" \
          "$(base64 -w0 "$artifact")"
      else
        printf '  %s (%s bytes)\n' "$artifact" "$bytes"
      fi
    done <<<"$new_artifacts" >>"$dir/result"
  fi
  return $status
}

# One harness per core at a time (each is one process), the lines in the
# targets' order.
flags=("$@")
jobs_max=${BAYON_FUZZ_JOBS:-$(nproc)}
pids=()
for target in "${targets[@]}"; do
  while [ "$(jobs -rp | wc -l)" -ge "$jobs_max" ]; do wait -n || true; done
  fuzz_one "$target" &
  pids+=($!)
done
status=0
for i in "${!targets[@]}"; do
  wait "${pids[$i]}" || status=1
  cat "$build/fuzz/${targets[$i]}/result" 2>/dev/null ||
    { echo "fuzz_${targets[$i]}: ERROR: no result"; status=1; }
done
exit $status
