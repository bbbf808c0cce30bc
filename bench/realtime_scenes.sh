#!/usr/bin/env bash
# Real-time factor of shipped scenes as a user runs them: `gradel run SCENE --threads T` end to end
# (build, steps, .vtu frames, metrics.csv), median of REPS runs. CSV on stdout.
# Usage: bench/realtime_scenes.sh [build/gradel] [threads] [reps] [scene names...]
set -euo pipefail
cd "$(dirname "$0")/.."
gradel=${1:-build/gradel}; threads=${2:-2}; reps=${3:-3}; shift $(( $# < 3 ? $# : 3 ))
scenes=("$@")
[ ${#scenes[@]} -eq 0 ] && scenes=(strike grasp-two two-balls phantom box-realtime)
out=$(mktemp -d); trap 'rm -rf "$out"' EXIT
echo "scene,threads,integrator,dt_s,vertices,simulated_s,wall_s_median,real_time_factor_median,load_1min"
for s in "${scenes[@]}"; do
  walls=()
  for ((r = 0; r < reps; ++r)); do
    "$gradel" run "scenes/$s.json" --threads "$threads" --out "$out/$s" > "$out/summary.json" 2> /dev/null
    walls+=("$(/usr/bin/python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["wall_seconds"])' "$out/summary.json")")
  done
  /usr/bin/python3 - "$out/summary.json" "$s" "$threads" "$(cut -d' ' -f1 /proc/loadavg)" "${walls[@]}" <<'PY'
import json, statistics, sys
j = json.load(open(sys.argv[1])); walls = sorted(float(w) for w in sys.argv[5:])
wall = statistics.median(walls)
print(f"{sys.argv[2]},{sys.argv[3]},{j.get('integrator','')},{j['dt']:.4g},{j['vertices']},{j['simulated_seconds']:.4g},"
      f"{wall:.4g},{j['simulated_seconds'] / wall:.3g},{sys.argv[4]}")
PY
done
