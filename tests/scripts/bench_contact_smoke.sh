#!/usr/bin/env bash
# ctest bench.contact_smoke: gradel-bench's contact set (two spheres in soft-soft contact) on small
# spheres at 1 and 2 threads: two rows, the body-contact stage's share a fraction in (0, 1), the
# state hash the same at both thread counts. Never a timing threshold.
# Usage: bench_contact_smoke.sh path/to/gradel-bench
set -euo pipefail
out=$("$1" --sets contact --sizes 16 --threads 1,2 --reps 1 --contact-steps 10 2>/dev/null)
echo "$out" | awk -F, '
  /^#/ { next }
  !header { for (i = 1; i <= NF; ++i) col[$i] = i; header = 1
            if (!("contact_stage_share" in col) || !("state_hash" in col)) { print "missing columns"; bad = 1 }
            next }
  { rows++
    s = $col["contact_stage_share"] + 0
    if (!(s > 0 && s < 1)) { print "row " NR ": contact_stage_share " $col["contact_stage_share"]; bad = 1 }
    if (hash != "" && hash != $col["state_hash"]) { print "state hash differs between thread counts"; bad = 1 }
    hash = $col["state_hash"] }
  END { if (rows != 2) { print "expected 2 contact rows"; bad = 1 }
        exit bad }' || { echo "$out"; exit 1; }
echo "bench contact smoke: 2 rows, share in (0, 1), hashes equal across threads"
