"""A thin layer over Clarabel's native API: stack constraint blocks, solve, report the status."""

from __future__ import annotations

from dataclasses import dataclass, field

import clarabel
import numpy as np
import scipy.sparse as sp

_OK = {"Solved", "AlmostSolved"}


@dataclass
class ConicProblem:
    """``min ½ xᵀ P x + qᵀ x  s.t.  A x + s = b, s ∈ K`` built block by block (dense rows, small problems)."""

    n: int
    p_diag: np.ndarray = field(init=False)
    q: np.ndarray = field(init=False)
    _rows: list[tuple[str, np.ndarray, np.ndarray, int]] = field(default_factory=list, init=False)

    def __post_init__(self) -> None:
        self.p_diag = np.zeros(self.n)
        self.q = np.zeros(self.n)

    def zero(self, a: np.ndarray, b: np.ndarray) -> None:
        """Equality rows ``a x = b``."""
        self._rows.append(("zero", np.atleast_2d(a), np.atleast_1d(b), 0))

    def leq(self, a: np.ndarray, b: np.ndarray) -> None:
        """Inequality rows ``a x ≤ b``."""
        a, b = np.atleast_2d(a), np.atleast_1d(b)
        if len(b):
            self._rows.append(("nonneg", a, b, 0))

    def soc(self, a: np.ndarray, b: np.ndarray) -> None:
        """One second-order cone: ``(b − a x) ∈ SOC`` (first entry ≥ norm of the rest)."""
        self._rows.append(("soc", np.atleast_2d(a), np.atleast_1d(b), len(b)))

    def solve(self, settings: clarabel.DefaultSettings | None = None) -> tuple[np.ndarray | None, str]:
        """Solve; returns (x or None, status name). Zero rows go first, then inequalities, then cones."""
        order = {"zero": 0, "nonneg": 1, "soc": 2}
        blocks = sorted(self._rows, key=lambda r: order[r[0]])
        a = np.vstack([blk[1] for blk in blocks])
        b = np.concatenate([blk[2] for blk in blocks])
        cones: list[object] = []
        for kind in ("zero", "nonneg"):
            count = sum(len(blk[2]) for blk in blocks if blk[0] == kind)
            if count:
                cones.append(clarabel.ZeroConeT(count) if kind == "zero" else clarabel.NonnegativeConeT(count))
        cones += [clarabel.SecondOrderConeT(blk[3]) for blk in blocks if blk[0] == "soc"]
        if settings is None:
            settings = default_settings()
        n = self.n
        p_mat = sp.csc_matrix((self.p_diag, _arange32(n), _arange32(n + 1)), shape=(n, n))
        solver = clarabel.DefaultSolver(p_mat, self.q, dense_to_csc(a), b, cones, settings)
        sol = solver.solve()
        status = str(sol.status).split(".")[-1]
        if status not in _OK:
            return None, status
        return np.asarray(sol.x), status


def dense_to_csc(a: np.ndarray) -> sp.csc_matrix:
    """The CSC matrix of a dense (r, c) array's nonzeros, built directly: the same matrix as ``sp.csc_matrix(a)``
    (sorted row indices, no explicit zeros) without its COO round trip (it cost as much as the solve)."""
    flat = a.ravel(order="F")  # column-major: by column, rows ascending within each
    idx = np.flatnonzero(flat)
    col, row = np.divmod(idx, a.shape[0])
    indptr = np.searchsorted(col, _arange32(a.shape[1] + 1))
    # int32 indices: scipy converts int64 ones on every construction (30 µs of a 50 µs build)
    return sp.csc_matrix((flat[idx], row.astype(np.int32), indptr.astype(np.int32)), shape=a.shape)


_ARANGE32 = np.arange(4096, dtype=np.int32)
_ARANGE32.setflags(write=False)  # shared by the matrices built from it: nothing may sort or edit it in place


def _arange32(n: int) -> np.ndarray:
    """``np.arange(n)`` as int32 (a view of one array for the small sizes of these problems)."""
    return _ARANGE32[:n] if n <= len(_ARANGE32) else np.arange(n, dtype=np.int32)


def default_settings() -> clarabel.DefaultSettings:
    """Quiet settings with a bounded iteration count."""
    s = clarabel.DefaultSettings()
    s.verbose = False
    s.max_iter = 80
    return s
