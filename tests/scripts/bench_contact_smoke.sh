#!/usr/bin/env bash
# ctest bench.contact_smoke: gradel-bench's contact set (two spheres in soft-soft contact) on small
# spheres at 1 and 2 threads: two rows, the body-contact stage's share a fraction in (0, 1), the
# state hash the same at both thread counts; its --contact-trace: a row per step and thread count,
# the same contacts and lookups per step at both counts, the forced lookups among the lookups, the
# stage within its step; an unwritable trace path refused by name. Never a timing threshold.
# Usage: bench_contact_smoke.sh path/to/gradel-bench
set -euo pipefail
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
out=$("$1" --sets contact --sizes 16 --threads 1,2 --reps 1 --contact-steps 10 --contact-trace "$tmp/trace.csv" 2>/dev/null)
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
awk -F, '
  NR == 1 { for (i = 1; i <= NF; ++i) col[$i] = i; next }
  { rows++
    key = $col["step"]; what = $col["contacts"] " " $col["lookups"] " " $col["moved_lookups"] " " $col["rounds"]
    if (key in seen && seen[key] != what) { print "step " key ": " seen[key] " at one thread count, " what " at the other"; bad = 1 }
    seen[key] = what
    if ($col["moved_lookups"] + 0 > $col["lookups"] + 0) { print "line " NR ": more forced lookups than lookups"; bad = 1 }
    if ($col["stage_us"] + 0 > $col["step_us"] + 0) { print "line " NR ": the stage took longer than its step"; bad = 1 } }
  END { if (rows != 20) { print "expected 20 trace rows, got " rows; bad = 1 }
        exit bad }' "$tmp/trace.csv" || { cat "$tmp/trace.csv"; exit 1; }
if err=$("$1" --sets contact --sizes 16 --threads 1 --reps 1 --contact-steps 1 --contact-trace "$tmp/no/such/dir.csv" 2>&1 >/dev/null); then
  echo "an unwritable --contact-trace was accepted"; exit 1
fi
echo "$err" | grep -q -- "--contact-trace: cannot write" || { echo "unclear message: $err"; exit 1; }
echo "bench contact smoke: 2 rows, share in (0, 1), hashes equal across threads; trace: 20 rows, the same per step across threads"
