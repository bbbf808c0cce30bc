#!/usr/bin/env bash
# ctest bench.drill_smoke: gradel-bench --drill on a 12^3 box at 1 and 2 threads: the burr removed
# voxels in most frames, and the carved body (voxels removed, vertices, dt after) is the same at
# both thread counts. Never a timing threshold. Usage: bench_drill_smoke.sh path/to/gradel-bench
set -euo pipefail
bench=$1
out=$(mktemp)
trap 'rm -f "$out"' EXIT
"$bench" --drill --sizes 12 --threads 1,2 >"$out" 2>/dev/null
awk -F, '
  !header { for (i = 1; i <= NF; ++i) col[$i] = i; header = 1; next }
  { ++rows
    if (!($col["removed_voxels"] + 0 > 0)) { print "row " NR ": no voxel removed"; bad = 1 }
    if (!($col["frames_with_event"] + 0 >= 30)) { print "row " NR ": events in fewer than 30 of 60 frames"; bad = 1 }
    if ($col["real_time_factor"] ~ /nan|inf/ || !($col["real_time_factor"] + 0 > 0)) { print "row " NR ": real_time_factor"; bad = 1 }
    key = $col["removed_voxels"] "/" $col["vertices_after"] "/" $col["dt_after_s"]
    if (rows > 1 && key != first) { print "the carved body differs between thread counts: " first " / " key; bad = 1 }
    if (rows == 1) first = key }
  END { if (rows != 2) { print "expected 2 rows"; bad = 1 }
        exit bad }' "$out" || { cat "$out"; exit 1; }
echo "drill smoke: $(tail -n +2 "$out" | wc -l) rows, voxels removed, the same carved body at 1 and 2 threads"
