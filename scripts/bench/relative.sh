#!/usr/bin/env bash
# Benchmark of bayon's automated relative orientation against stock COLMAP's
# features and matching on ../shared/data/sceaux-castle (11 JPEG photos,
# 2832 x 2128), in the same run, on the CPU:
#   bayon:  import (one camera, EXIF focal length), features (Moravec),
#           match --pairing exhaustive (correlation + relaxation),
#           relative (DRT + LMedS + coplanarity adjustment); and match +
#           relative again on a copy of the features with the conjugate
#           points refined and propagated by least-squares matching
#           (--lsm_refinement 1)
#   COLMAP: feature_extractor (SIFT, one camera) and exhaustive_matcher
#           (matching and geometric verification)
# Wall time and peak memory per stage (/usr/bin/time -v), the totals and
# their ratio, and what each produced: keypoints, matched pairs, matches,
# verified pairs (two-view geometries) and their inlier matches.
#   scripts/bench.sh relative
#   BAYON=build-rel/tools/bayon bash scripts/bench/relative.sh   (no rebuild)
set -euo pipefail
root="$(cd "$(dirname "$0")/../.." && pwd)"
BAYON="${BAYON:-$root/build/tools/bayon}"
BAYON_BUILD="${BAYON_BUILD:-$(dirname "$(dirname "$BAYON")")}"
data="${BAYON_DATA_DIR:-$root/../shared/data}"
images="$data/sceaux-castle/images"
dir="$BAYON_BUILD/bench/relative"
[ -x /usr/bin/time ] || { echo "relative.sh: /usr/bin/time missing (apt-get install time)" >&2; exit 2; }
[ -d "$images" ] || { echo "relative.sh: $images not found" >&2; exit 2; }
rm -rf "$dir"
mkdir -p "$dir/bayon" "$dir/colmap"

source "$(dirname "$0")/lib/timing.sh"
# What a database holds: keypoints, matched pairs, matches, verified pairs,
# inlier matches.
counts() {
  python3 - "$1" <<'EOF'
import sqlite3, sys
db = sqlite3.connect(sys.argv[1])
q = lambda sql: db.execute(sql).fetchone()[0] or 0
print(q("SELECT sum(rows) FROM keypoints"),
      q("SELECT count(*) FROM matches WHERE rows > 0"),
      q("SELECT sum(rows) FROM matches"),
      q("SELECT count(*) FROM two_view_geometries WHERE rows > 0"),
      q("SELECT sum(rows) FROM two_view_geometries"))
EOF
}

# --- bayon
bdb="$dir/bayon/database.db"
"$BAYON" import --image_path "$images" --database_path "$bdb" --single_camera 1 \
  --log_path "$dir/bayon/import.log" >/dev/null
timed "$dir/bayon_features" "$BAYON" features --database_path "$bdb" --image_path "$images"
ldb="$dir/bayon/lsm.db"
cp "$bdb" "$ldb"
timed "$dir/bayon_match" "$BAYON" match --database_path "$bdb" --image_path "$images" \
  --pairing exhaustive
timed "$dir/bayon_relative" "$BAYON" relative --database_path "$bdb"
timed "$dir/bayon_lsm_match" "$BAYON" match --database_path "$ldb" --image_path "$images" \
  --pairing exhaustive --lsm_refinement 1 --log_path "$dir/bayon/lsm_match.log"
timed "$dir/bayon_lsm_relative" "$BAYON" relative --database_path "$ldb" \
  --log_path "$dir/bayon/lsm_relative.log"

# --- COLMAP
cdb="$dir/colmap/database.db"
timed "$dir/colmap_features" colmap feature_extractor --database_path "$cdb" \
  --image_path "$images" --ImageReader.single_camera 1 --SiftExtraction.use_gpu 0
timed "$dir/colmap_match" colmap exhaustive_matcher --database_path "$cdb" \
  --SiftMatching.use_gpu 0

read -r b_kp b_pairs b_matches b_verified b_inliers < <(counts "$bdb")
read -r l_kp l_pairs l_matches l_verified l_inliers < <(counts "$ldb")
read -r c_kp c_pairs c_matches c_verified c_inliers < <(counts "$cdb")
row() {
  printf '%-34s %8.1f %8s\n' "$1" "$(wall_s "$dir/$2")" "$(peak_mb "$dir/$2")"
}
read -r b_total b_peak < <(totals "$dir"/{bayon_features,bayon_match,bayon_relative})
read -r l_total l_peak < <(totals "$dir"/{bayon_features,bayon_lsm_match,bayon_lsm_relative})
read -r c_total c_peak < <(totals "$dir"/{colmap_features,colmap_match})

echo "sceaux-castle: 11 images 2832 x 2128, all pairs, CPU ($(nproc) cores)"
printf '%-34s %8s %8s\n' "stage" "time s" "peak MB"
row "bayon features (Moravec)" bayon_features
row "bayon match (exhaustive)" bayon_match
row "bayon relative (DRT, LMedS)" bayon_relative
printf '%-34s %8.1f %8s\n' "bayon total" "$b_total" "$b_peak"
row "bayon match --lsm_refinement 1" bayon_lsm_match
row "bayon relative (LSM points)" bayon_lsm_relative
printf '%-34s %8.1f %8s\n' "bayon total with LSM" "$l_total" "$l_peak"
row "colmap feature_extractor (SIFT)" colmap_features
row "colmap exhaustive_matcher" colmap_match
printf '%-34s %8.1f %8s\n' "colmap total" "$c_total" "$c_peak"
awk -v a="$b_total" -v l="$l_total" -v b="$c_total" 'BEGIN {
  printf "time ratio bayon / colmap: %.2f (%s); with LSM %.2f (%s)\n", a / b,
         a < b ? "bayon faster" : "colmap faster", l / b,
         l < b ? "bayon faster" : "colmap faster" }'
printf '%-8s %10s %13s %10s %15s %14s\n' "" "keypoints" "matched pairs" "matches" \
  "verified pairs" "inlier matches"
printf '%-8s %10s %13s %10s %15s %14s\n' bayon "$b_kp" "$b_pairs" "$b_matches" \
  "$b_verified" "$b_inliers"
printf '%-8s %10s %13s %10s %15s %14s\n' "bayon+L" "$l_kp" "$l_pairs" "$l_matches" \
  "$l_verified" "$l_inliers"
printf '%-8s %10s %13s %10s %15s %14s\n' colmap "$c_kp" "$c_pairs" "$c_matches" \
  "$c_verified" "$c_inliers"
echo "outputs and logs in $dir"
