#!/usr/bin/env bash
# Issue 5's figure for `bayon refine_keypoints`: stock `colmap mapper` on a
# stock COLMAP database (SIFT from feature_extractor, exhaustive_matcher) and
# on its least-squares refined copy, judged against the calibrated cameras
# with `bayon evaluate` (camera centres and rotations after a 7-parameter
# similarity) and COLMAP's own mean reprojection error (model_analyzer):
#  1. ../shared/data/temple-ring (16 images, 640 x 480, Middlebury truth);
#  2. ../shared/data/fountain-P11 (11 images, 3072 x 2048, SIFT at 1600
#     pixels, Strecha truth).
# The stock databases are made once and kept in build/bench/refine_keypoints.
#   scripts/bench.sh refine_keypoints [temple|fountain ...]
set -euo pipefail
BAYON_BUILD="${BAYON_BUILD:-$(dirname "$(dirname "$BAYON")")}"
BAYON_DATA_DIR="${BAYON_DATA_DIR:-$(cd "$(dirname "$0")/../.." && pwd)/../shared/data}"
dir="$BAYON_BUILD/bench/refine_keypoints"
data="$BAYON_DATA_DIR"
mkdir -p "$dir"
datasets=("$@")
[ ${#datasets[@]} -gt 0 ] || datasets=(temple fountain)

# A consistent copy of a database (COLMAP rewrites the pragmas of every
# database it opens; the copy keeps the original as it is).
copy_db() {
  python3 - "$1" "$2" <<'EOF'
import sqlite3, sys
src = sqlite3.connect("file:%s?mode=ro" % sys.argv[1], uri=True)
dst = sqlite3.connect(sys.argv[2])
src.backup(dst)
dst.close()
EOF
}
seconds() {
  sed -n 's/.*Elapsed (wall clock) time (h:mm:ss or m:ss): //p' "$1" |
    awk -F: '{ s = 0; for (i = 1; i <= NF; ++i) s = s * 60 + $i; print s }'
}

# stock NAME IMAGES SIFT_OPTIONS...: the stock COLMAP database, once.
stock() {
  local name="$1" images="$2"
  shift 2
  local work="$dir/$name"
  if [ ! -f "$work/stock.db" ]; then
    rm -rf "$work"
    mkdir -p "$work"
    /usr/bin/time -v -o "$work/sift.time" colmap feature_extractor \
      --database_path "$work/building.db" --image_path "$images" \
      --ImageReader.single_camera 1 --SiftExtraction.use_gpu 0 "$@" \
      >"$work/feature_extractor.log" 2>&1
    /usr/bin/time -v -o "$work/match.time" colmap exhaustive_matcher \
      --database_path "$work/building.db" --SiftMatching.use_gpu 0 \
      >"$work/exhaustive_matcher.log" 2>&1
    mv "$work/building.db" "$work/stock.db"
  fi
}

# mapper NAME IMAGES LABEL DB: colmap mapper on a copy of DB, the model with
# the most images evaluated; prints one table row.
mapper() {
  local name="$1" images="$2" label="$3" db="$4"
  local work="$dir/$name/$label"
  rm -rf "$work"
  mkdir -p "$work/sparse"
  copy_db "$db" "$work/database.db"
  /usr/bin/time -v -o "$work/mapper.time" colmap mapper \
    --database_path "$work/database.db" --image_path "$images" \
    --output_path "$work/sparse" >"$work/mapper.log" 2>&1
  local best="" best_n=-1 model n
  for model in "$work"/sparse/*/; do
    [ -f "$model/images.bin" ] || continue
    n=$(colmap model_analyzer --path "$model" 2>&1 |
      sed -n 's/.*Registered images: \([0-9]*\).*/\1/p')
    if [ "${n:-0}" -gt "$best_n" ]; then best="$model" best_n="$n"; fi
  done
  if [ -z "$best" ]; then
    printf '%-10s %-10s mapper made no model (see %s)\n' "$name" "$label" \
      "$work/mapper.log"
    return
  fi
  colmap model_analyzer --path "$best" >"$work/model_analyzer.log" 2>&1
  "$BAYON" evaluate --input_path "$best" --ground_truth_path "$dir/$name/truth" \
    --output_path "$work/evaluate.json" --label "$name $label" \
    >"$work/evaluate.log" 2>&1
  python3 - "$work/evaluate.json" "$work/model_analyzer.log" \
    "$(seconds "$work/mapper.time")" "$name" "$label" <<'EOF'
import json, re, sys
s = json.load(open(sys.argv[1]))["sparse"]
log = open(sys.argv[2]).read()
def figure(name):
    m = re.search(name + r":\s*([0-9.]+)", log)
    return float(m.group(1)) if m else float("nan")
print("%-10s %-10s %5d/%-3d %7d %8d %9.4f %12.6g %9.4f %10.5f %7.1f" % (
    sys.argv[4], sys.argv[5], s["num_registered"], s["num_truth_images"],
    figure("Points"), figure("Observations"),
    figure("Mean reprojection error"), s["center_rms"],
    100 * s["center_rms_relative"], s["rotation_rms_deg"],
    float(sys.argv[3])))
EOF
}

# run NAME IMAGES TRUTH_FORMAT TRUTH_PATH SIFT_OPTIONS...
run() {
  local name="$1" images="$2" format="$3" truth="$4"
  shift 4
  stock "$name" "$images" "$@"
  local work="$dir/$name"
  rm -rf "$work/truth"
  "$BAYON" import_ground_truth --format "$format" --input_path "$truth" \
    --image_path "$images" --output_path "$work/truth" >"$work/truth.log" 2>&1
  /usr/bin/time -v -o "$work/refine.time" "$BAYON" refine_keypoints \
    --database_path "$work/stock.db" --image_path "$images" \
    --output_path "$work/refined.db" --overwrite 1 \
    --report_path "$work/refine.json" --log_path "$work/refine.log" \
    >"$work/refine_keypoints.log" 2>&1
  refine_lines+=("$(python3 - "$work/refine.json" "$name" \
    "$(seconds "$work/refine.time")" <<'EOF'
import json, sys
r = json.load(open(sys.argv[1]))
rejected = ", ".join("%s %d" % (k, v) for k, v in r["outcomes"].items()
                     if k not in ("reference", "refined") and v)
print("%s: %d tracks, %d of %d observations refined (%.1f %%), %d rejected "
      "(%s), median shift %.3f px, %.1f s" % (
          sys.argv[2], r["num_tracks"], r["num_refined"],
          r["num_observations"] - r["num_reference"],
          100.0 * r["num_refined"] / max(1, r["num_observations"] - r["num_reference"]),
          r["num_rejected"], rejected, r["median_shift_px"], float(sys.argv[3])))
EOF
)")
  rows+=("$(mapper "$name" "$images" stock "$work/stock.db")")
  rows+=("$(mapper "$name" "$images" refined "$work/refined.db")")
}

rows=()
refine_lines=()
for dataset in "${datasets[@]}"; do
  case "$dataset" in
    temple)
      run temple "$data/temple-ring" middlebury \
        "$data/temple-ring/templeSR_par.txt"
      ;;
    fountain)
      run fountain "$data/fountain-P11/images" strecha \
        "$data/fountain-P11/gt_dense_cameras" \
        --SiftExtraction.max_image_size 1600
      ;;
    *)
      echo "refine_keypoints.sh: unknown data set '$dataset' (temple, fountain)" >&2
      exit 2
      ;;
  esac
done

printf '%-10s %-10s %9s %7s %8s %9s %12s %9s %10s %7s\n' "data" "database" \
  "registered" "points" "obs." "reproj px" "centre RMS" "centre %" \
  "rot deg" "map s"
for row in "${rows[@]}"; do echo "$row"; done
for line in "${refine_lines[@]}"; do echo "$line"; done
echo "centre RMS in the truth's units (metres), after a 7-parameter similarity;"
echo "reproj: colmap model_analyzer's mean reprojection error"
echo "outputs and logs in $dir"
