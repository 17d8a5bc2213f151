#!/usr/bin/env bash
# `bayon texture`: view-dependent blending against the optimal image alone,
# for each radiometric pre-processing, with runtime and peak memory.
#   tower     the rendered tower (`bayon synth --scene tower`, 960 x 640, 16
#             views in sun, haze and overcast, 4 held-out viewpoints), its
#             true orientation and calibration; textured twice: the true
#             geometry (texture mapping alone) and the mesh bayon makes
#             (`dense` with its defaults, `mesh --method cylinder`); judged by
#             `bayon evaluate` from the held-out viewpoints against the true
#             texture (PSNR and SSIM after a per-channel gain and offset: the
#             photographs' light is not the albedo) and by the seam measure
#   fountain  ../shared/data/fountain-P11 and temple-ring with bayon's
#   temple    orientation, their dense clouds meshed by Poisson, where
#             `scripts/bench.sh dense` has made the clouds: time and peak
#             memory; renders (all modes and anaglyphs) from the stations;
#             and on fountain-P11, leave one out: textured without one of
#             three photographs and rendered from its station, PSNR and
#             SSIM against it over the facade (no gain or offset fitted),
#             for the default (balance, view-dependent blend, seam
#             levelling), the paper's (high pass and equalisation, no
#             levelling) and the optimal image alone as photographed
# Threads: $BAYON_THREADS (default 2, the CI machine's cores).
set -euo pipefail
dir="$(cd "$(dirname "$0")/../.." && pwd)/build/bench/texture"
threads="${BAYON_THREADS:-2}"
mkdir -p "$dir"
source "$(dirname "$0")/lib/timing.sh"

tower="$dir/tower"
if [ ! -f "$tower/ws/gt/synth.json" ]; then
  rm -rf "$tower"
  mkdir -p "$tower"
  timed "$tower/synth" "$BAYON" synth --scene tower --output_path "$tower/ws" \
    --num_views 16 --image_width 960 --mesh_spacing_m 0.05 \
    --texel_size_m 0.01 --supersampling 1 --seed 3 --num_threads "$threads"
fi
rm -rf "$tower/model" "$tower/dense" "$tower/mesh" "$tower/runs"
cp -r "$tower/ws/gt/sparse" "$tower/model"
cp "$tower/ws/gt/calibration.json" "$tower/model/"
timed "$tower/dense" "$BAYON" dense --image_path "$tower/ws/images" \
  --input_path "$tower/model" --output_path "$tower/dense/points.ply" \
  --num_threads "$threads"
timed "$tower/mesh" "$BAYON" mesh --input_path "$tower/dense/points.ply" \
  --output_path "$tower/mesh/mesh.ply" --method cylinder --cylinder.axis_point 0,0,0

# json_number FILE KEY: the first number stored under KEY.
json_number() {
  grep -o "\"$2\": [-0-9.e+]*" "$1" | head -1 | grep -o '[-0-9.e+]*$'
}

printf '%-14s %-18s %-15s %7s %8s %9s %7s %8s %8s\n' mesh preprocess blend \
  charts seam "PSNR* dB" SSIM* "time s" "peak MB"
for mesh in true reconstructed; do
  mesh_path="$tower/ws/gt/surface.ply"
  [ "$mesh" = reconstructed ] && mesh_path="$tower/mesh/mesh.ply"
  for preprocess in balance highpass_equalize wallis none; do
    for blend in none view_dependent; do
      out="$tower/runs/${mesh}_${preprocess}_$blend"
      mkdir -p "$(dirname "$out")"
      timed "$out" "$BAYON" texture --image_path "$tower/ws/images" \
        --input_path "$tower/model" --mesh_path "$mesh_path" \
        --output_path "$out" --preprocess "$preprocess" --blend "$blend" \
        --num_threads "$threads" || continue
      "$BAYON" evaluate --ground_truth_path "$tower/ws/gt" \
        --textured_mesh_path "$out/model.ply" --output_path "$out/evaluation.json" \
        --num_threads "$threads" >"$out.evaluate.log" 2>&1 || continue
      printf '%-14s %-18s %-15s %7s %8.2f %9.2f %7.4f %8.1f %8s\n' "$mesh" \
        "$preprocess" "$blend" "$(json_number "$out/texture.json" num_charts)" \
        "$(json_number "$out/texture.json" seam_difference)" \
        "$(json_number "$out/evaluation.json" mean_normalized_psnr_db)" \
        "$(json_number "$out/evaluation.json" mean_normalized_ssim)" \
        "$(wall_s "$out")" "$(peak_mb "$out")"
    done
  done
