#!/usr/bin/env bash
# ctest bench.real_smoke: runs gradel-bench on a small real scene (and the paper setting) for a
# few hundred steps at 1 and 2 threads and checks the CSV: every column the README quotes is
# present, every number is finite and positive where it must be, and the state hash is the same
# at both thread counts. Never a timing threshold. Usage: bench_smoke.sh path/to/gradel-bench
set -euo pipefail
bench=$1
out=$(mktemp)
trap 'rm -f "$out"' EXIT
"$bench" --sets real,paper --shapes sphere --sizes 24 --layouts gradational --moduli 1e5 --threads 1,2 \
  --reps 1 --min-time 0.01 >"$out" 2>/dev/null
awk -F, '
  /^#/ { next }
  !header { for (i = 1; i <= NF; ++i) col[$i] = i; header = 1
            split("set n layout youngs_modulus_pa threads load unique_vertices ns_per_vertex_step dt_s real_time_factor bytes_per_vertex state_hash", need, " ")
            for (k in need) if (!(need[k] in col)) { print "missing column " need[k]; bad = 1 }
            next }
  { rows[$col["set"]]++
    for (k in need) { v = $col[need[k]]
      if (v == "" || v ~ /nan|inf/) { print "row " NR ": " need[k] " = \"" v "\""; bad = 1 } }
    split("ns_per_vertex_step dt_s real_time_factor bytes_per_vertex unique_vertices", pos, " ")
    for (k in pos) if (!($col[pos[k]] + 0 > 0)) { print "row " NR ": " pos[k] " not > 0"; bad = 1 }
    key = $col["set"] "/" $col["n"]
    if (key in hash && hash[key] != $col["state_hash"]) { print "state hash differs between thread counts for " key; bad = 1 }
    hash[key] = $col["state_hash"] }
  END { if (rows["real"] != 2 || rows["paper"] != 2) { print "expected 2 real and 2 paper rows"; bad = 1 }
        exit bad }' "$out" || { cat "$out"; exit 1; }
echo "bench smoke: $(grep -vc '^#' "$out") lines, columns present and finite, hashes equal across threads"
