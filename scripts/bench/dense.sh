#!/usr/bin/env bash
# `bayon dense` (MPGC, CPU): points per second, peak memory, the time split
# of the multiview mode and, where the truth is known, accuracy and
# completeness.
#   tower     the rendered tower (`bayon synth --scene tower`, 1800 x 1200,
#             16 views) with its true orientation and calibration and tie
#             points triangulated into it, the default (multiview: every
#             photograph a master); judged by `bayon evaluate` against the
#             true surface (completeness within 5 GSD)
#   paper     the same with configs/dense_ring.ini (`--mode paper`: 5
#             masters, 7-pixel cells: the paper's sampling, the
#             reproduction row)
#   one_light the same tower with every photograph in the first one's
#             light (`synth --one_light 1`), the same model: a control for
#             what the photographs' changing sun costs
#   temple    ../shared/data/temple-ring, bayon's own orientation (the chain
#   fountain  benchmark's adjusted models; it runs first where they are
#             missing), the default
# Threads: $BAYON_THREADS (default 2, the CI machine's cores).
set -euo pipefail
dir="$(cd "$(dirname "$0")/../.." && pwd)/build/bench/dense"
chain_dir="$(dirname "$dir")/chain"
threads="${BAYON_THREADS:-2}"
mkdir -p "$dir"
source "$(dirname "$0")/lib/timing.sh"

if [ ! -d "$chain_dir/temple/adjusted" ] ||
  [ ! -d "$chain_dir/fountain/adjusted" ]; then
  echo "dense.sh: bayon's orientations first (scripts/bench/chain.sh)"
  bash "$(dirname "$0")/chain.sh" >/dev/null
fi

# synth_tower DIR [ARGS...]: the rendered tower (seed 2) in DIR/ws, made
# once
synth_tower() {
  local into="$1"
  shift
  if [ ! -f "$into/ws/gt/synth.json" ]; then
    rm -rf "$into"
    mkdir -p "$into"
    "$BAYON" synth --scene tower --output_path "$into/ws" --seed 2 \
      --num_heldout_views 0 --num_threads "$threads" "$@" \
      >"$into/synth.log" 2>&1
  fi
}
tower="$dir/tower"
synth_tower "$tower"
# The true orientation with tie points, as an adjusted model would carry
# them: bayon's features, matches and relative orientations, triangulated
# by stock `colmap point_triangulator` into the true poses (the tower's own
# chain breaks its ring, issue 4).
if [ ! -f "$tower/model/points3D.bin" ]; then
  rm -rf "$tower/model" "$tower/tie"
  mkdir -p "$tower/tie" "$tower/model"
  cp "$tower/ws/database.db" "$tower/tie/database.db"
  db="$tower/tie/database.db"
  "$BAYON" features --database_path "$db" --image_path "$tower/ws/images" \
    --num_threads "$threads" >"$tower/tie/features.log" 2>&1
  "$BAYON" match --database_path "$db" --image_path "$tower/ws/images" \
    --num_threads "$threads" >"$tower/tie/match.log" 2>&1
  "$BAYON" relative --database_path "$db" --num_threads "$threads" \
    >"$tower/tie/relative.log" 2>&1
  colmap point_triangulator --database_path "$db" \
    --image_path "$tower/ws/images" --input_path "$tower/ws/gt/sparse" \
    --output_path "$tower/model" --clear_points 1 >"$tower/tie/triangulator.log" 2>&1
  cp "$tower/ws/gt/calibration.json" "$tower/model/"
fi
rm -rf "$tower/dense"

# dense NAME IMAGES MODEL [ARGS...]
dense() {
  local name="$1" images="$2" model="$3"
  shift 3
  mkdir -p "$dir/$name"
  timed "$dir/$name/dense" "$BAYON" dense --image_path "$images" \
    --input_path "$model" --output_path "$dir/$name/dense/points.ply" \
    --overwrite 1 --num_threads "$threads" "$@"
}
# evaluate NAME GT: the cloud against the true surface
evaluate() {
  "$BAYON" evaluate --ground_truth_path "$2" \
    --cloud_path "$dir/$1/dense/points.ply" --completeness_threshold_gsd 5 \
    --cloud_errors_path "$dir/$1/errors.ply" \
    --output_path "$dir/$1/evaluation.json" >"$dir/$1/evaluate.log" 2>&1 ||
    { cat "$dir/$1/evaluate.log" >&2; exit 1; }
}
dense tower "$tower/ws/images" "$tower/model"
evaluate tower "$tower/ws/gt"
# The paper's sampling, as the reproduction rows measured it: the paper
# mode's config (5 masters, 7-pixel cells, MPGC's convergence as measured).
dense paper "$tower/ws/images" "$tower/model" \
  --config "$(dirname "$0")/../../configs/dense_ring.ini"
