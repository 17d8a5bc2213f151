#!/usr/bin/env bash
# Least-squares matches per second (ext/matching/lsm_benchmark.cc, Google
# Benchmark): one 15 x 15 template against 3 search images (affine + 2
# radiometric parameters, bilinear), single thread and both cores; and
# refine_keypoints' per-observation work (forward match, checks and
# back-matching). Extra arguments go to the benchmark binary, e.g.
# --benchmark_min_time=2.
#   scripts/bench.sh lsm
set -euo pipefail
BAYON_BUILD="${BAYON_BUILD:-$(dirname "$(dirname "$BAYON")")}"
binary="$BAYON_BUILD/ext/matching/matching_lsm_benchmark"
if [ ! -x "$binary" ]; then
  echo "lsm.sh: $binary not built (configure with -DBAYON_BUILD_BENCHMARKS=ON)" >&2
  exit 2
fi
dir="$BAYON_BUILD/bench/lsm"
mkdir -p "$dir"
"$binary" --benchmark_format=json --benchmark_out="$dir/lsm.json" \
  --benchmark_out_format=json "$@" >"$dir/lsm.log" 2>&1
python3 - "$dir/lsm.json" "$(nproc)" <<'EOF'
import json, sys
report = json.load(open(sys.argv[1]))
names = {
    "BM_LsmThreeSearchImages": "MatchLsmMulti, 3 search images",
    "BM_RefineObservationThreeSearchImages": "RefineObservation x 3 (checks, back-matching)",
}
print("%-48s %7s %12s %12s %10s %10s %6s %6s" % (
    "benchmark (15 x 15 patches)", "threads", "matches/s", "points/s",
    "us/match", "cpu us", "iter", "ok %"))
for b in report["benchmarks"]:
    base = b["name"].split("/")[0]
    threads = b.get("threads", 1)
    rate = b["items_per_second"]
    ok = b.get("converged_pct", b.get("refined_pct", float("nan")))
    # cpu_time: per iteration (3 matches) and thread, in time_unit.
    scale = {"ns": 1e-3, "us": 1.0, "ms": 1e3}[b.get("time_unit", "ns")]
    print("%-48s %7d %12.0f %12.0f %10.1f %10.1f %6.2f %6.1f" % (
        names.get(base, base), threads, rate, b["points"],
        1e6 * threads / rate, b["cpu_time"] * scale / 3,
        b.get("gn_iterations", float("nan")), ok))
context = report["context"]
print("%s, %d CPUs at %.0f MHz (nproc %s), load average %s" % (
    context.get("host_name", "?"), context.get("num_cpus", 0),
    context.get("mhz_per_cpu", 0), sys.argv[2],
    " ".join("%.2f" % x for x in context.get("load_avg", []))))
print("us/match: wall time per match and thread; cpu us: CPU time per match;")
print("iter: Gauss-Newton iterations per match; matches/s with 2 threads: both together")
EOF
echo "raw output in $dir"
