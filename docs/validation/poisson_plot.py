# The Poisson section's pictures from its CSV files: python3 poisson_plot.py [DIR] reads and writes DIR,
# by default the folder of this file (gradel-validate runs it on its --out folder).
import csv, os, sys
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
from matplotlib.patches import Circle
here = sys.argv[1] if len(sys.argv) > 1 else os.path.dirname(os.path.abspath(__file__))
rows = list(csv.DictReader(open(os.path.join(here, "poisson_ball_sections.csv"))))
ratios = sorted({r["nu"] for r in rows}, key=float)
shown = [ratios[0], ratios[-1]]
fig, axes = plt.subplots(1, 2, figsize=(10, 5), sharey=True)
for ax, nu in zip(axes, shown):
    for state, style in (("rest", "k:"), ("end", "b-")):
        for r in rows:
            if r["nu"] == nu and r["state"] == state:
                ax.plot([1000 * float(r["x0"]), 1000 * float(r["x1"])], [1000 * float(r["y0"]), 1000 * float(r["y1"])], style, lw=1)
    r0 = next(r for r in rows if r["nu"] == nu)
    for side in (-1, 1):
        ax.add_patch(Circle((side * 1000 * float(r0["tool_x"]), 0), 1000 * float(r0["tool_radius"]), color="0.8", zorder=0))
    ax.set_aspect("equal"); ax.set_xlim(-70, 70); ax.set_ylim(-60, 60)
    ax.set_title("nu = %s" % nu); ax.set_xlabel("x [mm]")
axes[0].set_ylabel("y [mm]")
fig.suptitle("ball squeezed between two spheres: mid-plane section at rest (dotted) and squeezed (blue)")
fig.tight_layout(); fig.savefig(os.path.join(here, "poisson_ball.png"), dpi=110)
uni = list(csv.DictReader(open(os.path.join(here, "poisson_uniaxial.csv"))))
fig, ax = plt.subplots(figsize=(6, 5))
ax.plot([0, 0.5], [0, 0.5], "k:", lw=1, label="lateral / axial = nu")
for (exp, integ, layout), m in (
        (("compression 2 %", "symplectic", "uniform"), "o"), (("compression 2 %", "symplectic", "gradational"), "s"),
        (("compression 2 %", "implicit", "uniform"), "^"), (("stretch 0.1 %", "symplectic", "gradational"), "x"),
        (("stretch 10 %", "symplectic", "gradational"), "+")):
    r = [x for x in uni if (x["experiment"], x["integrator"], x["layout"]) == (exp, integ, layout)]
    ax.plot([float(x["nu"]) for x in r], [float(x["ratio"]) for x in r], m, ms=8, mfc="none", label="%s, %s, %s" % (exp, integ, layout))
ax.set_xlabel("material.poisson_ratio"); ax.set_ylabel("measured lateral / axial strain"); ax.legend(fontsize=8)
fig.tight_layout(); fig.savefig(os.path.join(here, "poisson_ratio.png"), dpi=110)
