#!/usr/bin/env bash
# Issue 31's table: bayon's chain and stock COLMAP 3.8 side by side in the
# same run, each knowing the same about the camera, on the three real sets
# with ground truth, judged by `bayon evaluate` against the truth:
#  - calibrated: the truth's PINHOLE camera. bayon holds it (no
#    self-calibration, the demo's way); COLMAP gets it as
#    --ImageReader.camera_params and holds it (--Mapper.ba_refine_* 0);
#  - nothing: no calibration, no EXIF. bayon's import guesses 1.2 x the long
#    side, `relative` estimates the focal length from the photographs where
#    the pairs fix it (else strip keeps the guess and adjust estimates it
#    first), and adjust self-calibrates (significant); COLMAP starts from
#    the same guess (SIMPLE_RADIAL, its default) and refines it in its
#    mapper;
#  - focal5: a focal length 5 % too long, as EXIF gives a lens (principal
#    point at the image centre). bayon: import --focal_length_mm
#    --pixel_size_um, adjust self-calibrates; COLMAP: that focal length as
#    SIMPLE_RADIAL camera_params (its prior), refined in its mapper.
# Sets: ../shared/data/temple-ring (16 x 640x480, exhaustive pairs),
# fountain-P11 (11 x 3072x2048; bayon 3 successors per image, COLMAP
# exhaustive, SIFT at 2000 px), herz-jesu-P8 (8 x 3072x2048, exhaustive).
#   scripts/bench.sh uncalibrated [MODE...]   (default: calibrated nothing focal5)
# About 20 min on 2 cores. Outputs under $BAYON_BUILD/bench/uncalibrated;
# nothing is written into the data folder. BAYON_THREADS (default 2).
set -euo pipefail
dir="$BAYON_BUILD/bench/uncalibrated"
data="$BAYON_DATA_DIR"
threads="${BAYON_THREADS:-2}"
modes=("$@")
[ ${#modes[@]} -gt 0 ] || modes=(calibrated nothing focal5)
mkdir -p "$dir"
source "$(dirname "$0")/lib/timing.sh"
source "$(dirname "$0")/lib/bayon_chain.sh"
source "$(dirname "$0")/lib/colmap.sh"

# colmap_run WS IMAGES MODE TRUTH MAX_IMAGE_SIZE
colmap_run() {
  local ws="$1" images="$2" mode="$3" truth="$4" max_size="$5"
  local fx fy cx cy width height
  read -r fx fy cx cy width height < <(truth_camera "$truth")
  local reader=(--ImageReader.camera_model SIMPLE_RADIAL) mapper=()
  case "$mode" in
    calibrated)
      reader=(--ImageReader.camera_model PINHOLE
        --ImageReader.camera_params "$fx,$fy,$cx,$cy")
      mapper=(--Mapper.ba_refine_focal_length 0
        --Mapper.ba_refine_principal_point 0 --Mapper.ba_refine_extra_params 0) ;;
    nothing) ;;
    focal5)
      reader+=(--ImageReader.camera_params "$(python3 -c "
print('%r,%r,%r,0' % (1.05 * ($fx + $fy) / 2, $width / 2, $height / 2))")") ;;
  esac
  mkdir -p "$ws/sparse"
  timed "$ws/features" colmap feature_extractor --database_path "$ws/database.db" \
    --image_path "$images" --ImageReader.single_camera 1 "${reader[@]}" \
    --SiftExtraction.use_gpu 0 --SiftExtraction.max_image_size "$max_size" \
    --SiftExtraction.num_threads "$threads"
  timed "$ws/matches" colmap exhaustive_matcher --database_path "$ws/database.db" \
    --SiftMatching.use_gpu 0 --SiftMatching.num_threads "$threads"
  timed "$ws/mapper" colmap mapper --database_path "$ws/database.db" \
    --image_path "$images" --output_path "$ws/sparse" \
    --Mapper.num_threads "$threads" "${mapper[@]}"
  local model
  model=$(largest_model "$ws/sparse")
  [ -n "$model" ] && ln -sfn "$model" "$ws/model"
  return 0
}