done

# The real rings, where `scripts/bench.sh dense` has made their clouds.
echo
printf '%-14s %8s %8s %8s %12s %8s %8s\n' set step faces charts atlas "time s" \
  "peak MB"
for set in fountain-P11:fountain:/images temple-ring:temple:; do
  IFS=: read -r data name images <<<"$set"
  cloud="$(dirname "$dir")/dense/$name/dense/points.ply"
  model="$(dirname "$dir")/chain/$name/adjusted"
  [ -f "$cloud" ] && [ -d "$model" ] || continue
  out="$dir/$name"
  rm -rf "$out"
  mkdir -p "$out"
  timed "$out/mesh" "$BAYON" mesh --input_path "$cloud" --method poisson \
    --output_path "$out/mesh.ply" || continue
  timed "$out/texture" "$BAYON" texture \
    --image_path "$BAYON_DATA_DIR/$data$images" --input_path "$model" \
    --mesh_path "$out/mesh.ply" --output_path "$out/model" \
    --num_threads "$threads" || continue
  timed "$out/render" "$BAYON" render --model_path "$out/model/model.obj" \
    --output_path "$out/renders" --viewpoints stations --input_path "$model" \
    --max_image_size 800 --stereo anaglyph --num_threads "$threads" || continue
  t="$out/model/texture.json"
  printf '%-14s %8s %8s %8s %12s %8.1f %8s\n' "$name" texture \
    "$(json_number "$t" num_faces)" "$(json_number "$t" num_charts)" \
    "$(json_number "$t" atlas_width)x$(json_number "$t" atlas_height)" \
    "$(wall_s "$out/texture")" "$(peak_mb "$out/texture")"
  printf '%-14s %8s %8s %8s %12s %8.1f %8s\n' "$name" render - - - \
    "$(wall_s "$out/render")" "$(peak_mb "$out/render")"
done

# Leave one out on fountain-P11 (the mesh and model of the table above).
mesh="$dir/fountain/mesh.ply"
model="$(dirname "$dir")/chain/fountain/adjusted"
[ -f "$mesh" ] || exit 0
images="$BAYON_DATA_DIR/fountain-P11/images"
echo
printf '%-10s %-12s %8s %8s %8s %9s %8s\n' photograph method "PSNR dB" SSIM \
  seam "PSNR* dB" SSIM*
for k in 0002.jpg 0005.jpg 0008.jpg; do
  for method in "default:" \
    "paper:--preprocess highpass_equalize --seam_leveling 0" \
    "optimal:--preprocess none --blend none --seam_leveling 0"; do
    name="${method%%:*}"
    out="$dir/fountain/leave_one_out/${k%.jpg}_$name"
    mkdir -p "$out"
    # shellcheck disable=SC2086  # the method's options, split on purpose
    "$BAYON" texture --image_path "$images" --input_path "$model" \
      --mesh_path "$mesh" --output_path "$out" --formats ply \
      --exclude_images "$k" --overwrite 1 --num_threads "$threads" \
      ${method#*:} >"$out.log" 2>&1 || continue
    "$BAYON" evaluate --image_path "$images" --image_names "$k" \
      --textured_mesh_path "$out/model.ply" --input_path "$model" \
      --output_path "$out/evaluation.json" --render_path "$out/renders" \
      --num_threads "$threads" >"$out.evaluate.log" 2>&1 || continue
    printf '%-10s %-12s %8.2f %8.4f %8.2f %9.2f %8.4f\n' "$k" "$name" \
      "$(json_number "$out/evaluation.json" mean_psnr_db)" \
      "$(json_number "$out/evaluation.json" mean_ssim)" \
      "$(json_number "$out/texture.json" seam_difference)" \
      "$(json_number "$out/evaluation.json" mean_normalized_psnr_db)" \
      "$(json_number "$out/evaluation.json" mean_normalized_ssim)"
  done
done
