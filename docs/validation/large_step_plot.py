# The large step's sweep (large_step.csv): amplitude kept per period and frequency over CG iterations
# per substep at dt = 1/60 s, per coarse-space node budget. python3 large_step_plot.py [DIR] reads and
# writes DIR, by default the folder of this file (gradel-validate runs it on its --out folder).
import csv, os, sys
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
d = sys.argv[1] if len(sys.argv) > 1 else os.path.dirname(os.path.abspath(__file__))
with open(os.path.join(d, "large_step.csv")) as f:
    data = [x for x in csv.DictReader(f) if abs(float(x["dt"]) - 1 / 60) < 1e-6]
fig, axes = plt.subplots(1, 2, figsize=(10, 4))
# Amplitude kept per period (0 when no vibration is left); a red x where the frequency is more than 10 % off.
kept = lambda x: 0.0 if float(x["f"]) <= 0 else 1 - float(x["decay_per_period"])
off = lambda x: abs(float(x["f_over_explicit"]) - 1) > 0.1
for nodes in dict.fromkeys(x["coarse_nodes"] for x in data):
    r = [x for x in data if x["coarse_nodes"] == nodes]
    label = "projective preconditioner alone" if nodes == "0" else "+ coarse space, %s nodes" % nodes
    for ax, cost in zip(axes, [lambda x: int(x["passes"]), lambda x: float(x["cpu_us_per_step"]) / 1000]):
        ax.plot([cost(x) for x in r], [kept(x) for x in r], "o-", label=label)
        bad = [x for x in r if off(x)]
        ax.plot([cost(x) for x in bad], [kept(x) for x in bad], "rx", ms=10, mew=2)
for ax in axes:
    ax.axhline(0.9, color="k", lw=0.8, ls="--"); ax.grid(alpha=0.3); ax.set_ylabel("amplitude kept per period")
axes[0].set_xscale("log"); axes[0].set_xlabel("CG iterations per substep"); axes[0].legend()
axes[1].set_xscale("log"); axes[1].set_xlabel("CPU ms per step (one thread)")
fig.suptitle("large step on the clamped bar, dt = 1/60 s")
fig.tight_layout(); fig.savefig(os.path.join(d, "large_step_sweep.png"), dpi=110)
