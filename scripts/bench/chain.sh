#!/usr/bin/env bash
# bayon's own chain from photographs to the bundle (import with the
# calibrated camera, features, match, relative, disparity, tiepoints,
# strip, adjust; free network) against stock COLMAP 3.8's (CPU SIFT,
# exhaustive matching, mapper: scripts/bench/colmap_baseline.sh, run first
# if its results are missing) on the two real rings with ground truth,
# both judged by `bayon evaluate` against the truth of
# `bayon import_ground_truth`:
#  1. ../shared/data/temple-ring (16 x 640x480; all pairs matched);
#  2. ../shared/data/fountain-P11 (11 x 3072x2048; 3 successors per image).
# bayon is given the calibrated camera (interior orientation known, as the
# paper's); COLMAP starts from f = 1.2 x the long side and refines it.
#   scripts/bench.sh chain [SELF_CALIBRATION]   (none|significant|all;
#                                                default none)
# `scripts/bench.sh chain significant` prints issue 6's figure for the
# temple's self-calibrating bundle (rotation RMS < 0.1 deg, centres < 0.2 %).
# Outputs under $BAYON_BUILD/bench/chain; nothing is written into the data
# folder. BAYON_THREADS (default 2) threads.
set -euo pipefail
dir="$BAYON_BUILD/bench/chain"
baseline="$BAYON_BUILD/bench/colmap_baseline"
data="$BAYON_DATA_DIR"
threads="${BAYON_THREADS:-2}"
self_calibration="${1:-none}"
mkdir -p "$dir"

if [ ! -f "$baseline/temple/evaluation.json" ] ||
  [ ! -f "$baseline/fountain/evaluation.json" ]; then
  echo "chain.sh: stock COLMAP first (scripts/bench/colmap_baseline.sh)"
  bash "$(dirname "$0")/colmap_baseline.sh" >/dev/null
fi

source "$(dirname "$0")/lib/timing.sh"
source "$(dirname "$0")/lib/bayon_chain.sh"

# chain NAME IMAGES FORMAT TRUTH_INPUT MATCH_ARGS...
chain() {
  local name="$1" images="$2" format="$3" truth_input="$4"
  shift 4
  local ws="$dir/$name" db="$dir/$name/database.db"
  rm -rf "$ws"
  mkdir -p "$ws"
  local image_path_flag=()
  [ "$format" = strecha ] && image_path_flag=(--image_path "$images")
  "$BAYON" import_ground_truth --format "$format" --input_path "$truth_input" \
    --output_path "$ws/truth" "${image_path_flag[@]}" >"$ws/truth.log" 2>&1
  # The calibrated camera: the truth's PINHOLE fx fy cx cy.
  local params
  params=$(grep -v '^#' "$ws/truth/cameras.txt" | head -1 |
    awk '{ print $5 "," $6 "," $7 "," $8 }')
  timed "$ws/import" "$BAYON" import --image_path "$images" --database_path "$db" \
    --single_camera 1 --camera_model PINHOLE --camera_params "$params"
  bayon_tie_points "$ws" "$db" "$images" "$@"
  timed "$ws/strip" "$BAYON" strip --database_path "$db" \
    --output_path "$ws/initial" --num_threads "$threads"
  timed "$ws/adjust" "$BAYON" adjust --database_path "$db" \
    --input_path "$ws/initial" --output_path "$ws/adjusted" --datum free \
    --self_calibration "$self_calibration" --num_threads "$threads"
  "$BAYON" evaluate --input_path "$ws/adjusted" --ground_truth_path \
    "$ws/truth" --output_path "$ws/evaluation.json" --label "$name bayon" \
    >"$ws/evaluate.log" 2>&1 || { cat "$ws/evaluate.log" >&2; return 1; }
}

chain temple "$data/temple-ring" middlebury \
  "$data/temple-ring/templeSR_par.txt" --pairing exhaustive
chain fountain "$data/fountain-P11/images" strecha \
  "$data/fountain-P11/gt_dense_cameras" --pairing sequential --num_neighbors 3

printf '\n%-9s %-7s %10s %10s %10s %10s %10s %8s %8s\n' set program \
  registered "centre RMS" "centre max" "centre %" "rot RMS" time "peak"
printf '%-9s %-7s %10s %10s %10s %10s %10s %8s %8s\n' "" "" "" mm mm "" deg s MB
for name in temple fountain; do
  ws="$dir/$name" base="$baseline/$name"
  read -r b_time b_peak < <(totals "$ws"/{features,match,relative,disparity,tiepoints,strip,adjust})
  read -r c_time c_peak < <(totals "$base"/{features,matches,mapper})
  python3 - "$name" "$ws" "$b_time" "$b_peak" "$base" "$c_time" "$c_peak" <<'EOF'
import json, sys
name = sys.argv[1]
for program, (folder, seconds, peak) in zip(
        ("bayon", "colmap"), (sys.argv[2:5], sys.argv[5:8])):
    e = json.load(open(folder + "/evaluation.json"))["sparse"]
    print("%-9s %-7s %6d/%-3d %10.3f %10.3f %10.4f %10.4f %8.1f %8s"
          % (name, program, e["num_registered"], e["num_truth_images"],
             1000 * e["center_rms"], 1000 * e["center_max"],
             100 * e["center_rms_relative"], e["rotation_rms_deg"],
             float(seconds), peak))
EOF
done
# Issue 6's figure for the temple's self-calibrating bundle, which no test
# holds because it is not reached (2026-12-02: 0.211 deg, 0.210 %; dx0, dy0
# and B1 correlate above 0.99 with the exterior orientations here).
python3 - "$dir/temple/evaluation.json" "$self_calibration" <<'EOF'
import json, sys
e = json.load(open(sys.argv[1]))["sparse"]
ok = (e["num_registered"] == 16 and e["rotation_rms_deg"] < 0.1
      and e["center_rms_relative"] < 0.002)
print("\ntemple, self-calibration %s: rotation RMS %.3f deg, centre RMS %.3f %%;"
      " issue 6's figure with self-calibration (16/16, < 0.1 deg, < 0.2 %%): %s"
      % (sys.argv[2], e["rotation_rms_deg"], 100 * e["center_rms_relative"],
         "reached" if ok else "not reached"))
EOF
echo
echo "bayon: self-calibration $self_calibration, calibrated camera given;"
echo "colmap: f from 1.2 x the long side, principal point fixed at the centre."
echo "centre %: RMS centre error / mean camera-to-centroid distance, after the"
echo "7-parameter similarity fitted by bayon evaluate. Time: the stages' wall"
echo "clock summed; peak: the largest resident set of any stage."
echo "outputs and logs in $dir"
