#!/usr/bin/env bash
# Runs the benchmark and writes bench/results/<date>-<host>-{real,paper,contact,threads}.csv with the
# machine description. Usage: bench/run.sh [build-dir]   (default build/, from scripts/setup)
#  real:    SI scenes (gravity, walls, a pressing manipulator, a pin, metrics per 1/60 s frame),
#           n = 16..256, E = 1e4, 1e5, 1e6 Pa, 1 and 2 threads, gradational and uniform
#           (uniform at n = 256 too: where gradational should pass 5x, README "Speed");
#  paper:   the paper's Table 1 setting, for the comparison with the paper and with `real`;
#  contact: two spheres in soft-soft contact (n = 32, 64): the body-contact stage's share of a step;
#  threads: the threading mechanisms compared (docs/speed.md, "Threads"), quiet and with one busy process.
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
stem=bench/results/$(date -u +%Y-%m-%d)-$(hostname -s)
describe() {
  echo "# gradel-bench $(git rev-parse --short HEAD 2>/dev/null || echo unknown), $(date -u +%FT%TZ)"
  echo "# cpu: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs), $(nproc) cores; L3 $(lscpu | awk -F: '/L3/{print $2}' | xargs)"
  echo "# compiler: $(c++ --version | head -1); load average before: $(cut -d' ' -f1-3 /proc/loadavg)"
}
bench() { "$build/gradel-bench" --reps 5 --min-time 0.3 "$@"; }
{
  describe
  bench --sets real --sizes 16,32,64,128 --layouts gradational --moduli 1e4,1e5,1e6 --threads 1,2
  bench --sets real --sizes 256 --layouts gradational --moduli 1e5 --threads 1,2 | grep -v '^set,'
  bench --sets real --sizes 64,128,256 --layouts uniform --moduli 1e5 --threads 1,2 | grep -v '^set,'
} > "$stem-real.csv.tmp" && mv "$stem-real.csv.tmp" "$stem-real.csv"
{
  describe
  bench --sets paper --shapes sphere --sizes 16,32,64,128,256 --layouts gradational --threads 1,2
  bench --sets paper --shapes sphere --sizes 64,128,256 --layouts uniform --threads 1,2 | grep -v '^set,'
} > "$stem-paper.csv.tmp" && mv "$stem-paper.csv.tmp" "$stem-paper.csv"
# contact: two spheres in soft-soft contact, the body-contact stage's share of the step (issue 12).
{
  describe
  "$build/gradel-bench" --reps 5 --sets contact --sizes 32,64 --threads 1,2
} > "$stem-contact.csv.tmp" && mv "$stem-contact.csv.tmp" "$stem-contact.csv"
# The threading mechanisms: the team (default), OpenMP with libgomp's default (spinning) wait and
# with OMP_WAIT_POLICY=passive; each on a quiet machine and beside one busy process (--load).
# The OpenMP path exists only in a build configured with -DGRADEL_OPENMP_COMPARISON=ON.
if grep -q '^GRADEL_OPENMP_COMPARISON:BOOL=ON' "$build/CMakeCache.txt" 2>/dev/null; then
  mechanisms="team openmp-default openmp-passive"
else
  mechanisms=team
fi
{
  describe
  [ "$mechanisms" = team ] && echo "# OpenMP rows left out: $build was configured without -DGRADEL_OPENMP_COMPARISON=ON"
  echo "# mechanism,then the gradel-bench columns"
  for load in "" --load; do
    for mech in $mechanisms; do
      case $mech in
        team) env=() ;;
        openmp-default) env=(GRADEL_THREADING=openmp) ;;
        openmp-passive) env=(GRADEL_THREADING=openmp OMP_WAIT_POLICY=passive) ;;
      esac
      env "${env[@]}" "$build/gradel-bench" --reps 7 --min-time 0.3 --sets real --sizes 64,128 --layouts gradational \
        --moduli 1e5 --threads 1,2 $load | grep -v '^set,' | sed "s/^/$mech,/"
    done
  done
} > "$stem-threads.csv.tmp" && mv "$stem-threads.csv.tmp" "$stem-threads.csv"
echo "wrote $stem-{real,paper,contact,threads}.csv" >&2
