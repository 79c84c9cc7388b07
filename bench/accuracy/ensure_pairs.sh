# Sourced by bench/bench_accuracy.sh and bench/compare_peers.sh.
#
# output_dir NAME: makes OUT (the caller's variable) an absolute, existing folder; when OUT is
# empty, a temporary one (vdbmatch-NAME.XXXXXX) removed on exit, and KEEP=0 (else KEEP=1).
output_dir() {
  KEEP=1
  if [ -z "$OUT" ]; then
    OUT=$(mktemp -d "${TMPDIR:-/tmp}/vdbmatch-$1.XXXXXX")
    KEEP=0
    trap 'rm -rf "$OUT"' EXIT
  fi
  mkdir -p "$OUT"
  OUT=$(cd "$OUT" && pwd)
}

# ensure_pairs OUT PAIR...: generates OUT/pairs/P with make_pairs.py for every pair P that is
# missing, older than make_pairs.py, or lacks a file the current generator writes (landmarks,
# the resampled target); prints what it did. The caller sets PYTHON and MAKE_PAIRS and defines die.
ensure_pairs() {
  local out=$1 p start
  shift
  local missing=()
  for p in "$@"; do
    if [ ! -f "$out/pairs/$p/pair.json" ] || [ "$MAKE_PAIRS" -nt "$out/pairs/$p/pair.json" ] \
        || [ ! -f "$out/pairs/$p/landmarks_source.csv" ] \
        || ! ls "$out/pairs/$p"/target_resampled.* >/dev/null 2>&1 \
        || ! ls "$out/pairs/$p"/target_scan.* >/dev/null 2>&1; then
      missing+=("$p")
    fi
  done
  if [ ${#missing[@]} -eq 0 ]; then
    echo "pairs: reusing $out/pairs"
    return
  fi
  start=$(date +%s.%N)
  "$PYTHON" "$MAKE_PAIRS" "$out/pairs" --only "$(IFS=,; echo "${missing[*]}")" >"$out/make_pairs.log" 2>&1 \
      || { cat "$out/make_pairs.log" >&2; die "make_pairs.py failed"; }
  echo "pairs generated in $(awk -v a="$start" -v b="$(date +%s.%N)" 'BEGIN { printf "%.1f", b - a }') s:"
  sed -n 's/^/  /p' "$out/make_pairs.log"
}
