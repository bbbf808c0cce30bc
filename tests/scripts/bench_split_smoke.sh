#!/usr/bin/env bash
# ctest bench.split_smoke: gradel-bench --split on a 12^3 box at 1 and 2 threads: the blade cut
# the box into two bodies, the same vertices at both thread counts, every time finite. Never a
# timing threshold. Usage: bench_split_smoke.sh path/to/gradel-bench
set -euo pipefail
bench=$1
out=$(mktemp)
trap 'rm -f "$out"' EXIT
"$bench" --split --sizes 12 --threads 1,2 --reps 1 >"$out" 2>/dev/null
awk -F, '
  !header { for (i = 1; i <= NF; ++i) col[$i] = i; header = 1; next }
  { ++rows
    if ($col["bodies_after"] != 2) { print "row " NR ": " $col["bodies_after"] " bodies after the cut"; bad = 1 }
    if ($col["ms_split_event"] ~ /nan|inf/ || !($col["ms_split_event"] + 0 > 0)) { print "row " NR ": ms_split_event"; bad = 1 }
    if (rows > 1 && $col["vertices_after"] != first) { print "the pieces differ between thread counts"; bad = 1 }
    if (rows == 1) first = $col["vertices_after"] }
  END { if (rows != 2) { print "expected 2 rows"; bad = 1 }
        exit bad }' "$out" || { cat "$out"; exit 1; }
echo "split smoke: $(tail -n +2 "$out" | wc -l) rows, two bodies after the cut at 1 and 2 threads"
