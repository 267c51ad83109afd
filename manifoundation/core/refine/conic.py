"""A thin layer over Clarabel's native API: stack constraint blocks, solve, report the status.

Blocks are given dense (small problems) or as `Rows`, the nonzeros of a block placed at its columns: the SCP step
has ~200 variables and ~300 rows, most of them identity blocks, and building them dense and scanning them for
their nonzeros cost more than Clarabel's setup and solve together.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import clarabel
import numpy as np
import scipy.sparse as sp

_OK = {"Solved", "AlmostSolved"}


@dataclass(frozen=True)
class Rows:
    """A block of ``count`` constraint rows by its nonzeros: row (within the block), column and value (T,) each."""

    count: int
    row: np.ndarray
    col: np.ndarray
    val: np.ndarray

    @classmethod
    def dense(cls, a: np.ndarray, col: int = 0) -> Rows:
        """The nonzeros of a dense block (r, c), its first column at ``col``."""
        a = np.atleast_2d(a)
        r, c = np.nonzero(a)
        return cls(a.shape[0], r, c + col, a[r, c])

    @classmethod
    def eye(cls, count: int, col: int, scale: float = 1.0) -> Rows:
        """``scale`` × the identity (count, count), its first column at ``col``."""
        i = _ARANGE64[:count] if count <= len(_ARANGE64) else np.arange(count)
        return cls(count, i, i + col, np.full(count, scale))

    @classmethod
    def beside(cls, *blocks: Rows) -> Rows:
        """Blocks of the same rows side by side (each with its own columns already)."""
        return cls(blocks[0].count, np.concatenate([b.row for b in blocks]), np.concatenate([b.col for b in blocks]),
                   np.concatenate([b.val for b in blocks]))  # fmt: skip


@dataclass
class ConicProblem:
    """``min ½ xᵀ P x + qᵀ x  s.t.  A x + s = b, s ∈ K`` built block by block (dense rows, small problems)."""

    n: int
    p_diag: np.ndarray = field(init=False)
    q: np.ndarray = field(init=False)
    _rows: list[tuple[str, Rows, np.ndarray, int]] = field(default_factory=list, init=False)

    def __post_init__(self) -> None:
        self.p_diag = np.zeros(self.n)
        self.q = np.zeros(self.n)

    def zero(self, a: np.ndarray | Rows, b: np.ndarray) -> None:
        """Equality rows ``a x = b``."""
        self._rows.append(("zero", _as_rows(a), np.atleast_1d(b), 0))

    def leq(self, a: np.ndarray | Rows, b: np.ndarray) -> None:
        """Inequality rows ``a x ≤ b``."""
        b = np.atleast_1d(b)
        if len(b):
            self._rows.append(("nonneg", _as_rows(a), b, 0))

    def soc(self, a: np.ndarray | Rows, b: np.ndarray) -> None:
        """One second-order cone: ``(b − a x) ∈ SOC`` (first entry ≥ norm of the rest)."""
        self._rows.append(("soc", _as_rows(a), np.atleast_1d(b), len(b)))

    def constraints(self) -> tuple[sp.csc_matrix, np.ndarray, list[object]]:
        """``A`` (CSC, sorted row indices, no explicit zeros), ``b`` and the cones: zero rows first, then
        inequalities, then the second-order cones, each kind in the order given."""
        order = {"zero": 0, "nonneg": 1, "soc": 2}
        blocks = sorted(self._rows, key=lambda r: order[r[0]])
        b = np.concatenate([blk[2] for blk in blocks])
        cones: list[object] = []
        for kind in ("zero", "nonneg"):
            count = sum(len(blk[2]) for blk in blocks if blk[0] == kind)
            if count:
                cones.append(clarabel.ZeroConeT(count) if kind == "zero" else clarabel.NonnegativeConeT(count))
        cones += [clarabel.SecondOrderConeT(blk[3]) for blk in blocks if blk[0] == "soc"]
        return _stack([blk[1] for blk in blocks], self.n), b, cones

    def solve(self, settings: clarabel.DefaultSettings | None = None) -> tuple[np.ndarray | None, str]:
        """Solve; returns (x or None, status name)."""
        a, b, cones = self.constraints()
        if settings is None:
            settings = default_settings()
        n = self.n
        p_mat = sp.csc_matrix((self.p_diag, _arange32(n), _arange32(n + 1)), shape=(n, n))
        solver = clarabel.DefaultSolver(p_mat, self.q, a, b, cones, settings)
        sol = solver.solve()
        status = str(sol.status).split(".")[-1]
        if status not in _OK:
            return None, status
        return np.asarray(sol.x), status


def _as_rows(a: np.ndarray | Rows) -> Rows:
    return a if isinstance(a, Rows) else Rows.dense(a)


def _stack(blocks: list[Rows], n: int) -> sp.csc_matrix:
    """The blocks one below the other (n columns) as a CSC matrix with sorted row indices and no explicit zeros:
    ``sp.csc_matrix`` of the dense stack, from the nonzeros alone."""
    starts = np.cumsum([0] + [blk.count for blk in blocks])
    row = np.concatenate([blk.row + start for blk, start in zip(blocks, starts, strict=False)])
    col = np.concatenate([blk.col for blk in blocks])
    val = np.concatenate([blk.val for blk in blocks])
    nonzero = val != 0
    row, col, val = row[nonzero], col[nonzero], val[nonzero]
    order = np.lexsort((row, col))  # by column, rows ascending within each
    indptr = np.searchsorted(col[order], _arange32(n + 1))
    # int32 indices: scipy converts int64 ones on every construction (30 µs of a 50 µs build)
    return sp.csc_matrix((val[order], row[order].astype(np.int32), indptr.astype(np.int32)),
                         shape=(int(starts[-1]), n))  # fmt: skip


_ARANGE32 = np.arange(4096, dtype=np.int32)
_ARANGE32.setflags(write=False)  # shared by the matrices built from it: nothing may sort or edit it in place
_ARANGE64 = np.arange(4096)
_ARANGE64.setflags(write=False)


def _arange32(n: int) -> np.ndarray:
    """``np.arange(n)`` as int32 (a view of one array for the small sizes of these problems)."""
    return _ARANGE32[:n] if n <= len(_ARANGE32) else np.arange(n, dtype=np.int32)


def default_settings() -> clarabel.DefaultSettings:
    """Quiet settings with a bounded iteration count."""
    s = clarabel.DefaultSettings()
    s.verbose = False
    s.max_iter = 80
    return s
