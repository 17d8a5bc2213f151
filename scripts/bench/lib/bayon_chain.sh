# bayon's chain from an imported database to the tie points, each stage timed
# (lib/timing.sh) into WS/<stage>.{log,time}. Sourced by scripts/bench/*.sh;
# not a benchmark itself. Needs $BAYON and $threads.

# bayon_tie_points WS DB IMAGES MATCH_ARGS...: features (with
# --detector $BAYON_DETECTOR, default moravec), match (with MATCH_ARGS),
# relative, disparity, tiepoints.
bayon_tie_points() {
  local ws="$1" db="$2" images="$3"
  shift 3
  timed "$ws/features" "$BAYON" features --database_path "$db" \
    --image_path "$images" --num_threads "$threads" \
    --detector "${BAYON_DETECTOR:-moravec}"
  timed "$ws/match" "$BAYON" match --database_path "$db" --image_path "$images" \
    --num_threads "$threads" "$@"
  timed "$ws/relative" "$BAYON" relative --database_path "$db" \
    --num_threads "$threads"
  timed "$ws/disparity" "$BAYON" disparity --database_path "$db" \
    --num_threads "$threads"
  timed "$ws/tiepoints" "$BAYON" tiepoints --database_path "$db" \
    --image_path "$images" --num_threads "$threads"
}

# fresh_truth SET_DIR IMAGES FORMAT TRUTH_INPUT: SET_DIR emptied, the
# truth imported into SET_DIR/truth as a COLMAP model.
fresh_truth() {
  local set_dir="$1" images="$2" format="$3" truth_input="$4"
  rm -rf "$set_dir"
  mkdir -p "$set_dir"
  local image_path_flag=()
  [ "$format" = strecha ] && image_path_flag=(--image_path "$images")
  "$BAYON" import_ground_truth --format "$format" --input_path "$truth_input" \
    --output_path "$set_dir/truth" "${image_path_flag[@]}" \
    >"$set_dir/truth.log" 2>&1
}

# The truth's camera: "fx fy cx cy width height".
truth_camera() {
  grep -v '^#' "$1/cameras.txt" | head -1 | awk '{ print $5, $6, $7, $8, $3, $4 }'
}

# bayon_run WS IMAGES MODE TRUTH MATCH_ARGS...
bayon_run() {
  local ws="$1" images="$2" mode="$3" truth="$4"
  shift 4
  local db="$ws/database.db"
  local fx fy cx cy width height
  read -r fx fy cx cy width height < <(truth_camera "$truth")
  local import_args=() self_calibration=significant
  case "$mode" in
    calibrated)
      import_args=(--camera_model PINHOLE --camera_params "$fx,$fy,$cx,$cy")
      self_calibration=none ;;
    nothing) ;;
    focal5)
      # A 10 um pixel: the lens in mm that gives 1.05 x the true focal length.
      import_args=(--pixel_size_um 10 --focal_length_mm
        "$(python3 -c "print(1.05 * ($fx + $fy) / 2 * 0.01)")") ;;
  esac
  timed "$ws/import" "$BAYON" import --image_path "$images" --database_path "$db" \
    --single_camera 1 "${import_args[@]}"
  bayon_tie_points "$ws" "$db" "$images" "$@"
  timed "$ws/strip" "$BAYON" strip --database_path "$db" \
    --output_path "$ws/initial" --num_threads "$threads" || return 0
  timed "$ws/adjust" "$BAYON" adjust --database_path "$db" \
    --input_path "$ws/initial" --output_path "$ws/model" --datum free \
    --self_calibration "$self_calibration" --num_threads "$threads" || return 0
}

# judge WS TRUTH LABEL: evaluation.json and the model's cameras as text.
judge() {
  local ws="$1" truth="$2" label="$3"
  [ -d "$ws/model" ] || return 0
  "$BAYON" evaluate --input_path "$ws/model" --ground_truth_path "$truth" \
    --output_path "$ws/evaluation.json" --label "$label" \
    >"$ws/evaluate.log" 2>&1 || true
  mkdir -p "$ws/model_txt"
  colmap model_converter --input_path "$ws/model" --output_path "$ws/model_txt" \
    --output_type TXT >/dev/null 2>&1 || true
}
