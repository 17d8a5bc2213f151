#!/usr/bin/env bash
# The first line of the tower's comparison table: stock COLMAP 3.8 on the CPU
# (feature_extractor with one shared OPENCV camera, exhaustive_matcher,
# mapper, otherwise defaults) on the rendered tower (`bayon synth --scene
# tower`, 16 views, 1800 x 1200), judged by `bayon evaluate` against gt/
# (camera centres and rotations after a similarity, focal length and
# principal point against the true Brown/Beyer camera, the 3D points against
# the true surface). Also the synth benchmark's figure (render time).
#   scripts/bench.sh colmap_tower [extra synth options]
set -euo pipefail
dir="$BAYON_BUILD/bench/colmap_tower"
threads="${BAYON_THREADS:-2}"
rm -rf "$dir"
mkdir -p "$dir/sparse"
ws="$dir/ws"
/usr/bin/time -v -o "$dir/synth.time" "$BAYON" synth --scene tower \
  --output_path "$ws" --num_views 16 --image_width 1800 "$@" >"$dir/synth.log"
grep '^synth:' "$dir/synth.log"
start=$(date +%s.%N)
colmap feature_extractor --database_path "$dir/database.db" \
  --image_path "$ws/images" --ImageReader.single_camera 1 \
  --ImageReader.camera_model OPENCV --SiftExtraction.use_gpu 0 \
  --SiftExtraction.num_threads "$threads" >"$dir/features.log" 2>&1
extracted=$(date +%s.%N)
colmap exhaustive_matcher --database_path "$dir/database.db" \
  --SiftMatching.use_gpu 0 --SiftMatching.num_threads "$threads" \
  >"$dir/matches.log" 2>&1
matched=$(date +%s.%N)
colmap mapper --database_path "$dir/database.db" --image_path "$ws/images" \
  --output_path "$dir/sparse" --Mapper.num_threads "$threads" \
  >"$dir/mapper.log" 2>&1 || true  # exits 1 when it makes no model
mapped=$(date +%s.%N)
awk -v a="$start" -v b="$extracted" -v c="$matched" -v d="$mapped" 'BEGIN {
  printf "colmap times: extract %.1f s, match %.1f s, map %.1f s\n", b - a, c - b, d - c }'
sqlite3 "$dir/database.db" "SELECT 'verified pairs: ' || count(*) || ' of ' ||
  (SELECT count(*) FROM matches) || ', inlier matches: ' || sum(rows)
  FROM two_view_geometries WHERE rows > 0"
model=$(ls -d "$dir"/sparse/*/ 2>/dev/null | head -n 1)
if [ -z "$model" ]; then
  echo "tower colmap: registered 0/16 (mapper: $(grep -m1 -E 'No good initial|ERROR' "$dir/mapper.log"))"
  exit 0
fi
colmap model_converter --input_path "$model" --output_path "$model" \
  --output_type TXT >/dev/null 2>&1
colmap model_analyzer --path "$model" 2>&1 | grep -E "Registered|Points|Mean" || true
"$BAYON" evaluate --input_path "$model" --ground_truth_path "$ws/gt" \
  --label "tower colmap" --output_path "$dir/evaluation.json"
echo "outputs and logs in $dir"
