#!/usr/bin/env bash
# Benchmark of `bayon adjust` against `colmap bundle_adjuster` on the same
# models, with wall time, peak memory and the final figures:
#  1. ../shared/data/bundle/ladybug-49-7776 (a BAL problem, imported with
#     `bayon import_bal`): both adjust the 49 RADIAL cameras (focal length and
#     k1, k2 per camera, principal point fixed) in one solution, as COLMAP
#     does; bayon adds the statistics (inverse of the normal equations).
#  2. a stock `colmap mapper` model of ../shared/data/sceaux-castle (SIFT at
#     1600 px, made once and kept in build/bench/adjust/sceaux): COLMAP's
#     bundle adjustment of its SIMPLE_RADIAL camera, bayon on the same
#     camera, and bayon's full run (two steps, the ten additional parameters
#     selected by significance, robust solution and data snooping).
#   scripts/bench.sh adjust
set -euo pipefail
dir="$BAYON_BUILD/bench/adjust"
data="$BAYON_DATA_DIR"
mkdir -p "$dir"

source "$(dirname "$0")/lib/timing.sh"
# Figures from the reports: bayon's adjustment.json, COLMAP's log.
bayon_figures() {
  python3 - "$1" <<'EOF'
import json, sys
s = json.load(open(sys.argv[1]))["statistics"]
# COLMAP's "final cost" is sqrt(0.5 sum v^2 / n) (unit weights).
colmap_cost = (s["sigma0_px"] ** 2 * s["r"] / (2 * s["n"])) ** 0.5
print("sigma0 %.4f px, mean reproj. %.4f px, r/n %.3f (COLMAP's final "
      "cost %.6f px)" % (s["sigma0_px"], s["mean_reprojection_error_px"],
                        s["r_over_n"], colmap_cost))
EOF
}
colmap_figures() {
  local final iterations
  final=$(sed -n 's/.*Final cost : \([0-9.e+-]*\) \[px\].*/\1/p' "$dir/$1.log" | tail -1)
  iterations=$(sed -n 's/.*Iterations : \([0-9]*\).*/\1/p' "$dir/$1.log" | tail -1)
  echo "final cost ${final} px, ${iterations} iterations"
}
row() {
  printf '%-44s %7.1f %7s   %s\n' "$1" "$(wall_s "$dir/$2")" "$(peak_mb "$dir/$2")" "$3"
}

# --- 1. BAL ladybug-49-7776
bal="$dir/ladybug"
rm -rf "$bal"
"$BAYON" import_bal --input_path "$data/bundle/ladybug-49-7776/problem-49-7776-pre.txt" \
  --output_path "$bal" >/dev/null
mkdir -p "$bal/sparse/colmap"
timed "$dir/bal_bayon" "$BAYON" adjust --database_path "$bal/database.db" \
  --input_path "$bal/sparse/0" --output_path "$bal/sparse/bayon" \
  --camera_model colmap --self_calibration all --two_steps 0 \
  --blunder_detection none --datum free --log_path "$bal/adjust.log"
timed "$dir/bal_colmap" colmap bundle_adjuster --input_path "$bal/sparse/0" \
  --output_path "$bal/sparse/colmap"

# --- 2. sceaux-castle, stock COLMAP model
sceaux="$dir/sceaux"
if [ ! -f "$sceaux/sparse/0/images.bin" ]; then
  rm -rf "$sceaux"
  mkdir -p "$sceaux/sparse"
  colmap feature_extractor --database_path "$sceaux/database.db" \
    --image_path "$data/sceaux-castle/images" --ImageReader.single_camera 1 \
    --SiftExtraction.use_gpu 0 --SiftExtraction.max_image_size 1600 \
    >"$sceaux/features.log" 2>&1
  colmap exhaustive_matcher --database_path "$sceaux/database.db" \
    --SiftMatching.use_gpu 0 >"$sceaux/matcher.log" 2>&1
  colmap mapper --database_path "$sceaux/database.db" \
    --image_path "$data/sceaux-castle/images" --output_path "$sceaux/sparse" \
    >"$sceaux/mapper.log" 2>&1
fi
rm -rf "$sceaux/adjusted" "$sceaux/adjusted_colmap_camera" "$sceaux/adjusted_aps" \
  "$sceaux/colmap_ba"
mkdir -p "$sceaux/colmap_ba"
timed "$dir/sceaux_colmap" colmap bundle_adjuster --input_path "$sceaux/sparse/0" \
  --output_path "$sceaux/colmap_ba"
timed "$dir/sceaux_bayon_same" "$BAYON" adjust --database_path "$sceaux/database.db" \
  --input_path "$sceaux/sparse/0" --output_path "$sceaux/adjusted_colmap_camera" \
  --camera_model colmap --self_calibration all --two_steps 0 \
  --blunder_detection none --datum free --log_path "$sceaux/adjust.log"
timed "$dir/sceaux_bayon_aps" "$BAYON" adjust --database_path "$sceaux/database.db" \
  --input_path "$sceaux/sparse/0" --output_path "$sceaux/adjusted_aps" \
  --blunder_detection none --log_path "$sceaux/adjust.log"
timed "$dir/sceaux_bayon_full" "$BAYON" adjust --database_path "$sceaux/database.db" \
  --input_path "$sceaux/sparse/0" --output_path "$sceaux/adjusted" \
  --log_path "$sceaux/adjust.log"
colmap_mean=$(colmap model_analyzer --path "$sceaux/sparse/0" 2>&1 |
  sed -n 's/.*Mean reprojection error: \([0-9.]*\)px.*/\1/p')

printf '%-44s %7s %7s   %s\n' "problem / program" "time s" "peak MB" "result"
row "ladybug-49-7776: colmap bundle_adjuster" bal_colmap "$(colmap_figures bal_colmap)"
row "ladybug-49-7776: bayon adjust (same cameras)" bal_bayon \
  "$(bayon_figures "$bal/sparse/bayon/adjustment.json")"
row "sceaux: colmap bundle_adjuster" sceaux_colmap "$(colmap_figures sceaux_colmap)"
row "sceaux: bayon adjust (same camera)" sceaux_bayon_same \
  "$(bayon_figures "$sceaux/adjusted_colmap_camera/adjustment.json")"
row "sceaux: bayon adjust (10 APs selected)" sceaux_bayon_aps \
  "$(bayon_figures "$sceaux/adjusted_aps/adjustment.json")"
row "sceaux: bayon adjust (10 APs, snooping)" sceaux_bayon_full \
  "$(bayon_figures "$sceaux/adjusted/adjustment.json")"
echo "sceaux: colmap mapper's mean reprojection error ${colmap_mean} px"
awk -v a="$(wall_s "$dir/bal_bayon")" -v b="$(wall_s "$dir/bal_colmap")" \
  -v c="$(wall_s "$dir/sceaux_bayon_same")" -v d="$(wall_s "$dir/sceaux_colmap")" 'BEGIN {
  printf "time ratio bayon / colmap: ladybug %.2f, sceaux (same camera) %.2f\n",
         a / b, c / d }'
echo "outputs and logs in $dir"
