#!/usr/bin/env bash
# The main job on a fresh machine, end to end: set up (apt, build), then one
# command, `bayon pipeline`, from a ring of photographs to the measured,
# texture-mapped model (orientation, bundle adjustment, MPGC dense points,
# editing, mesh, texture, renders, web viewer), stock COLMAP on the same
# photographs beside it (`compare_colmap`), the orientation judged against
# the calibrated truth (`evaluate`), and the report.
#   scripts/demo.sh [temple|fountain] [WORKSPACE]
#     temple   ../shared/data/temple-ring: 16 photographs on a ring around a
#              plaster temple (the default; configs/ring.ini)
#     fountain ../shared/data/fountain-P11: 11 photographs of a fountain
#              facade, 3072 x 2048 (configs/facade.ini; about 13 minutes)
# The photographs' calibrated camera is given to bayon (as a photogrammetrist
# brings a calibrated camera); compare_colmap gives COLMAP the same camera.
# BAYON_THREADS (default 2) threads; BAYON_DATA_DIR the data folder.
set -euo pipefail
cd "$(dirname "$0")/.."
set_name=${1:-temple}
ws=${2:-demo-$set_name}
threads=${BAYON_THREADS:-2}
data=${BAYON_DATA_DIR:-../shared/data}
case "$set_name" in
  temple)
    images="$data/temple-ring"
    truth=(--format middlebury --input_path "$data/temple-ring/templeSR_par.txt")
    config=configs/ring.ini ;;
  fountain)
    images="$data/fountain-P11/images"
    truth=(--format strecha --input_path "$data/fountain-P11/gt_dense_cameras"
      --image_path "$images")
    config=configs/facade.ini ;;
  *) echo "demo.sh: unknown set '$set_name' (temple or fountain)" >&2; exit 2 ;;
esac
[ -d "$images" ] || {
  echo "demo.sh: $images not found (set BAYON_DATA_DIR to the data folder)" >&2
  exit 2
}
# Only the program the demo runs (with its viewer page): the tests are
# scripts/test.sh's to build.
scripts/setup.sh --target bayon
bayon=build/tools/bayon
# Only a previous demo's workspace is replaced, never another folder.
if [ -e "$ws" ]; then
  if [ -f "$ws/demo.ini" ]; then
    rm -rf "$ws"
  else
    echo "demo.sh: $ws exists and is not a demo workspace; give another path" >&2
    exit 2
  fi
fi
mkdir -p "$ws"
start=$(date +%s)

echo "== 1. the calibrated cameras as a COLMAP model ($ws/gt), the camera for bayon"
$bayon import_ground_truth "${truth[@]}" --output_path "$ws/gt" >/dev/null
params=$(grep -v '^#' "$ws/gt/cameras.txt" | head -1 | cut -d' ' -f5- | tr ' ' ',')
model=$(grep -v '^#' "$ws/gt/cameras.txt" | head -1 | cut -d' ' -f2)
cat >"$ws/demo.ini" <<INI
# The demo's additions to $config: the calibrated camera, a free network.
[import]
camera_model = $model
camera_params = $params
[adjust]
datum = free
self_calibration = none
INI

echo "== 2. bayon pipeline: photographs to textured model, stock COLMAP beside it"
$bayon pipeline --workspace_path "$ws" --image_path "$images" \
  --config "$config" --config "$ws/demo.ini" --compare_colmap 1 \
  --num_threads "$threads" 2>"$ws/pipeline.stderr"

echo
echo "== 3. bayon beside stock COLMAP, both against the truth"
cat "$ws/colmap/comparison.txt"
if [ "$set_name" = temple ]; then
  echo
  echo "== 4. the model carried back into the photographs: its silhouette against the temple's (IoU)"
  $bayon evaluate --silhouette_image_path "$images" --mesh_path "$ws/mesh/mesh.ply" \
    --input_path "$ws/sparse/adjusted" --silhouette_mask_path "$ws/silhouettes" \
    --output_path "$ws/silhouettes.json" | tail -1
fi
echo
echo "demo finished in $(( $(date +%s) - start )) s (after the build)"
echo "  report:  $ws/report.html"
echo "  model:   $ws/model/model.obj, .ply, .wrl, .glb (atlas model.png)"
echo "  viewer:  $ws/viewer/index.html (opens offline in a browser)"
echo "  renders: $ws/renders/ (textured_*.png, shaded_*.png: the model upright, all round)"
[ "$set_name" = temple ] && echo "  silhouettes: $ws/silhouettes/ (white both, red model only, blue photograph only)"
true
