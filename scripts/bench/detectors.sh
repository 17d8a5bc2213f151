#!/usr/bin/env bash
# Issue 31 part 2: which candidates orient best. bayon's chain (features,
# match, relative, disparity, tiepoints, strip, adjust) with each detector:
#  - moravec: the paper's points, matched by correlation and relaxation;
#  - sift: SIFT keypoints (OpenCV), matched by RootSIFT descriptor (ratio
#    test 0.8, mutual best);
#  - both: the two sets side by side, each matched its own way.
# Cameras: calibrated (the truth's PINHOLE camera held, no
# self-calibration) and nothing (no focal length: estimated in `relative`,
# then self-calibration), as `scripts/bench.sh uncalibrated` defines them.
# Sets: temple-ring (exhaustive pairs), fountain-P11 (3 successors),
# herz-jesu-P8 (exhaustive), judged by `bayon evaluate` against the truth;
# and the rendered tower (`bayon synth --scene tower`, seed 1, 1200 x 800,
# the true camera, exhaustive pairs), where the pairs themselves are judged
# too: how many are oriented, and how many of those are false (rotation
# more than 5 deg from the truth).
#   scripts/bench.sh detectors [DETECTOR...]   (default: moravec sift both)
# About 25 min on 2 cores. Outputs under $BAYON_BUILD/bench/detectors.
set -euo pipefail
dir="$BAYON_BUILD/bench/detectors"
data="$BAYON_DATA_DIR"
threads="${BAYON_THREADS:-2}"
detectors=("$@")
[ ${#detectors[@]} -gt 0 ] || detectors=(moravec sift both)
mkdir -p "$dir"
source "$(dirname "$0")/lib/timing.sh"
source "$(dirname "$0")/lib/bayon_chain.sh"

# one SET IMAGES FORMAT TRUTH_INPUT MATCH_ARGS...
one() {
  local set="$1" images="$2" format="$3" truth_input="$4"
  shift 4
  local truth="$dir/$set/truth"
  fresh_truth "$dir/$set" "$images" "$format" "$truth_input"
  for detector in "${detectors[@]}"; do
    for mode in calibrated nothing; do
      local ws="$dir/$set/$detector/$mode"
      mkdir -p "$ws"
      echo "detectors.sh: $set, $detector, $mode" >&2
      BAYON_DETECTOR="$detector" bayon_run "$ws" "$images" "$mode" "$truth" "$@"
      judge "$ws" "$truth" "$set $detector $mode"
    done
  done
}

# The rendered tower: the pairs, then the chain with the true camera.
tower() {
  local ws="$dir/tower/scene"
  rm -rf "$dir/tower"
  mkdir -p "$dir/tower"
  "$BAYON" synth --scene tower --output_path "$ws" --image_width 1200 \
    --supersampling 2 --num_heldout_views 0 --num_threads "$threads" \
    >"$dir/tower/synth.log" 2>&1
  for detector in "${detectors[@]}"; do
    local run="$dir/tower/$detector/calibrated"
    mkdir -p "$run"
    echo "detectors.sh: tower, $detector" >&2
    cp "$ws/database.db" "$run/database.db"
    # The tower's Moravec points as its tests take them: one per 8-pixel
    # patch.
    local moravec=()
    [ "$detector" = sift ] || moravec=(--patch_size 8 --max_num_features 0)
    timed "$run/features" "$BAYON" features --database_path "$run/database.db" \
      --image_path "$ws/images" --detector "$detector" --overwrite 1 \
      "${moravec[@]}" --num_threads "$threads"
    timed "$run/match" "$BAYON" match --database_path "$run/database.db" \
      --image_path "$ws/images" --pairing exhaustive --num_threads "$threads"
    for stage in relative disparity; do
      timed "$run/$stage" "$BAYON" "$stage" --database_path "$run/database.db" \
        --num_threads "$threads"
    done
    "$BAYON" evaluate --ground_truth_path "$ws/gt" \
      --database_path "$run/database.db" --output_path "$run/pairs.json" \
      >"$run/pairs.txt" 2>&1 || true
    timed "$run/tiepoints" "$BAYON" tiepoints --database_path "$run/database.db" \
      --image_path "$ws/images" --num_threads "$threads"
    timed "$run/strip" "$BAYON" strip --database_path "$run/database.db" \
      --output_path "$run/initial" --num_threads "$threads" || continue
    timed "$run/adjust" "$BAYON" adjust --database_path "$run/database.db" \
      --input_path "$run/initial" --output_path "$run/model" --datum free \
      --self_calibration none --num_threads "$threads" || continue
    "$BAYON" evaluate --input_path "$run/model" --ground_truth_path "$ws/gt" \
      --output_path "$run/evaluation.json" >"$run/evaluate.log" 2>&1 || true
  done
}

one temple "$data/temple-ring" middlebury \
  "$data/temple-ring/templeSR_par.txt" --pairing exhaustive
one fountain "$data/fountain-P11/images" strecha \
  "$data/fountain-P11/gt_dense_cameras" --pairing sequential --num_neighbors 3
one herz-jesu "$data/herz-jesu-P8/images" strecha \
  "$data/herz-jesu-P8/gt_dense_cameras" --pairing exhaustive
tower

python3 - "$dir" "${detectors[@]}" <<'PY'
import json, os, re, sys
root, detectors = sys.argv[1], sys.argv[2:]

def seconds(ws, stage):
    """Wall time of a stage from /usr/bin/time's record (lib/timing.sh)."""
    try:
        text = open(os.path.join(ws, stage + ".time")).read()
    except OSError:
        return 0.0
    m = re.search(r"Elapsed \(wall clock\) time \(h:mm:ss or m:ss\): (\S+)", text)
    if not m:
        return 0.0
    total = 0.0
    for part in m.group(1).split(":"):
        total = 60 * total + float(part)
    return total

def pairs(ws):
    """Oriented pairs: the summary line of relative's log."""
    try:
        line = open(os.path.join(ws, "relative.log")).read().strip().splitlines()[-1]
    except (OSError, IndexError):
        return "-"
    m = re.search(r"(\d+) pairs oriented", line)
    return m.group(1) if m else "-"

print("\n%-9s %-8s %-10s %10s %6s %10s %10s %9s %8s" % (
    "set", "detector", "camera", "registered", "pairs", "centre RMS",
    "centre %", "rot RMS", "feat+match"))
print("%-9s %-8s %-10s %10s %6s %10s %10s %9s %8s" % (
    "", "", "", "", "", "mm", "", "deg", "s"))
for set_name in ("temple", "fountain", "herz-jesu", "tower"):
    for detector in detectors:
        for mode in ("calibrated", "nothing"):
            ws = os.path.join(root, set_name, detector, mode)
            if not os.path.isdir(ws):
                continue
            t = seconds(ws, "features") + seconds(ws, "match")
            path = os.path.join(ws, "evaluation.json")
            if not os.path.exists(path):
                print("%-9s %-8s %-10s %10s %6s %10s %10s %9s %8.1f" % (
                    set_name, detector, mode, "failed", pairs(ws), "", "", "", t))
                continue
            e = json.load(open(path))["sparse"]
            scale = 1000 if set_name != "tower" else 1
            print("%-9s %-8s %-10s %6d/%-3d %6s %10.3f %10.4f %9.4f %8.1f" % (
                set_name, detector, mode, e["num_registered"],
                e["num_truth_images"], pairs(ws), scale * e["center_rms"],
                100 * e["center_rms_relative"], e["rotation_rms_deg"], t))
print("\ntower pairs (exhaustive, true camera; false: rotation > 5 deg off):")
for detector in detectors:
    path = os.path.join(root, "tower", detector, "calibrated", "pairs.json")
    try:
        r = json.load(open(path))["relative"]
    except (OSError, KeyError, ValueError):
        print("  %-8s failed" % detector)
        continue
    oriented = [p for p in r["pairs"] if p.get("oriented")]
    false = [p for p in oriented if p.get("rotation_error_deg", 0) > 5]
    # What strip's view graph left out (strip.json), and so the false pairs
    # left in its input.
    try:
        strip = json.load(open(os.path.join(
            root, "tower", detector, "calibrated", "initial", "strip.json")))
        dropped = {frozenset(line.split(":")[0].split(" - "))
                   for line in strip["dropped_pairs"]}
    except (OSError, KeyError, ValueError):
        dropped = set()
    left = [p for p in false
            if frozenset((p["image1"], p["image2"])) not in dropped]
    print("  %-8s %3d oriented, %d false: %s; strip dropped %d, %d false left"
          % (detector, len(oriented), len(false),
             ", ".join("%s-%s %.0f deg" % (p["image1"][6:9], p["image2"][6:9],
                                           p["rotation_error_deg"])
                       for p in false),
             len(dropped), len(left)))
print("\ncentre RMS in mm for the real sets, model units for the tower; "
      "pairs: oriented by `relative`;\nfeat+match: wall time of features "
      "and match on %s cores." % os.environ.get("BAYON_THREADS", "2"))
PY
