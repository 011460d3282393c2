"""Anderson mixing of the settled Coulomb cycle on MPI ranks: the serial SettledAnderson
(steps/settled_anderson.hpp says why and what keeps it safe) with its dot products as exact sums
over the owned dofs, so the mixing weights are the same bits on every rank and every rank count.

The vectors span every local dof, ghosts included: the mixed iterate is formed entry by entry from
values a ghost shares with its owner and weights every rank shares, so a ghost row of the mixed
iterate is its owner's, bit for bit, without an exchange."""
from __future__ import annotations

from typing import Callable, List, Optional, Tuple

import numpy as np

from .exchange import exact_dots

# the cycles mixed: the serial SettledAnderson::kDepth (a fixed internal choice; 2-5 behave alike)
DEPTH = 3


class DistributedAnderson:
    """The history of the last cycles x -> G(x) of one contact state and the mixed iterate."""

    def __init__(self, comm, owned_nodes: np.ndarray, d: int):
        self.comm, self.owned, self.d = comm, np.ascontiguousarray(owned_nodes, np.uint8), d
        self.reset()

    def reset(self) -> None:
        """Forget the history and the last iterate (a new contact state, or a step that did not help)."""
        self.pairs: List[Tuple[np.ndarray, np.ndarray]] = []  # (dx, dg), oldest first
        self.gram: List[List[float]] = []  # dg_a . dg_b
        self.rhs: List[float] = []
        self.last: Optional[Tuple[np.ndarray, np.ndarray]] = None  # (x', G(x'))
        self.last_gnorm = 0.0
        self.accelerated = False

    def memory_bytes(self) -> int:
        """The bytes of the history and the last iterate held now."""
        held = [v for pair in self.pairs for v in pair] + (list(self.last) if self.last is not None else [])
        return int(sum(v.nbytes for v in held))

    def _dots(self, pairs) -> List[float]:
        """a . b over the owned dofs for each pair (flat vectors), one collective for all."""
        d = self.d
        return exact_dots([(a.reshape(-1, d), b.reshape(-1, d)) for a, b in pairs], self.comm, self.owned)

    def step(self, x: np.ndarray, gx: np.ndarray, admit: Callable[[np.ndarray, np.ndarray], bool],
             restart: bool = False) -> bool:
        """x: the iterate before the cycle, gx: its result G(x) (flat, every local dof), replaced in
        place by the mixed iterate where `admit(candidate, plain)` accepts it (it may adjust the
        candidate). Returns whether it did. restart: forget the history first."""
        if restart:  # this cycle's pair spans two contact states: the history starts with the next one
            self.reset()
            return False
        g = gx - x
        if self.last is not None:
            xl, gl = self.last
            dx, dg = x - xl, g - (gl - xl)
            # every dot this step may need, in one collective: |g|^2, the new Gram row, the new rhs
            k = len(self.pairs)
            dots = self._dots([(g, g)] + [(dg, old_dg) for _, old_dg in self.pairs] + [(dg, dg)] +
                              [(old_dg, g) for _, old_dg in self.pairs] + [(dg, g)])
            gnorm, row, rhs = dots[0], dots[1:k + 2], dots[k + 2:]
            if self.accelerated and not gnorm < self.last_gnorm:  # the mixed step did not help: start over
                self.reset()
                self.last = (x.copy(), gx.copy())
            else:
                for i, v in enumerate(row[:-1]):
                    self.gram[i].append(v)
                self.gram.append(row)
                self.pairs.append((dx, dg))
                self.rhs = rhs
                self.last = None
        else:
            gnorm = self._dots([(g, g)])[0]
            self.last = (x.copy(), gx.copy())
        self.last_gnorm = gnorm
        self.accelerated = False
        if self.last is not None:  # no history, or it was just restarted: x, G(x) kept
            return False
        if gnorm == 0:
            self.last = (x.copy(), gx.copy())
            return False
        # gamma = argmin |g - dG gamma| by the normal equations, least squares with a rank cut-off
        # (nearly dependent columns get no weight), the same bits on every rank
        M, rhs = np.array(self.gram), np.array(self.rhs)
        gamma = np.linalg.lstsq(M, rhs, rcond=None)[0]
        if not np.all(np.isfinite(gamma)):
            self.last = (x.copy(), gx.copy())
            return False
        s = np.zeros_like(gx)
        for c, (dx_i, dg_i) in zip(gamma, self.pairs):
            s += c * (dx_i + dg_i)
        plain = gx.copy()
        self.last = (x.copy(), plain)
        if len(self.pairs) == DEPTH:  # the next step would drop the oldest pair: drop it now
            self.pairs.pop(0)
            self.gram = [r[1:] for r in self.gram[1:]]
        gx -= s
        if not admit(gx, plain):
            gx[:] = plain
            return False
        self.accelerated = True
        return True
