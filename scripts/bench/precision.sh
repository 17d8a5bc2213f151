#!/usr/bin/env bash
# Is the precision that `bayon adjust` states the precision it has?
#  1. Monte Carlo (ext/adjustment/precision_monte_carlo.cc): the points
#     scene of `bayon synth` (16 stations, 1500 points, 0.3 px, 8 control
#     points, 8 check points, a levelling bar) adjusted 50 times with fresh
#     noise, with control, in the minimum datum and as a free network. Per
#     datum: the stated standard deviations of the tie points and camera
#     centres (RMS), stated / empirical per axis (pooled), the median ratio
#     over the coordinates and the share of coordinates within 0.8-1.25
#     (with 50 draws an empirical standard deviation is itself uncertain by
#     about 10 %, so about 96 % is what a correct covariance gives).
#  2. temple-ring as the demo orients it (free network, the calibrated
#     camera): the stated standard deviations of the camera stations beside
#     their true errors (`bayon evaluate`: after a similarity over the
#     centres), in the truth's units.
#   scripts/bench.sh precision [num_draws]
set -euo pipefail
dir="$BAYON_BUILD/bench/precision"
threads="${BAYON_THREADS:-2}"
draws="${1:-50}"
rm -rf "$dir"
mkdir -p "$dir"
cmake --build "$BAYON_BUILD" --target adjustment_precision_monte_carlo >/dev/null
"$BAYON_BUILD/ext/adjustment/adjustment_precision_monte_carlo" \
  --num_draws "$draws" --num_threads "$threads"

echo
ws="$dir/temple"
data="$BAYON_DATA_DIR/temple-ring"
mkdir -p "$ws"
"$BAYON" import_ground_truth --format middlebury \
  --input_path "$data/templeSR_par.txt" --output_path "$dir/truth" >/dev/null
params=$(grep -v '^#' "$dir/truth/cameras.txt" | head -1 | cut -d' ' -f5- | tr ' ' ',')
model=$(grep -v '^#' "$dir/truth/cameras.txt" | head -1 | cut -d' ' -f2)
cat >"$dir/temple.ini" <<INI
[import]
camera_model = $model
camera_params = $params
[match]
pairing = exhaustive
[adjust]
datum = free
self_calibration = none
INI
"$BAYON" pipeline --workspace_path "$ws" --image_path "$data" \
  --config configs/ring.ini --config "$dir/temple.ini" --to_stage adjust \
  --num_threads "$threads" >"$dir/temple.log" 2>&1
"$BAYON" evaluate --ground_truth_path "$dir/truth" \
  --input_path "$ws/sparse/adjusted" --output_path "$dir/temple_eval.json" \
  >/dev/null
python3 - "$ws/sparse/adjusted/adjustment.json" "$dir/temple_eval.json" <<'EOF'
import json, math, sys
adjustment = json.load(open(sys.argv[1]))
sparse = json.load(open(sys.argv[2]))["sparse"]
scale = sparse["similarity"]["scale"]  # truth units per model unit
s = adjustment["statistics"]
def rms3(v):
    return math.sqrt(sum(x * x for x in v))
stated_center = scale * rms3(s["center_precision_rms_mm"]) / 1000
stated_rotation = rms3(s["rotation_precision_rms_mdeg"]) / 1000
distance = sparse["mean_camera_distance"]
print("temple-ring, free network (%d datum points; %s): %d images" %
      (adjustment["datum"]["num_datum_points"],
       "stated sigmas relative to their centroid",
       s["num_images"]))
print("%-34s %12s %12s" % ("", "stated (RMS)", "true (RMS)"))
print("%-34s %11.3f%% %11.3f%%" % ("camera centre, 3D, of the distance",
      100 * stated_center / distance,
      100 * sparse["center_rms_relative"]))
print("%-34s %10.3f deg %8.3f deg" % ("rotation, 3 axes",
      stated_rotation, sparse["rotation_rms_deg"]))
print("%-34s %12.3f" % ("tie points, 3D, model mm",
      rms3(s["point_precision_rms_mm"])))
print("sigma0 %.3f px; %d tie points whose rays meet at less than %.1f deg "
      "kept apart" % (s["sigma0_px"], s["num_weak_tie_points"],
                      s["min_intersection_angle_deg"]))
EOF
echo "outputs and logs in $dir"
