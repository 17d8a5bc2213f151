# Helpers for benchmarks that run stock COLMAP. Sourced by scripts/bench/*.sh;
# not a benchmark itself.

# largest_model SPARSE_DIR: the mapper's model with the most registered images
# (images.bin starts with their number); empty when there is none.
largest_model() {
  local best="" best_n=-1 n model
  for model in "$1"/*/; do
    [ -f "$model/images.bin" ] || continue
    n=$(od -An -t u8 -N 8 "$model/images.bin" | tr -d ' ')
    if [ "$n" -gt "$best_n" ]; then
      best="${model%/}"
      best_n="$n"
    fi
  done
  echo "$best"
}