# one SET IMAGES FORMAT TRUTH_INPUT MAX_IMAGE_SIZE BAYON_MATCH_ARGS...
one() {
  local set="$1" images="$2" format="$3" truth_input="$4" max_size="$5"
  shift 5
  local truth="$dir/$set/truth"
  fresh_truth "$dir/$set" "$images" "$format" "$truth_input"
  for mode in "${modes[@]}"; do
    local ws="$dir/$set/$mode"
    mkdir -p "$ws/bayon" "$ws/colmap"
    echo "uncalibrated.sh: $set, $mode" >&2
    bayon_run "$ws/bayon" "$images" "$mode" "$truth" "$@"
    judge "$ws/bayon" "$truth" "$set $mode bayon"
    colmap_run "$ws/colmap" "$images" "$mode" "$truth" "$max_size"
    judge "$ws/colmap" "$truth" "$set $mode colmap"
  done
}

one temple "$data/temple-ring" middlebury \
  "$data/temple-ring/templeSR_par.txt" 3200 --pairing exhaustive
one fountain "$data/fountain-P11/images" strecha \
  "$data/fountain-P11/gt_dense_cameras" 2000 --pairing sequential --num_neighbors 3
one herz-jesu "$data/herz-jesu-P8/images" strecha \
  "$data/herz-jesu-P8/gt_dense_cameras" 2000 --pairing exhaustive

python3 - "$dir" "${modes[@]}" <<'EOF'
import json, os, sys
root, modes = sys.argv[1], sys.argv[2:]

def focal(model_txt):
    """The model camera's mean focal length, pixels (COLMAP's text)."""
    try:
        line = next(l for l in open(os.path.join(model_txt, "cameras.txt"))
                    if not l.startswith("#"))
    except (OSError, StopIteration):
        return None
    words = line.split()
    params = [float(w) for w in words[4:]]
    two = words[1] in ("PINHOLE", "OPENCV", "FULL_OPENCV", "OPENCV_FISHEYE")
    return (params[0] + params[1]) / 2 if two else params[0]

print("\n%-9s %-10s %-7s %10s %9s %9s %10s %10s %9s" % (
    "set", "camera", "program", "registered", "f", "f error",
    "centre RMS", "centre %", "rot RMS"))
print("%-9s %-10s %-7s %10s %9s %9s %10s %10s %9s" % (
    "", "", "", "", "px", "%", "mm", "", "deg"))
for set_name in ("temple", "fountain", "herz-jesu"):
    truth_f = focal(os.path.join(root, set_name, "truth"))
    for mode in modes:
        for program in ("bayon", "colmap"):
            ws = os.path.join(root, set_name, mode, program)
            path = os.path.join(ws, "evaluation.json")
            if not os.path.exists(path):
                print("%-9s %-10s %-7s %10s" % (set_name, mode, program,
                                                "failed"))
                continue
            e = json.load(open(path))["sparse"]
            f = focal(os.path.join(ws, "model_txt"))
            print("%-9s %-10s %-7s %6d/%-3d %9.1f %9.2f %10.3f %10.4f %9.4f" % (
                set_name, mode, program, e["num_registered"],
                e["num_truth_images"], f or 0,
                100 * (f / truth_f - 1) if f and truth_f else 0,
                1000 * e["center_rms"], 100 * e["center_rms_relative"],
                e["rotation_rms_deg"]))
print("\ncalibrated: both hold the truth's camera; nothing: both start from"
      "\n1.2 x the long side (bayon estimates it in `relative` where the pairs"
      "\nfix it, else first in adjust, then self-calibrates; COLMAP refines it"
      "\nin its mapper); focal5: both start"
      "\nfrom 1.05 x the true focal length and refine it. f: the model's mean"
      "\nfocal length (temple: the truth's fx, fy differ by 0.4 %). centre %:"
      "\nRMS centre error / mean camera-to-centroid distance after the"
      "\n7-parameter similarity. failed: no model (see the logs in "
      "\n" + root + "/SET/MODE/bayon).")
EOF
