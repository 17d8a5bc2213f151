#!/usr/bin/env bash
# Issue 4's figures on the rendered tower that no test holds, because they
# are not reached (the tests assert what is):
#  1. every oriented adjacent pair within 0.02 deg of the true rotation and
#     0.2 deg of the true base direction, with at least 13 of the 16 pairs
#     oriented (three converge by more than 45 degrees by design);
#  2. stock `colmap mapper` registering all 16 images from a database that
#     bayon alone filled (features, match, relative), the camera fixed at
#     the truth's.
# The tower as relative_pipeline_test makes it: `bayon synth --scene tower`
# at 1200 x 800 (seed 1, supersampling 2), Moravec points on 8-pixel
# patches, ring matches, relative orientation with the true interior
# orientation; the pairs with correlation peaks and with least-squares
# conjugate points (match --lsm_refinement 1), judged by `bayon evaluate
# --database_path --adjacent_pairs 1`.
#   scripts/bench.sh tower_pairs
set -euo pipefail
dir="$BAYON_BUILD/bench/tower_pairs"
threads="${BAYON_THREADS:-2}"
rm -rf "$dir"
mkdir -p "$dir"
ws="$dir/ws"
"$BAYON" synth --scene tower --output_path "$ws" --image_width 1200 \
  --supersampling 2 --num_heldout_views 0 --num_threads "$threads" \
  >"$dir/synth.log" 2>&1
"$BAYON" features --database_path "$ws/database.db" --image_path "$ws/images" \
  --patch_size 8 --max_num_features 0 --num_threads "$threads" \
  >"$dir/features.log" 2>&1
cp "$ws/database.db" "$ws/lsm.db"
for name in database lsm; do
  lsm=0
  [ "$name" = lsm ] && lsm=1
  "$BAYON" match --database_path "$ws/$name.db" --image_path "$ws/images" \
    --pairing ring --lsm_refinement "$lsm" --num_threads "$threads" \
    >"$dir/match_$name.log" 2>&1
  "$BAYON" relative --database_path "$ws/$name.db" --num_threads "$threads" \
    >"$dir/relative_$name.log" 2>&1
  "$BAYON" evaluate --ground_truth_path "$ws/gt" --database_path "$ws/$name.db" \
    --adjacent_pairs 1 --label "tower $name.db" \
    --output_path "$dir/pairs_$name.json" >"$dir/pairs_$name.txt"
done

echo "1. adjacent tower pairs against the truth (bounds: 0.02 deg rotation, 0.2 deg base)"
printf '%-30s %8s %8s %12s %12s %12s\n' points oriented within "median rot" "max rot" "max base"
printf '%-30s %8s %8s %12s %12s %12s\n' "" "of 16" "bounds" deg deg deg
for name in database lsm; do
  python3 - "$dir/pairs_$name.json" "$name" <<'PY'
import json, sys
e = json.load(open(sys.argv[1]))["relative"]
within = sum(1 for p in e["pairs"] if p["oriented"]
             and p["rotation_error_deg"] < 0.02 and p["base_error_deg"] < 0.2)
label = {"database": "correlation peaks", "lsm": "least-squares conjugate points"}
print("%-30s %8d %8d %12.4f %12.4f %12.3f" % (
    label[sys.argv[2]], e["num_oriented"], within,
    e["median_rotation_error_deg"], e["max_rotation_error_deg"],
    e["max_base_error_deg"]))
PY
done
echo "per pair: $dir/pairs_database.txt, $dir/pairs_lsm.txt"

# 2. Stock COLMAP's mapper on a copy of bayon's database (COLMAP rewrites the
# pragmas of a database it opens), the calibrated camera held fixed.
for name in database lsm; do
  out="$dir/mapper_$name"
  mkdir -p "$out/sparse"
  cp "$ws/$name.db" "$out/colmap.db"
  colmap mapper --database_path "$out/colmap.db" --image_path "$ws/images" \
    --output_path "$out/sparse" --Mapper.num_threads "$threads" \
    --Mapper.ba_refine_focal_length 0 --Mapper.ba_refine_principal_point 0 \
    --Mapper.ba_refine_extra_params 0 >"$out/mapper.log" 2>&1 || true
done
echo
echo "2. stock colmap mapper on bayon's tower database (figure: 16 of 16 registered)"
for name in database lsm; do
  out="$dir/mapper_$name"
  best=0 best_model=""
  for model in "$out"/sparse/*/; do
    [ -f "$model/images.bin" ] || continue
    n=$(colmap model_analyzer --path "$model" 2>&1 | sed -n 's/.*Registered images: //p')
    if [ "${n:-0}" -gt "$best" ]; then best=$n best_model=$model; fi
  done
  printf '%-30s registered %2d of 16' "$name.db" "$best"
  if [ -n "$best_model" ]; then
    "$BAYON" evaluate --input_path "$best_model" --ground_truth_path "$ws/gt/sparse" \
      --label "mapper on $name.db" --output_path "$out/evaluation.json" >"$out/evaluate.txt" 2>&1
    python3 -c 'import json,sys; e=json.load(open(sys.argv[1]))["sparse"]; print(", rotation RMS %.3f deg" % e["rotation_rms_deg"])' "$out/evaluation.json"
  else
    echo " (mapper: $(grep -m1 -E 'No good initial|ERROR|failed' "$out/mapper.log" || echo 'no model'))"
  fi
done
echo "outputs and logs in $dir"
