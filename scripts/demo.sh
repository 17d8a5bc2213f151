#!/usr/bin/env bash
# The main job on an embedded default, on a fresh machine: set up, make a
# synthetic ring of 16 photographs around an object with known truth, write it
# as a COLMAP project with bayon, reconstruct it with stock `colmap mapper`
# from bayon's database, and print the accuracy against the truth.
#   scripts/demo.sh [WORKSPACE]     (default: demo-workspace/)
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
bayon=build/tools/bayon
ws=${1:-demo-workspace}
rm -rf "$ws"
start=$(date +%s)

echo "== 1. bayon synth: 16 stations around 1500 points, 0.3 px noise"
$bayon synth --scene points --output_path "$ws/synthetic" --num_views 16 \
  --keypoint_noise_px 0.3 --seed 1

echo "== 2. colmap mapper on bayon's database (a copy: COLMAP rewrites pragmas)"
cp "$ws/synthetic/database.db" "$ws/colmap.db"
mkdir -p "$ws/sparse"
colmap mapper --database_path "$ws/colmap.db" --image_path "$ws/synthetic/images" \
  --output_path "$ws/sparse" --Mapper.ba_refine_extra_params 0 \
  > "$ws/colmap_mapper.log" 2>&1
echo "   log: $ws/colmap_mapper.log"

echo "== 3. bayon evaluate: the COLMAP model against the truth"
$bayon evaluate --input_path "$ws/sparse/0" --ground_truth_path "$ws/synthetic/gt/sparse" \
  --label "colmap mapper" --output_path "$ws/evaluation.json"
echo "   (centre errors in metres on a ring of radius 10 m; report: $ws/evaluation.json)"
echo "demo finished in $(( $(date +%s) - start )) s"
