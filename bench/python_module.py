#!/usr/bin/env python3
"""Speed of the pip-installed gradel module against the build tree's, on the same scene.

Each (module, round) runs in its own interpreter: the installed one with the venv's python from
outside the source tree, the build tree's with PYTHONPATH=<build>/python. A run builds a sphere of
SIZE^3 voxels resting on the floor (symplectic Euler, dt auto, THREADS threads), steps it WARMUP
steps, then times REPEATS blocks of STEPS steps and prints the median block in ns per
vertex-step. Rounds alternate between the two modules so that a change in the machine's load hits
both. Rows (one per run, plus a median row per module and the ratio) go to stdout or --out as CSV.

Usage: bench/python_module.py --venv-python .venv/bin/python --build-dir build \\
           [--size 32] [--threads 2] [--rounds 5] [--out bench/results/...csv]
"""
import argparse
import datetime
import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile

RUN = r"""
import json, os, statistics, sys, time
import gradel
size, threads, steps, repeats, warmup = (int(a) for a in sys.argv[1:6])
body = gradel.Body.from_shape("sphere", size)
extent = 0.01 * size
sim = gradel.Simulation(body, integrator="symplectic", threads=threads, position=[0, extent / 2, 0],
                        domain_min=[-extent, 0, -extent], domain_max=[extent, 2 * extent, extent])
sim.step(warmup)
blocks = []
for _ in range(repeats):
    t0 = time.perf_counter()
    sim.step(steps)
    blocks.append((time.perf_counter() - t0) * 1e9 / (steps * sim.num_vertices))
print(json.dumps({"module": os.path.realpath(gradel.__file__), "vertices": sim.num_vertices,
                  "dt": sim.dt, "ns_per_vertex_step": statistics.median(blocks)}))
"""


def run_once(python, env, args):
    with tempfile.TemporaryDirectory() as cwd:  # outside the source tree: no stray `gradel` package
        out = subprocess.run([python, "-c", RUN, str(args.size), str(args.threads), str(args.steps),
                              str(args.repeats), str(args.warmup)],
                             env=env, cwd=cwd, check=True, capture_output=True, text=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def cache_value(build_dir, name):
    try:
        with open(os.path.join(build_dir, "CMakeCache.txt")) as f:
            for line in f:
                if line.startswith(name + ":"):
                    return line.strip().split("=", 1)[1]
    except OSError:
        pass
    return "?"


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--venv-python", required=True, help="python of the venv the package is installed into")
    p.add_argument("--build-dir", required=True, help="the build tree whose python/ holds its module")
    p.add_argument("--installed-tree", default="build/python-package/cmake",
                   help="the CMake tree pip built (for its GRADEL_X86_64_V3 setting)")
    p.add_argument("--system-python", default="/usr/bin/python3")
    p.add_argument("--size", type=int, default=32)
    p.add_argument("--threads", type=int, default=2)
    p.add_argument("--steps", type=int, default=100)
    p.add_argument("--repeats", type=int, default=5)
    p.add_argument("--warmup", type=int, default=20)
    p.add_argument("--rounds", type=int, default=5)
    p.add_argument("--out", help="CSV file (default: stdout)")
    args = p.parse_args()

    load = " ".join(f"{x:.2f}" for x in os.getloadavg())
    base = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    base["PYTHONDONTWRITEBYTECODE"] = "1"
    tree_env = dict(base, PYTHONPATH=os.path.abspath(os.path.join(args.build_dir, "python")))
    modules = {
        "installed": (args.venv_python, base, cache_value(args.installed_tree, "GRADEL_X86_64_V3")),
        "build_tree": (args.system_python, tree_env, cache_value(args.build_dir, "GRADEL_X86_64_V3")),
    }
    rows, per = [], {name: [] for name in modules}
    for r in range(args.rounds):
        for name, (python, env, v3) in modules.items():
            res = run_once(python, env, args)
            per[name].append(res["ns_per_vertex_step"])
            rows.append([name, v3, r, res["vertices"], f"{res['dt']:.4g}", f"{res['ns_per_vertex_step']:.2f}",
                         res["module"]])
            print(f"{name:10s} round {r}: {res['ns_per_vertex_step']:.2f} ns per vertex-step", file=sys.stderr)
    med = {name: statistics.median(v) for name, v in per.items()}
    for name, (_, _, v3) in modules.items():
        rows.append([name, v3, "median", rows[0][3], rows[0][4], f"{med[name]:.2f}", ""])
    ratio = med["installed"] / med["build_tree"]
    rows.append(["installed/build_tree", "", "median", "", "", f"{ratio:.3f}", ""])

    head = [f"# bench/python_module.py {datetime.datetime.now(datetime.timezone.utc).isoformat(timespec='seconds')}",
            f"# cpu: {platform.processor() or platform.machine()}, {os.cpu_count()} cores; load average before: {load}",
            f"# scene: sphere {args.size}^3 on the floor, symplectic, dt auto, {args.threads} threads; "
            f"{args.repeats} blocks of {args.steps} steps after {args.warmup}, median block per run",
            "module,x86_64_v3,round,vertices,dt,ns_per_vertex_step,path"]
    text = "\n".join(head + [",".join(str(c) for c in row) for row in rows]) + "\n"
    if args.out:
        with open(args.out, "w") as f:
            f.write(text)
    else:
        sys.stdout.write(text)
    print(f"installed / build tree: {ratio:.3f} (target <= 1.2)", file=sys.stderr)


if __name__ == "__main__":
    main()
