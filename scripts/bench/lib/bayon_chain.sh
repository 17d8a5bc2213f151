# bayon's chain from an imported database to the tie points, each stage timed
# (lib/timing.sh) into WS/<stage>.{log,time}. Sourced by scripts/bench/*.sh;
# not a benchmark itself. Needs $BAYON and $threads.

# bayon_tie_points WS DB IMAGES MATCH_ARGS...: features, match (with
# MATCH_ARGS), relative, disparity, tiepoints.
bayon_tie_points() {
  local ws="$1" db="$2" images="$3"
  shift 3
  timed "$ws/features" "$BAYON" features --database_path "$db" \
    --image_path "$images" --num_threads "$threads"
  timed "$ws/match" "$BAYON" match --database_path "$db" --image_path "$images" \
    --num_threads "$threads" "$@"
  timed "$ws/relative" "$BAYON" relative --database_path "$db" \
    --num_threads "$threads"
  timed "$ws/disparity" "$BAYON" disparity --database_path "$db" \
    --num_threads "$threads"
  timed "$ws/tiepoints" "$BAYON" tiepoints --database_path "$db" \
    --image_path "$images" --num_threads "$threads"
}
