#!/usr/bin/env bash
# The first line of every comparison table: stock COLMAP 3.8 on the CPU
# (feature_extractor, exhaustive_matcher, mapper, all at their defaults but
# for one shared PINHOLE camera, both sets being distortion-free) on the two
# real rings with ground truth, judged by `bayon evaluate` against the truth
# that `bayon import_ground_truth` makes of their calibration files:
#  1. ../shared/data/temple-ring: 16 x 640x480, Middlebury templeSR_par.txt;
#  2. ../shared/data/fountain-P11: 11 x 3072x2048, Strecha gt_dense_cameras,
#     SIFT on images reduced to 2000 px (--SiftExtraction.max_image_size).
# No EXIF in either set: COLMAP starts from f = 1.2 x the long side.
#   scripts/bench.sh colmap_baseline
# Outputs under $BAYON_BUILD/bench/colmap_baseline; nothing is written into
# the data folder. BAYON_THREADS (default 2) threads for COLMAP.
set -euo pipefail
dir="$BAYON_BUILD/bench/colmap_baseline"
data="$BAYON_DATA_DIR"
threads="${BAYON_THREADS:-2}"
mkdir -p "$dir"

source "$(dirname "$0")/lib/timing.sh"
source "$(dirname "$0")/lib/colmap.sh"
# baseline NAME IMAGES MAX_IMAGE_SIZE FORMAT TRUTH_INPUT
baseline() {
  local name="$1" images="$2" max_size="$3" format="$4" truth_input="$5"
  local ws="$dir/$name"
  rm -rf "$ws"
  mkdir -p "$ws/sparse"
  local image_path_flag=()
  [ "$format" = strecha ] && image_path_flag=(--image_path "$images")
  "$BAYON" import_ground_truth --format "$format" --input_path "$truth_input" \
    --output_path "$ws/truth" "${image_path_flag[@]}" >"$ws/truth.log" 2>&1
  timed "$ws/features" colmap feature_extractor --database_path "$ws/database.db" \
    --image_path "$images" --ImageReader.single_camera 1 \
    --ImageReader.camera_model PINHOLE --SiftExtraction.use_gpu 0 \
    --SiftExtraction.max_image_size "$max_size" \
    --SiftExtraction.num_threads "$threads"
  timed "$ws/matches" colmap exhaustive_matcher --database_path "$ws/database.db" \
    --SiftMatching.use_gpu 0 --SiftMatching.num_threads "$threads"
  timed "$ws/mapper" colmap mapper --database_path "$ws/database.db" \
    --image_path "$images" --output_path "$ws/sparse" \
    --Mapper.num_threads "$threads"
  local model
  model=$(largest_model "$ws/sparse")
  [ -n "$model" ] || { echo "$name: colmap mapper made no model" >&2; return 1; }
  "$BAYON" evaluate --input_path "$model" --ground_truth_path "$ws/truth" \
    --output_path "$ws/evaluation.json" --label "$name colmap" \
    >"$ws/evaluate.log" 2>&1 || { cat "$ws/evaluate.log" >&2; return 1; }
  mkdir -p "$ws/model_txt"
  colmap model_converter --input_path "$model" --output_path "$ws/model_txt" \
    --output_type TXT >/dev/null 2>&1
  colmap model_analyzer --path "$model" >"$ws/analyzer.log" 2>&1
  echo "$model" >"$ws/model_path"
}

baseline temple "$data/temple-ring" 3200 middlebury \
  "$data/temple-ring/templeSR_par.txt"
baseline fountain "$data/fountain-P11/images" 2000 strecha \
  "$data/fountain-P11/gt_dense_cameras"

printf '\n%-9s %7s %8s %6s %10s %9s %9s %9s %9s %10s %10s %10s %10s\n' \
  set extract match map registered points "reproj" "f est" "f true" \
  "centre RMS" "centre max" "centre %" "rot RMS"
printf '%-9s %7s %8s %6s %10s %9s %9s %9s %9s %10s %10s %10s %10s\n' \
  "" s s s "" "" px px px mm mm "" deg
for name in temple fountain; do
  ws="$dir/$name"
  python3 - "$ws" "$name" "$(wall_s "$ws/features")" "$(wall_s "$ws/matches")" \
    "$(wall_s "$ws/mapper")" <<'EOF'
import json, re, sys
ws, name, t_extract, t_match, t_map = sys.argv[1:6]
e = json.load(open(ws + "/evaluation.json"))["sparse"]
def camera(path):
    for line in open(path):
        if not line.startswith("#") and line.strip():
            return line.split()
est, true = camera(ws + "/model_txt/cameras.txt"), camera(ws + "/truth/cameras.txt")
analyzer = open(ws + "/analyzer.log").read()
points = re.search(r"Points: (\d+)", analyzer).group(1)
reproj = re.search(r"Mean reprojection error: ([0-9.]+)", analyzer).group(1)
print("%-9s %7.1f %8.1f %6.1f %6d/%-3d %9s %9.2f %9.1f %9.1f %10.3f %10.3f %10.4f %10.4f"
      % (name, float(t_extract), float(t_match), float(t_map), e["num_registered"],
         e["num_truth_images"], points, float(reproj),
         (float(est[4]) + float(est[5])) / 2, (float(true[4]) + float(true[5])) / 2,
         1000 * e["center_rms"], 1000 * e["center_max"],
         100 * e["center_rms_relative"], e["rotation_rms_deg"]))
EOF
done
echo
echo "f est / f true: mean of fx, fy of COLMAP's camera and of the truth;"
echo "centre %: RMS centre error / mean camera-to-centroid distance, after the"
echo "7-parameter similarity fitted by bayon evaluate. bayon evaluate's tables:"
for name in temple fountain; do
  grep -v '^evaluate:' "$dir/$name/evaluate.log" || true
done
echo "outputs and logs in $dir"