evaluate paper "$tower/ws/gt"
# The control: the same tower, stations and noise, every photograph in the
# first one's light (`synth --one_light 1`), with the same model: what the
# changing light of the photographs costs.
one_light="$dir/one_light"
synth_tower "$one_light" --one_light 1
rm -rf "$one_light/dense"
dense one_light "$one_light/ws/images" "$tower/model"
evaluate one_light "$one_light/ws/gt"
dense temple "$BAYON_DATA_DIR/temple-ring" "$chain_dir/temple/adjusted"
dense fountain "$BAYON_DATA_DIR/fountain-P11/images" \
  "$chain_dir/fountain/adjusted"

printf '\n%-9s %9s %8s %8s %8s %9s %9s %7s %9s %9s %9s %7s %7s %6s %6s %6s %7s\n' set cells \
  points time "cells/s" "points/s" peak "acc med" "acc RMS" "acc p95" complete \
  walls tops depth fusion MPGC "err/sig"
printf '%-9s %9s %8s %8s %8s %9s %9s %7s %9s %9s %9s %7s %7s %6s %6s %6s %7s\n' "" "" "" s "" "" \
  MB GSD GSD GSD "5 GSD" "5 GSD" "5 GSD" s s s ""
for name in tower paper one_light temple fountain; do
  read -r cells points split < <(python3 -c '
import json, sys
r = json.load(open(sys.argv[1]))
split = "- - -"
if r.get("mode") == "multiview":
    split = "%.0f %.0f %.0f" % (r["propagation_seconds"], r["fusion_seconds"],
                                r["mpgc_seconds"])
print(r["num_cells"], r["num_points"], split)' "$dir/$name/dense/points.json")
  t=$(wall_s "$dir/$name/dense")
  m=$(peak_mb "$dir/$name/dense")
  accuracy="- - - - - -"
  if [ -f "$dir/$name/evaluation.json" ]; then
    accuracy=$(python3 -c '
import json, sys
c = json.load(open(sys.argv[1]))["cloud"]
a = c["accuracy_gsd"]
o = c["completeness_by_orientation"]
print("%.2f %.2f %.2f %.1f%% %.1f%% %.1f%%" % (
    a["median"], a["rms"], a["p95"], 100 * c["completeness_fraction"],
    100 * o["walls"]["completeness_fraction"],
    100 * o["tops"]["completeness_fraction"]))' \
      "$dir/$name/evaluation.json")
    gsd=$(python3 -c 'import json, sys
print(json.load(open(sys.argv[1]))["cloud"]["gsd_m"])' "$dir/$name/evaluation.json")
    read -r ratio _ < <(python3 "$(dirname "$0")/lib/sigma_ratio.py" \
      "$dir/$name/errors.ply" "$gsd")
  else
    ratio="-"
  fi
  read -r med rms p95 complete walls tops <<<"$accuracy"
  read -r t_depth t_fusion t_mpgc <<<"$split"
  awk -v n="$name" -v c="$cells" -v p="$points" -v t="$t" -v m="$m" \
    -v a="$med" -v r="$rms" -v q="$p95" -v k="$complete" -v w="$walls" \
    -v u="$tops" -v d="$t_depth" -v f="$t_fusion" -v g="$t_mpgc" \
    -v e="$ratio" 'BEGIN {
      printf "%-9s %9d %8d %8.1f %8.0f %9.0f %9d %7s %9s %9s %9s %7s %7s %6s %6s %6s %7s\n",
        n, c, p, t, c / t, p / t, m, a, r, q, k, w, u, d, f, g, e }'
done
echo
echo "cells: multiview, the depth maps' pixels (every photograph a master);"
echo "paper, the dense pattern's 7-pixel cells of 5 masters; points: those"
echo "accepted. depth, fusion, MPGC: multiview's time split (s). err/sig: the"
echo "points' true errors against their stated sigmas along the normal (median"
echo "|error| / s_normal / 0.6745 over the points within 5 GSD; 1 = as stated)."
echo "tower, paper: true orientation with triangulated tie points; one_light: the"
echo "same tower photographed in one light (synth --one_light 1); temple, fountain:"
echo "bayon's own orientation (chain.sh)."
echo "complete: share of the true surface seen in 2 or more photographs within 5"
echo "GSD of a point; walls, tops: the same for the surface facing sideways and"
echo "up (normals within 45 degrees of horizontal, of up; bayon evaluate)."
echo "Threads: $threads. Reject reasons per master: build/bench/dense/*/dense/points.json"
