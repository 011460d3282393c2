"""The textbook Anderson mixing of settled cycles, computed independently with numpy (history lists of
dx, dg, the oldest dropped at depth 3, a restart when the mixed step did not lower |G(x) - x|, a
refused candidate leaving G(x)), and the affine maps the core's mixing is tested on (the serial
SettledAnderson and the distributed NodeAnderson)."""
import numpy as np

DEPTH = 3


def apply(M, x, c):
    """diag(M, M, ...) x + c, as the core's test hook applies it"""
    return (x.reshape(-1, M.shape[0]) @ M.T).ravel() + c


def textbook(M, c, x0, steps, refuse_every=0):
    dx, dg = [], []
    last = None
    accelerated, last_gnorm, calls = False, 0.0, 0
    x = x0.copy()
    out, mixed = [], []
    for _ in range(steps):
        gx = apply(M, x, c)
        g = gx - x
        gnorm = g @ g
        if last is not None and accelerated and not gnorm < last_gnorm:
            dx, dg, last = [], [], None
        if last is not None:
            if len(dx) == DEPTH:
                dx.pop(0), dg.pop(0)
            dx.append(x - last[0])
            dg.append(g - last[1])
        last, last_gnorm, accelerated = (x.copy(), g.copy()), gnorm, False
        if dx and gnorm != 0:
            G = np.array(dg)
            gamma = np.linalg.lstsq(G @ G.T, G @ g, rcond=None)[0]
            cand = gx - sum(gm * (a + b) for gm, a, b in zip(gamma, dx, dg))
            calls += 1
            if refuse_every <= 0 or calls % refuse_every != 0:
                gx, accelerated = cand, True
        x = gx
        out.append(x.copy())
        mixed.append(accelerated)
    return np.array(out), np.array(mixed)


def affine_map(m, reps, seed):
    """a symmetric contraction on blocks of m entries (spectrum in [0.18, 0.9]), repeated reps times"""
    rng = np.random.default_rng(seed)
    Q, _ = np.linalg.qr(rng.standard_normal((m, m)))
    M = Q @ np.diag(0.9 * rng.uniform(0.2, 1.0, m)) @ Q.T
    return M, rng.standard_normal(m * reps), rng.standard_normal(m * reps)
