#!/usr/bin/env bash
# Checksums of what the chain writes, to show that a refactoring changed no
# output (issue 33). One thread, so that every run writes the same bytes:
#  1. temple-ring with its calibrated camera, as scripts/demo.sh gives it,
#     `bayon pipeline` to the mesh: the adjusted model, the dense cloud and
#     the mesh (relative orientation's LMedS, the bundle, dense, mesh);
#  2. the rendered tower as scanned film (`synth --film_scan 1`),
#     `bayon pipeline --config configs/film.ini` to relative: the database's
#     records of virtual fiducials, correlation matching and relative
#     orientation (sqlite3 dumps);
#  3. a synthetic block with 8 control points (`synth --scene points`),
#     `bayon strip` with its control: the similarity onto them (LMedS).
#   scripts/bench.sh checksums [OUT]
# prints one line per file (sha256, then the file) and writes them to OUT
# (default build/bench/checksums/checksums.txt), so that two builds compare
# by diff. Outputs under $BAYON_BUILD/bench/checksums.
set -euo pipefail
dir="$BAYON_BUILD/bench/checksums"
out="${1:-$dir/checksums.txt}"
data="$BAYON_DATA_DIR"
rm -rf "$dir/temple" "$dir/tower" "$dir/points"
mkdir -p "$dir/temple" "$dir/tower" "$dir/points"

# 1. The temple, calibrated.
"$BAYON" import_ground_truth --format middlebury \
  --input_path "$data/temple-ring/templeSR_par.txt" \
  --output_path "$dir/temple/gt" >/dev/null
camera=$(grep -v '^#' "$dir/temple/gt/cameras.txt" | head -1)
cat >"$dir/temple.ini" <<INI
[import]
camera_model = $(echo "$camera" | cut -d' ' -f2)
camera_params = $(echo "$camera" | cut -d' ' -f5- | tr ' ' ',')
[adjust]
datum = free
self_calibration = none
INI
"$BAYON" pipeline --workspace_path "$dir/temple/ws" \
  --image_path "$data/temple-ring" --config configs/ring.ini \
  --config "$dir/temple.ini" --to_stage mesh --num_threads 1 \
  >"$dir/temple.log" 2>&1 || {
  echo "checksums.sh: the temple pipeline failed; see $dir/temple.log" >&2
  exit 1
}

# 2. The tower as scanned film, to relative orientation: its records.
"$BAYON" synth --scene tower --output_path "$dir/tower/ws" --film_scan 1 \
  >"$dir/synth.log" 2>&1 || {
  echo "checksums.sh: synth failed; see $dir/synth.log" >&2
  exit 1
}
"$BAYON" pipeline --workspace_path "$dir/tower/ws" \
  --image_path "$dir/tower/ws/images" --config configs/film.ini \
  --to_stage relative --num_threads 1 >"$dir/tower.log" 2>&1 || {
  echo "checksums.sh: the tower pipeline failed; see $dir/tower.log" >&2
  exit 1
}
# Every column but the time a record took (`seconds`).
for table in bayon_interior matches two_view_geometries \
  bayon_relative_orientation; do
  db="$dir/tower/ws/database.db"
  columns=$(sqlite3 "$db" "SELECT group_concat(name) FROM
    pragma_table_info('$table') WHERE name != 'seconds'")
  sqlite3 "$db" "SELECT $columns FROM $table ORDER BY 1" |
    sha256sum | sed "s|-\$|tower/ws/database.db:$table|"
done >"$dir/tower/tables.txt"

# 3. Synthetic points with 8 control points: strip's datum on them.
"$BAYON" synth --scene points --output_path "$dir/points/ws" \
  --num_points 900 --num_control_points 8 --num_check_points 4 --seed 3 \
  >"$dir/points.log" 2>&1 &&
  "$BAYON" strip --database_path "$dir/points/ws/database.db" \
    --control_path "$dir/points/ws/control" \
    --output_path "$dir/points/ws/sparse/strip" --num_threads 1 \
    >>"$dir/points.log" 2>&1 || {
  echo "checksums.sh: the points' strip failed; see $dir/points.log" >&2
  exit 1
}

(
  cd "$dir"
  for ws in temple/ws points/ws; do
    find "$ws/sparse" "$ws/dense" "$ws/mesh" -maxdepth 2 -type f \
      \( -name '*.bin' -o -name '*.ply' -o -name '*.vis' \) 2>/dev/null ||
      true
  done | sort | xargs sha256sum
  cat tower/tables.txt
) | tee "$out"
