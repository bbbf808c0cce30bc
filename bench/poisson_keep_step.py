#!/usr/bin/python3
"""Two ways to keep the explicit step at a high Poisson's ratio, tried on small models (issue 29 item 2).

The volumetric stiffness at nu = 0.49 shortens the explicit step 3.4x (docs/speed.md, "Poisson's
ratio: what each integrator pays"). Both ideas below keep the static equilibria exact, which the
substep split did not; this script measures whether they keep the step.

1. `imex`: the volumetric part implicit (backward Euler on the pressure, one unknown per element:
   (1/kappa + dt^2 B M^-1 B^T) p = e(x) + dt B v*), solved by a few L1-Jacobi sweeps per step,
   warm started from the last step's pressures or started from the explicit kappa b. A chain of
   unit masses with a soft spring (the shape term, k) and a stiff one (the volume term,
   kappa = ratio k) on every element, dt a fraction of the soft spring's explicit limit, 20,000
   steps from a random start, no damping. Prints the peak and end energy over the start.
2. `sms`: selective mass scaling with an inverse mass applied directly (no solve):
   W = D^-1 - sum_e c_e (D^-1 g_e)(D^-1 g_e)^T, c_e = gamma / (g_e^T D^-1 g_e), g_e the
   element's dilatation direction. Momentum and static equilibria stay exact; the question is how
   far gamma can go before W stops being positive definite and what that buys in the highest
   frequency of W K. A 2D grid of 8 x 8 square shape-matching elements with the corotated
   volumetric term of element.h (kappa = 2 nu / (1 - 2 nu) k), K by central differences.

Usage: bench/poisson_keep_step.py [imex|sms]   (both by default; numpy only)
"""
import sys

import numpy as np


def imex_chain(init, sweeps, ratio, frac, n=60, steps=20000, seed=1):
    rng = np.random.default_rng(seed)
    k, kappa = 1.0, ratio
    B = np.zeros((n, n + 1))
    for e in range(n):
        B[e, e], B[e, e + 1] = -1, 1
    free = np.ones(n + 1, bool)
    free[0] = False  # the first mass held
    inv_m = np.where(free, 1.0, 0.0)
    K = k * B.T @ B
    dt = frac * 2 / np.sqrt(np.max(np.linalg.eigvalsh(K[np.ix_(free, free)])))
    rest = np.arange(n + 1, dtype=float)
    x = rest + rng.standard_normal(n + 1) * 0.05
    x[0] = 0
    v = np.zeros(n + 1)
    S = np.eye(n) / kappa + dt * dt * (B * inv_m) @ B.T
    D = np.abs(S).sum(1)  # L1-Jacobi: converges for any SPD S
    p = np.zeros(n)

    def energy():
        e = B @ (x - rest)
        return 0.5 * (v * v).sum() + 0.5 * (k + kappa) * (e * e).sum()

    e0 = peak = energy()
    for _ in range(steps):
        vs = v - dt * inv_m * (K @ (x - rest))
        b = B @ (x - rest) + dt * B @ vs
        if init == "explicit":
            p = kappa * b
        for _ in range(sweeps):
            p = p + (b - S @ p) / D
        v = vs - dt * inv_m * (B.T @ p)
        x = x + dt * v
        now = energy()
        peak = max(peak, now)
        if not np.isfinite(now) or now > 1e6 * e0:
            break
    return peak / e0, energy() / e0


def sms_grid(nu, gamma, n=8):
    dim = 2
    X = np.array([[j, i] for i in range(n + 1) for j in range(n + 1)], float)
    idx = lambda i, j: i * (n + 1) + j
    els = [[idx(i, j), idx(i, j + 1), idx(i + 1, j + 1), idx(i + 1, j)] for i in range(n) for j in range(n)]
    k = 1.0
    kappa = k * 2 * nu / (1 - 2 * nu)

    def forces(x):
        f = np.zeros_like(x)
        for e in els:
            R0 = X[e] - X[e].mean(0)
            r = x[e] - x[e].mean(0)
            A = r.T @ R0
            U, _, Vt = np.linalg.svd(A)
            M = U @ Vt
            if np.linalg.det(M) < 0:
                U[:, -1] *= -1
                M = U @ Vt
            f[e] += k * ((M @ R0.T).T - r)
            trS = np.trace(R0.T @ R0)
            ev = dim * (np.trace(M.T @ A) - trS) / trS
            f[e] -= kappa * ev * (dim / trS) * (M @ R0.T).T
        return f

    nd = X.size
    K = np.zeros((nd, nd))
    h = 1e-6
    for a in range(nd):
        xp, xm = X.ravel().copy(), X.ravel().copy()
        xp[a] += h
        xm[a] -= h
        K[:, a] = -(forces(xp.reshape(-1, 2)) - forces(xm.reshape(-1, 2))).ravel() / (2 * h)
    K = 0.5 * (K + K.T)
    m = np.zeros(len(X))
    for e in els:
        m[e] += 0.25
    Dm = np.repeat(m, 2)
    plain = np.sqrt(max(np.linalg.eigvalsh(K / np.sqrt(Dm)[:, None] / np.sqrt(Dm)[None, :])))
    W = np.diag(1 / Dm)
    for e in els:
        g = np.zeros((len(X), 2))
        g[e] = X[e] - X[e].mean(0)
        g = g.ravel()
        u = g / Dm
        W -= gamma / (g @ u) * np.outer(u, u)
    lowest = np.linalg.eigvalsh(W).min()
    if lowest <= 0:
        return plain, None, lowest
    L = np.linalg.cholesky(W)
    return plain, np.sqrt(max(np.linalg.eigvalsh(L.T @ K @ L))), lowest


def main():
    what = sys.argv[1:] or ["imex", "sms"]
    if "imex" in what:
        print("method,start,sweeps,kappa/k,dt/explicit limit of k,peak/E0,end/E0")
        for init in ("warm", "explicit"):
            for sweeps in (1, 2, 3, 5, 200):
                for ratio in (4, 15, 60):
                    for frac in (0.5, 0.9):
                        peak, end = imex_chain(init, sweeps, ratio, frac)
                        print(f"imex,{init},{sweeps},{ratio},{frac},{peak:.3g},{end:.3g}")
    if "sms" in what:
        print("method,nu,gamma,omega_max plain,omega_max scaled,dt gain,lowest eigenvalue of W")
        for nu in (0.45, 0.49):
            for gamma in (0.3, 0.5, 0.6, 0.7, 0.9):
                plain, scaled, lowest = sms_grid(nu, gamma)
                if scaled is None:
                    print(f"sms,{nu},{gamma},{plain:.4g},not positive definite,,{lowest:.3g}")
                else:
                    print(f"sms,{nu},{gamma},{plain:.4g},{scaled:.4g},{plain / scaled:.3f},{lowest:.3g}")


if __name__ == "__main__":
    main()
