#!/usr/bin/python3
"""The viewer's frame loop, measured as a user runs it: gradel-view's play sphere at each size
under Xvfb (Mesa llvmpipe, software OpenGL), `--run-for S` (frame times, the real-time factor
over the last second, the stepping thread's CPU per vertex-step, the drawing's CPU per frame,
triangles drawn). CSV on stdout, one row per run, with the 1-minute load average before and
after each run (the machine is shared: wall-clock figures are loaded, the CPU ones less so).

Usage: bench/viewer_frames.py [--view build/gradel-view] [--sizes 32,64,128] [--seconds 12]
                              [--reps 1] [--full-surface] [--rebuild 12:128]
       bench/viewer_frames.py --pieces [--sizes ...] [--reps N]
With --pieces no window is opened: `gradel-view --frame-pieces` times the frame loop's CPU pieces
(one step on one thread and the real-time factor one free core gives, the draw list coarse and
full, the stress pass) on the thread's CPU clock.
"""
import argparse
import json
import os
import subprocess
import sys


def load():
    return float(open("/proc/loadavg").read().split()[0])


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--view", default="build/gradel-view")
    p.add_argument("--sizes", default="32,64,128")
    p.add_argument("--seconds", type=float, default=12)
    p.add_argument("--reps", type=int, default=1)
    p.add_argument("--full-surface", action="store_true", help="draw the full surface over the budget too")
    p.add_argument("--rebuild", default="", help="FROM:TO: start at FROM, ask for TO at 2 s (as the panel would)")
    p.add_argument("--pieces", action="store_true", help="no window: the frame loop's CPU pieces")
    a = p.parse_args()
    if not os.access(a.view, os.X_OK):
        print(f"viewer_frames: {a.view}: not an executable (build the gradel-view target)", file=sys.stderr)
        return 2
    if a.pieces:
        return pieces(a)
    cols = ["size", "rep", "surface", "vertices", "draw_triangles", "full_surface_triangles", "coarse_step", "dt_s",
            "real_time_factor_last_s", "steps_per_second_last_s", "frame_ms_median", "frame_ms_max",
            "frame_work_ms_median", "world_held_ms_median", "frames_per_second", "step_cpu_ns_per_vertex_step",
            "step_thread_core_share", "draw_cpu_ms_per_frame", "rebuild_to", "rebuild_s",
            "frame_ms_max_during_rebuild", "load_1min_before", "load_1min_after"]
    print(",".join(cols))
    runs = [(int(s), None) for s in a.sizes.split(",")]
    if a.rebuild:
        f, t = a.rebuild.split(":")
        runs = [(int(f), int(t))]
    for size, to in runs:
        for rep in range(a.reps):
            cmd = ["xvfb-run", "-a", "-s", "-screen 0 1400x900x24", a.view, "--body-size", str(size),
                   "--run-for", str(a.seconds)]
            if a.full_surface:
                cmd.append("--full-surface")
            if to:
                cmd += ["--rebuild-size", str(to), "--rebuild-at", "2"]
            before = load()
            out = subprocess.run(cmd, capture_output=True, text=True)
            after = load()
            if out.returncode != 0:
                print(f"viewer_frames: size {size}: exit {out.returncode}: {out.stderr.strip()}", file=sys.stderr)
                return 1
            j = json.loads(out.stdout[out.stdout.index("{"):])
            row = {"size": size, "rep": rep, "surface": "coarse" if j["coarse_surface"] else "full",
                   "dt_s": f'{j["dt"]:.4g}', "rebuild_to": to or "", "rebuild_s": j.get("rebuild_seconds", ""),
                   "frame_ms_max_during_rebuild": j.get("frame_ms_max_during_rebuild", ""),
                   "load_1min_before": before, "load_1min_after": after, "rep": rep}
            for c in cols:
                if c not in row:
                    v = j[c]
                    row[c] = f"{v:.4g}" if isinstance(v, float) else v
            print(",".join(str(row[c]) for c in cols), flush=True)
    return 0


def pieces(a):
    cols = ["body_size", "rep", "vertices", "dt", "step_cpu_ms_1_thread", "step_cpu_ns_per_vertex_step",
            "real_time_factor_one_free_core", "draw_triangles", "full_surface_triangles", "coarse_step",
            "draw_list_cpu_ms", "draw_list_full_cpu_ms", "stress_pass_cpu_ms", "bounds_cpu_ms", "build_cpu_s",
            "body_view_cpu_s", "load_1min_before", "load_1min_after"]
    print(",".join(cols))
    for size in (int(s) for s in a.sizes.split(",")):
        for rep in range(a.reps):
            before = load()
            out = subprocess.run([a.view, "--frame-pieces", "--body-size", str(size)], capture_output=True, text=True)
            after = load()
            if out.returncode != 0:
                print(f"viewer_frames: size {size}: exit {out.returncode}: {out.stderr.strip()}", file=sys.stderr)
                return 1
            j = json.loads(out.stdout)
            j.update(rep=rep, load_1min_before=before, load_1min_after=after)
            print(",".join(f"{j[c]:.4g}" if isinstance(j[c], float) else str(j[c]) for c in cols), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
