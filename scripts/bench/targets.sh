#!/usr/bin/env bash
# Issue 32's figures for coded targets on the rendered tower (1800 x 1200,
# seed 2, 50 targets of 0.2 m: about 28 px): `bayon synth --coded_targets`,
# then `bayon targets`, judged against the truth in gt/: the targets the
# truth counts visible (unoccluded, within 75 deg of their normal, sides of
# 16 px or more) that were found, wrong codes (a measurement more than
# 3 px from the true projection of the target its code names: every
# measurement is checked, also those beyond the visibility rule), and the
# centres' RMS against the exact projections, beside the stated sigmas.
#   scripts/bench.sh targets
set -euo pipefail
dir="$BAYON_BUILD/bench/targets"
threads="${BAYON_THREADS:-2}"
rm -rf "$dir"
mkdir -p "$dir"
ws="$dir/ws"
source "$(dirname "$0")/lib/timing.sh"
timed "$dir/synth" "$BAYON" synth --scene tower --output_path "$ws" --seed 2 \
  --num_heldout_views 0 --coded_targets 50 --num_threads "$threads"
timed "$dir/targets" "$BAYON" targets --database_path "$ws/database.db" \
  --image_path "$ws/images" --output_path "$dir/targets.txt" \
  --report_path "$dir/targets.json" --num_threads "$threads"
python3 "$(dirname "$0")/lib/judge_targets.py" "$ws" "$dir/targets.txt" \
  "$(wall_s "$dir/targets")" "$(peak_mb "$dir/targets")"
