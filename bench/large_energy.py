#!/usr/bin/python3
"""Peak energy of the frame-size integrators in contact against the explicit run (issue 26 item 1).

Each shipped contact scene (strike, grasp-wall, grasp-two, grasp-body) is copied with every
material's Young's modulus times a factor, then run with `gradel run` once explicitly (the scene's
own integrator at dt = "auto": the reference) and once per frame-size integrator and dt. The peak
is the largest kinetic + elastic energy [J] over the run's frames (metrics.csv; the row "all" with
several bodies); the explicit run writes a frame every 5 ms, the frame-size runs one per step. A
run that exits 3 (diverged: nothing written) reports the energy the divergence guard measured, a
lower bound of its peak, with exit 3.
CSV on stdout: scene, E factor, integrator, dt, peak, explicit peak, ratio, end energy, explicit end.

Usage: bench/large_energy.py [--gradel build/gradel] [--scenes strike,grasp-wall,...]
       [--factors 1,10,100,1000] [--integrators large_step,implicit] [--dts 1/60,1/30] [--threads 1]
       [--explicit-from OLD.csv]  (the explicit peaks and ends of an earlier table: the explicit
       runs at E x1000 take most of the time, and a change to the frame-size steps leaves them;
       lines of OLD.csv starting with '#' are skipped)
       [--friction MU]  (every manipulator's and the walls' friction set to MU, in the frame-size
       runs and the explicit reference alike: e.g. 0 to see what the surfaces' friction costs)
"""
import argparse
import copy
import csv
import json
import os
import re
import subprocess
import sys
import tempfile
from fractions import Fraction

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DEFAULT_E = 1e5  # docs/scenes.md, material.youngs_modulus


def scaled(scene, factor):
    """The scene with every material's Young's modulus (regions included) times factor."""
    s = copy.deepcopy(scene)

    def scale(material):
        material["youngs_modulus"] = material.get("youngs_modulus", DEFAULT_E) * factor
        for r in material.get("regions", []):
            if "youngs_modulus" in r:
                r["youngs_modulus"] *= factor

    if "bodies" in s:
        for b in s["bodies"]:
            scale(b.setdefault("material", {}))
    else:
        scale(s.setdefault("material", {}))
    return s


def with_friction(scene, mu):
    """The scene with every manipulator's and the domain's friction set to mu."""
    s = copy.deepcopy(scene)
    for m in s.get("manipulators", []):
        m["friction"] = mu
    if "domain" in s:
        s["domain"]["friction"] = mu
    return s


def run(gradel, scene, workdir, name, threads):
    """Runs the scene; returns (peak, end) of kinetic + elastic energy [J] over its frames."""
    path = os.path.join(workdir, name + ".json")
    with open(path, "w") as f:
        json.dump(scene, f)
    out = os.path.join(workdir, name)
    r = subprocess.run([gradel, "run", path, "--out", out, "--threads", str(threads), "--max-steps", "1e8"],
                       stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    if r.returncode == 3:
        # Diverged (nothing written): the energy the guard measured is a lower bound of the peak.
        m = re.search(r"kinetic \+ elastic energy ([0-9.e+-]+) J", r.stderr)
        return (float(m.group(1)) if m else float("inf")), None, 3
    if r.returncode != 0:
        return None, None, r.returncode
    energies = []
    with open(os.path.join(out, "metrics.csv")) as f:
        for row in csv.DictReader(f):
            if "body" in row and row["body"] != "all":
                continue
            energies.append(float(row["kinetic_energy"]) + float(row["elastic_energy"]))
    subprocess.run(["rm", "-rf", out])
    return max(energies), energies[-1], 0


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--gradel", default=os.path.join(ROOT, "build", "gradel"))
    p.add_argument("--scenes", default="strike,grasp-wall,grasp-two,grasp-body")
    p.add_argument("--factors", default="1,10,100,1000")
    p.add_argument("--integrators", default="large_step,implicit")
    p.add_argument("--dts", default="1/60,1/30")
    p.add_argument("--threads", type=int, default=1)
    p.add_argument("--explicit-from", default="")
    p.add_argument("--friction", type=float, default=None)
    a = p.parse_args()
    dts = [float(Fraction(d)) for d in a.dts.split(",")]
    known = {}
    if a.explicit_from:
        with open(a.explicit_from) as f:
            for row in csv.DictReader(line for line in f if not line.startswith("#")):
                known[(row["scene"], float(row["e_factor"]))] = (float(row["explicit_peak_j"]),
                                                                 float(row["explicit_end_j"]), 0)
    w = csv.writer(sys.stdout, lineterminator="\n")
    w.writerow(["scene", "e_factor", "integrator", "dt_s", "peak_j", "explicit_peak_j", "ratio", "end_j",
                "explicit_end_j", "exit"])
    with tempfile.TemporaryDirectory() as tmp:
        for name in a.scenes.split(","):
            with open(os.path.join(ROOT, "scenes", name + ".json")) as f:
                base = json.load(f)
            for factor in [float(x) for x in a.factors.split(",")]:
                scene = scaled(base, factor)
                if a.friction is not None:
                    scene = with_friction(scene, a.friction)
                ref = copy.deepcopy(scene)
                ref["simulation"]["dt"] = "auto"
                ref["simulation"]["frame_interval"] = 0.005
                ref["simulation"].pop("integrator", None)
                if (name, factor) in known:
                    refPeak, refEnd, refExit = known[(name, factor)]
                else:
                    refPeak, refEnd, refExit = run(a.gradel, ref, tmp, "explicit", a.threads)
                for integrator in a.integrators.split(","):
                    for dt in dts:
                        s = copy.deepcopy(scene)
                        s["simulation"]["integrator"] = integrator
                        s["simulation"]["dt"] = dt
                        s["simulation"]["frame_interval"] = dt
                        peak, end, code = run(a.gradel, s, tmp, "frame", a.threads)
                        ok = peak is not None and refPeak
                        w.writerow([name, f"{factor:g}", integrator, f"{dt:.6g}",
                                    f"{peak:.6g}" if peak is not None else "",
                                    f"{refPeak:.6g}" if refPeak is not None else "",
                                    f"{peak / refPeak:.4g}" if ok else "",
                                    f"{end:.6g}" if end is not None else "",
                                    f"{refEnd:.6g}" if refEnd is not None else "", code or refExit])
                        sys.stdout.flush()


if __name__ == "__main__":
    main()
