#!/usr/bin/env bash
# Runs the full benchmark (issue 4) and writes bench/results/<date>-<host>.csv together with the
# machine description. Usage: bench/run.sh [build-dir]   (default build/, from scripts/setup)
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
out=bench/results/$(date -u +%Y-%m-%d)-$(hostname -s).csv
{
  echo "# gradel-bench $(git rev-parse --short HEAD 2>/dev/null || echo unknown), $(date -u +%FT%TZ)"
  echo "# cpu: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs), $(nproc) cores; L3 $(lscpu | awk -F: '/L3/{print $2}' | xargs)"
  echo "# compiler: $(c++ --version | head -1); load average before: $(cut -d' ' -f1-3 /proc/loadavg)"
  "$build/gradel-bench" --shapes sphere,box --sizes 12,32,64,128,256 --layouts gradational,uniform,voxel \
    --threads 1,2 --reps 5 --min-time 0.3 --max-pairs 40000000 --find-realtime
} > "$out.tmp"
mv "$out.tmp" "$out"
echo "wrote $out" >&2
