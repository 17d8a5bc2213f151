# Wall time and peak memory of benchmark steps, by /usr/bin/time -v.
# Sourced by scripts/bench/*.sh; not a benchmark itself.

# timed LOG COMMAND...: the command's output to LOG.log, /usr/bin/time's
# report to LOG.time; on failure a line naming LOG.log, and status 1.
timed() {
  local log="$1"
  shift
  if ! /usr/bin/time -v -o "$log.time" "$@" >"$log.log" 2>&1; then
    echo "failed: $*; see $log.log" >&2
    return 1
  fi
}

# wall_s LOG: the wall-clock seconds in LOG.time.
wall_s() {
  sed -n 's/.*Elapsed (wall clock) time (h:mm:ss or m:ss): //p' "$1.time" |
    awk -F: '{ s = 0; for (i = 1; i <= NF; ++i) s = s * 60 + $i; print s }'
}

# peak_mb LOG: the largest resident set in LOG.time, MB.
peak_mb() {
  echo $(($(sed -n 's/.*Maximum resident set size (kbytes): //p' "$1.time") / 1024))
}

# totals LOG...: the steps' wall-clock seconds summed and their largest
# peak, "SECONDS MB".
totals() {
  local t=0 m=0 log
  for log in "$@"; do
    t=$(awk -v a="$t" -v b="$(wall_s "$log")" 'BEGIN { print a + b }')
    m=$(awk -v a="$m" -v b="$(peak_mb "$log")" 'BEGIN { print (b > a ? b : a) }')
  done
  echo "$t $m"
}
