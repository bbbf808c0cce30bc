# Plots a contact trace (gradel-bench --sets contact --contact-trace FILE): per step of the
# collision, the body-contact stage's share of the step time at each thread count, and the
# lookups of the narrow phase against the contacts, with the lookups the stage's own corrections
# forced (moved_lookups: the floor, docs/speed.md). Averages over windows of 25 steps.
#   /usr/bin/python3 bench/plot_contact_trace.py TRACE.csv OUT.png
import csv, sys
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt

if len(sys.argv) != 3:
    sys.exit("usage: plot_contact_trace.py TRACE.csv OUT.png")
try:
    with open(sys.argv[1]) as f:
        rows = list(csv.DictReader(f))
    need = {"threads", "step", "contacts", "lookups", "moved_lookups", "stage_us", "step_us"}
    if not rows or not need <= set(rows[0]):
        sys.exit("%s: not a contact trace (columns %s)" % (sys.argv[1], ", ".join(sorted(need))))
except OSError as e:
    sys.exit("%s: %s" % (sys.argv[1], e.strerror))
W = 25
fig, axes = plt.subplots(1, 2, figsize=(11, 4))
for t in dict.fromkeys(r["threads"] for r in rows):
    r = [x for x in rows if x["threads"] == t]
    steps, share = [], []
    for a in range(0, len(r) - W + 1, W):
        w = r[a:a + W]
        steps.append(int(w[W // 2]["step"]))
        share.append(sum(float(x["stage_us"]) for x in w) / sum(float(x["step_us"]) for x in w))
    axes[0].plot(steps, share, label="%s thread%s" % (t, "" if t == "1" else "s"))
axes[0].axhline(0.25, color="k", lw=0.8, ls="--", label="issue 12 target (25 %)")
axes[0].set_xlabel("step after the balls touch"); axes[0].set_ylabel("contact stage / step time")
axes[0].set_ylim(0, 1); axes[0].legend(); axes[0].grid(alpha=0.3)
r = [x for x in rows if x["threads"] == rows[0]["threads"]]
mean = lambda k, a: sum(float(x[k]) for x in r[a:a + W]) / W
steps = [int(r[a + W // 2]["step"]) for a in range(0, len(r) - W + 1, W)]
for key, label in [("lookups", "lookups"), ("moved_lookups", "lookups of vertices the stage itself moved (the floor)"),
                   ("contacts", "contacts")]:
    axes[1].plot(steps, [mean(key, a) for a in range(0, len(r) - W + 1, W)], label=label)
axes[1].set_xlabel("step after the balls touch"); axes[1].set_ylabel("per step")
axes[1].legend(); axes[1].grid(alpha=0.3)
fig.suptitle("two 64^3 balls colliding head on: the body-contact stage over the collision")
fig.tight_layout(); fig.savefig(sys.argv[2], dpi=100)
