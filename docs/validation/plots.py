# The report's pictures from its CSV files: python3 plots.py [DIR] reads and writes DIR, by default
# the folder of this file (gradel-validate runs it on its --out folder).
import csv, os, sys
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
d = sys.argv[1] if len(sys.argv) > 1 else os.path.dirname(os.path.abspath(__file__))
def rows(name):
    with open(os.path.join(d, name)) as f:
        return list(csv.DictReader(f))
def convergence(name, value, ylabel, png):
    data = rows(name)
    fig, axes = plt.subplots(1, 2, figsize=(10, 4), sharey=True)
    for ax, scaling in zip(axes, ["consistent", "paper"]):
        for layout, m in [("gradational", "o-"), ("uniform", "s--"), ("voxel", "^:")]:
            r = [x for x in data if x["scaling"] == scaling and x["layout"] == layout]
            ax.plot([int(x["across"]) for x in r], [value(x) for x in r], m, label=layout)
        ax.axhline(1.0, color="k", lw=0.8)
        ax.set_xscale("log", base=2); ax.set_xlabel("voxels across the section"); ax.set_title(scaling + " scaling")
        ax.grid(alpha=0.3)
    axes[0].set_ylabel(ylabel); axes[0].legend()
    fig.tight_layout(); fig.savefig(os.path.join(d, png), dpi=110)
convergence("sag.csv", lambda x: float(x["sag"]) / float(x["theory_nominal"]),
            "tip sag / Euler-Bernoulli (E = 1e7 Pa)", "sag_convergence.png")
convergence("frequency.csv", lambda x: float(x["f_explicit"]) / float(x["f_theory_nominal"]),
            "first frequency / Euler-Bernoulli", "frequency_convergence.png")
tip = rows("tip.csv")
fig, ax = plt.subplots(figsize=(10, 4))
for run in dict.fromkeys(x["run"] for x in tip):
    r = [x for x in tip if x["run"] == run]
    ax.plot([float(x["time"]) for x in r], [1000 * float(x["tip"]) for x in r], label=run, lw=1)
ax.set_xlim(0, 0.6); ax.set_xlabel("time [s]"); ax.set_ylabel("tip displacement [mm]"); ax.grid(alpha=0.3); ax.legend()
ax.set_title("clamped bar released under gravity: explicit vs implicit")
fig.tight_layout(); fig.savefig(os.path.join(d, "tip_explicit_implicit.png"), dpi=110)
