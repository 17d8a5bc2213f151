#!/usr/bin/env bash
# Rendering the synthetic tower: `bayon synth --scene tower` at full size
# (16 views, 1800 x 1200, 3 x 3 supersampling), wall time, rendering time and
# peak memory. Run as: scripts/bench.sh synth [extra synth options]
set -euo pipefail
out="${BAYON_BUILD}/bench/synth_tower"
log="${BAYON_BUILD}/bench/synth_tower.time"
/usr/bin/time -v "$BAYON" synth --scene tower --output_path "$out" \
  --overwrite 1 --num_views 16 --image_width 1800 "$@" \
  >"${BAYON_BUILD}/bench/synth_tower.log" 2>"$log"
summary=$(grep '^synth:' "${BAYON_BUILD}/bench/synth_tower.log")
render=$(sed -n 's/.*images rendered in \([0-9.]*\) s (\([0-9.]*\) s in all).*/\1 \2/p' <<<"$summary")
wall=$(grep 'Elapsed (wall clock)' "$log" | awk '{print $NF}')
rss=$(grep 'Maximum resident set size' "$log" | awk '{print $NF}')
cpu_user=$(grep 'User time' "$log" | awk '{print $NF}')
printf "%-34s %8s %10s %10s %10s %12s\n" benchmark views "render s" "total s" "cpu s" "peak MiB"
printf "%-34s %8d %10.1f %10.1f %10.1f %12.0f\n" "synth tower 1800x1200 ss3" 16 \
  $(awk '{print $1}' <<<"$render") $(awk '{print $2}' <<<"$render") \
  "$cpu_user" "$(awk -v k="$rss" 'BEGIN{print k/1024}')"
echo "wall clock (time -v): $wall; workspace: $out"
