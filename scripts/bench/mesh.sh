#!/usr/bin/env bash
# Benchmark of the editing and meshing stages on a synthetic tower cloud of
# one million points (2 % blunders, per-point sigmas, true normals): `bayon
# edit` (local surface fitting and PCL's statistical outlier removal), then
# every `bayon mesh` method on the edited cloud, and normal estimation (PCL +
# MST orientation) on the same cloud without normals. Prints wall time and
# peak memory (/usr/bin/time -v) per step. Then, where `scripts/bench.sh
# dense` has made it, the same for fountain-P11's dense cloud (bayon's own
# orientation and MPGC): edited, and meshed by the 3D methods and stock
# `colmap poisson_mesher`; and the rendered tower's, the same, each mesh
# against the true surface.
#   scripts/bench.sh mesh [num_points]     (default 1000000)
set -euo pipefail
num_points="${1:-1000000}"
dir="$BAYON_BUILD/bench/mesh"
rm -rf "$dir"
mkdir -p "$dir/dense" "$dir/mesh"

"$BAYON" synth_cloud --shape box_tower --num_points "$num_points" \
  --with_normals 1 --output_path "$dir/dense/points.ply" \
  --truth_path "$dir/surface.ply" >/dev/null
"$BAYON" synth_cloud --shape box_tower --num_points "$num_points" \
  --blunder_fraction 0 --output_path "$dir/dense/plain.ply" >/dev/null

printf '%-36s %10s %10s %10s %12s\n' step points faces "time s" "peak MB"
# run LABEL REPORT_JSON COMMAND...: times the command, prints a row.
run() {
  local label="$1" report="$2"
  shift 2
  if ! /usr/bin/time -v -o "$dir/time.txt" "$@" >"$dir/$label.log" 2>&1; then
    printf '%-36s failed, see %s\n' "$label" "$dir/$label.log"
    return
  fi
  local wall rss faces points
  wall=$(sed -n 's/.*Elapsed (wall clock) time (h:mm:ss or m:ss): //p' "$dir/time.txt" |
    awk -F: '{ s = 0; for (i = 1; i <= NF; ++i) s = s * 60 + $i; print s }')
  rss=$(sed -n 's/.*Maximum resident set size (kbytes): //p' "$dir/time.txt")
  faces=$(grep -o '"num_faces": [0-9]*' "$report" 2>/dev/null | grep -o '[0-9]*$' || echo -)
  points=$(grep -o '"num_input[a-z_]*": [0-9]*' "$report" 2>/dev/null | grep -o '[0-9]*$' || echo -)
  printf '%-36s %10s %10s %10.1f %12.0f\n' "$label" "$points" "$faces" "$wall" "$((rss / 1024))"
}

run "edit surface_fit" "$dir/edit.json" \
  "$BAYON" edit --input_path "$dir/dense/points.ply" \
  --output_path "$dir/dense/points_edited.ply" --report_path "$dir/edit.json"
run "edit statistical (PCL)" "$dir/edit_statistical.json" \
  "$BAYON" edit --input_path "$dir/dense/points.ply" --method statistical \
  --output_path "$dir/dense/points_statistical.ply" \
  --report_path "$dir/edit_statistical.json"
for method in cylinder greedy_projection poisson advancing_front colmap_poisson; do
  run "mesh $method" "$dir/mesh/$method.json" \
    "$BAYON" mesh --input_path "$dir/dense/points_edited.ply" --method "$method" \
    --output_path "$dir/mesh/$method.ply" --report_path "$dir/mesh/$method.json"
done
run "mesh greedy_projection + normals" "$dir/mesh/estimated.json" \
  "$BAYON" mesh --input_path "$dir/dense/plain.ply" --method greedy_projection \
  --output_path "$dir/mesh/estimated.ply" --report_path "$dir/mesh/estimated.json"

fountain="$BAYON_BUILD/bench/dense/fountain/dense/points.ply"
if [ -f "$fountain" ]; then
  run "fountain edit surface_fit" "$dir/fountain_edit.json" \
    "$BAYON" edit --input_path "$fountain" \
    --output_path "$dir/dense/fountain_edited.ply" \
    --report_path "$dir/fountain_edit.json"
  for method in greedy_projection poisson advancing_front colmap_poisson; do
    run "fountain mesh $method" "$dir/mesh/fountain_$method.json" \
      "$BAYON" mesh --input_path "$dir/dense/fountain_edited.ply" \
      --method "$method" --output_path "$dir/mesh/fountain_$method.ply" \
      --report_path "$dir/mesh/fountain_$method.json"
  done
else
  echo "(fountain-P11's dense cloud: run scripts/bench.sh dense first)"
fi
# The rendered tower's dense cloud (scripts/bench.sh dense), edited, meshed
# by the 3D methods and the cylinder, each against the true surface:
# accuracy (mesh to truth) and completeness (truth within 5 GSD of the mesh).
tower="$BAYON_BUILD/bench/dense/tower"
if [ -f "$tower/dense/points.ply" ]; then
  "$BAYON" edit --input_path "$tower/dense/points.ply" \
    --output_path "$dir/dense/tower_edited.ply" >/dev/null 2>&1
  printf '\n%-34s %8s %8s %8s %9s %7s %7s %6s\n' "tower (truth)" "acc med" "acc RMS" \
    "acc p95" complete walls tops loops
  printf '%-34s %8s %8s %8s %9s %7s %7s %6s\n' "" GSD GSD GSD "5 GSD" "" "" ""
  tower_row() {
    local label="$1"
    shift
    "$BAYON" mesh --input_path "$dir/dense/tower_edited.ply" \
      --output_path "$dir/mesh/tower.ply" --overwrite 1 "$@" \
      >"$dir/tower_mesh.log" 2>&1 || { printf '%-34s failed\n' "$label"; return; }
    "$BAYON" evaluate --ground_truth_path "$tower/ws/gt" \
      --mesh_path "$dir/mesh/tower.ply" --completeness_threshold_gsd 5 \
      --output_path "$dir/tower_eval.json" >/dev/null 2>&1
    python3 - "$label" "$dir/tower_eval.json" <<'PY'
import json, sys
m = json.load(open(sys.argv[2]))["mesh"]
a = m["accuracy_gsd"]
o = m["completeness_by_orientation"]
print("%-34s %8.2f %8.2f %8.2f %8.1f%% %6.1f%% %6.1f%% %6d" % (
    sys.argv[1], a["median"], a["rms"], a["p95"],
    100 * m["completeness_fraction"], 100 * o["walls"]["completeness_fraction"],
    100 * o["tops"]["completeness_fraction"], m["topology"]["boundary_loops"]))
PY
  }
  tower_row "poisson 10, holes <= 50 (ring.ini)" --method poisson --poisson.depth 10 \
    --cleanup.max_hole_edges 50
  tower_row "delaunay_graph_cut" --method delaunay_graph_cut \
    --sparse_path "$tower/model"
  tower_row "delaunay_graph_cut, no edge limit" --method delaunay_graph_cut \
    --sparse_path "$tower/model" --delaunay_graph_cut.max_edge_factor 0
  tower_row "cylinder" --method cylinder
  tower_row "poisson depth 10" --method poisson --poisson.depth 10
else
  echo "(the rendered tower's dense cloud: run scripts/bench.sh dense first)"
fi
echo "outputs and logs in $dir"
