"""Smooth interpolation over a triangle mesh: the cotangent Laplacian and biharmonic fill-in.

Given values on some vertices (the constrained set) a biharmonic field is the smoothest surface function
through them: it minimises the integrated squared Laplacian ``x^T L^T M^-1 L x`` (``L`` the cotangent
Laplacian, ``M`` the lumped vertex areas; Jacobson et al., "Mixed finite elements for variational surface
modeling", SGP 2010, and libigl's ``harmonic(k=2)``). It is linear in the constrained values and, unlike the
harmonic (``k=1``) field, has no cusp at an isolated constrained vertex, so a point pulled by a feature
point makes a round bump, not a tent. Mesh holes (the mouth slit, the eye openings) are natural boundaries:
the field only couples vertices joined by triangles.

Cotangent weights are clipped to ``[0, COT_CLIP]`` so slivers and obtuse triangles (common around lids and
lip corners of scanned heads) cannot make the system indefinite.

scipy's sparse LU is used when installed; otherwise a Jacobi-preconditioned conjugate gradient in numpy
solves the same system (slower, same result to its tolerance).

>>> v = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [0, 1, 0], [1, 1, 0], [2, 1, 0]], float)
>>> f = np.array([[0, 1, 4], [0, 4, 3], [1, 2, 5], [1, 5, 4]])
>>> x = biharmonic_fill(v, f, np.array([0, 3, 2, 5]), np.array([[0.0], [0.0], [1.0], [1.0]]))
>>> np.round(x[[1, 4], 0], 2).tolist()   # halfway, up to the strip's diagonal
[0.52, 0.48]
"""

from __future__ import annotations

import numpy as np

from mien.errors import InvalidValueError
from mien.extras import available

__all__ = ["COT_CLIP", "BiharmonicSystem", "biharmonic_fill", "cotan_laplacian"]

COT_CLIP = 50.0
"""Largest cotangent weight kept (a 1.1 degree angle); larger ones come from slivers."""


def cotan_laplacian(
    vertices: np.ndarray, faces: np.ndarray
) -> tuple[tuple[np.ndarray, np.ndarray, np.ndarray], np.ndarray]:
    """The (n, n) cotangent Laplacian (sparse COO triplets, rows summing to 0) and (n,) lumped areas (m^2).

    Returns ``((rows, cols, values), areas)``: off-diagonal ``(i, j, w_ij)`` with ``w_ij`` half the sum of the
    clipped cotangents opposite edge ``ij``, and the diagonal ``-sum_j w_ij``. ``areas`` is a third of the
    area of the triangles around each vertex (floored so isolated vertices stay finite).
    """
    p = np.asarray(vertices, dtype=np.float64)
    tri = np.asarray(faces, dtype=np.int64)
    if p.ndim != 2 or p.shape[1] != 3 or tri.ndim != 2 or tri.shape[1] != 3:
        raise InvalidValueError("mesh", (p.shape, tri.shape), "(n, 3) vertices and (m, 3) triangles")
    rows, cols, vals = [], [], []
    for k in range(3):
        i, j, o = tri[:, (k + 1) % 3], tri[:, (k + 2) % 3], tri[:, k]
        a, b = p[i] - p[o], p[j] - p[o]
        cross = np.linalg.norm(np.cross(a, b), axis=1)
        cot = np.einsum("ij,ij->i", a, b) / np.maximum(cross, 1e-18)
        w = 0.5 * np.clip(cot, 0.0, COT_CLIP)
        rows += [i, j]
        cols += [j, i]
        vals += [w, w]
    r, c, w = np.concatenate(rows), np.concatenate(cols), np.concatenate(vals)
    n = len(p)
    diag = np.zeros(n)
    np.add.at(diag, r, w)
    r = np.concatenate([r, np.arange(n)])
    c = np.concatenate([c, np.arange(n)])
    w = np.concatenate([w, -diag])
    area = 0.5 * np.linalg.norm(np.cross(p[tri[:, 1]] - p[tri[:, 0]], p[tri[:, 2]] - p[tri[:, 0]]), axis=1)
    areas = np.zeros(n)
    for k in range(3):
        np.add.at(areas, tri[:, k], area / 3.0)
    floor = max(float(np.median(areas[areas > 0])) * 1e-3, 1e-12) if np.any(areas > 0) else 1e-12
    return (r, c, w), np.maximum(areas, floor)


class _Csr:
    """A minimal CSR matrix in numpy (products and slicing), for the no-scipy path."""

    def __init__(self, rows: np.ndarray, cols: np.ndarray, vals: np.ndarray, n: int) -> None:
        order = np.lexsort((cols, rows))
        rows, cols, vals = rows[order], cols[order], vals[order]
        key = rows * n + cols
        first = np.concatenate([[True], key[1:] != key[:-1]])
        starts = np.flatnonzero(first)
        self.rows, self.cols = rows[starts], cols[starts]
        self.vals = np.add.reduceat(vals, starts) if vals.size else vals
        self.n = n

    def matvec(self, x: np.ndarray) -> np.ndarray:
        out = np.zeros((self.n, *x.shape[1:]))
        np.add.at(out, self.rows, self.vals.reshape((-1,) + (1,) * (x.ndim - 1)) * x[self.cols])
        return out


def _solve_numpy(lmat: _Csr, lt: _Csr, inv_area: np.ndarray, free: np.ndarray, rhs: np.ndarray) -> np.ndarray:
    """Jacobi-preconditioned CG on ``(L^T M^-1 L)_ff x = rhs`` with products through ``L`` and ``L^T`` (no scipy)."""
    n = lmat.n

    def apply(xf: np.ndarray) -> np.ndarray:
        full = np.zeros((n, *xf.shape[1:]))
        full[free] = xf
        y = lmat.matvec(full) * inv_area.reshape((-1,) + (1,) * (xf.ndim - 1))
        return lt.matvec(y)[free]

    diag = np.zeros(n)
    np.add.at(diag, lmat.cols, lmat.vals**2 * inv_area[lmat.rows])
    pre = 1.0 / np.maximum(diag[free], 1e-30)
    x = np.zeros_like(rhs)
    res = rhs - apply(x)
    z = res * pre[:, None]
    d = z.copy()
    rz = np.einsum("ij,ij->j", res, z)
    norm0 = np.linalg.norm(rhs, axis=0) + 1e-300
    for _ in range(20 * len(free) + 100):
        if np.all(np.linalg.norm(res, axis=0) <= 1e-10 * norm0):
            break
        q = apply(d)
        alpha = rz / np.maximum(np.einsum("ij,ij->j", d, q), 1e-300)
        x += alpha * d
        res -= alpha * q
        z = res * pre[:, None]
        rz_new = np.einsum("ij,ij->j", res, z)
        d = z + (rz_new / np.maximum(rz, 1e-300)) * d
        rz = rz_new
    return x


class BiharmonicSystem:
    """The biharmonic energy ``L^T M^-1 L`` of one mesh, built once and solved for many constraint sets."""

    def __init__(self, vertices: np.ndarray, faces: np.ndarray) -> None:
        p = np.asarray(vertices, dtype=np.float64)
        self.n_vertices = len(p)
        """Number of vertices."""
        self._lap, areas = cotan_laplacian(p, faces)
        self._inv_area = 1.0 / areas
        self._q: object | None = None
        self._csr: tuple[_Csr, _Csr] | None = None
        r_, c_, w_ = self._lap
        if not available("scipy.sparse"):
            return
        from scipy.sparse import coo_matrix, diags

        lmat = coo_matrix((w_, (r_, c_)), shape=(self.n_vertices, self.n_vertices)).tocsr()
        self._q = (lmat.T @ diags(self._inv_area) @ lmat).tocsr()

    def _numpy_operators(self) -> tuple[_Csr, _Csr]:
        """``(L, L^T)`` for the no-scipy path, built on first use and kept."""
        if self._csr is None:
            r_, c_, w_ = self._lap
            self._csr = (_Csr(r_, c_, w_, self.n_vertices), _Csr(c_, r_, w_, self.n_vertices))
        return self._csr

    def fill(self, fixed: np.ndarray, values: np.ndarray, free: np.ndarray | None = None) -> np.ndarray:
        """(n, k) float64 fields equal to ``values`` (len(fixed), k) on vertex ids ``fixed``, smoothest elsewhere.

        ``free`` (vertex ids) are solved for; default every vertex not in ``fixed``. Vertices neither fixed
        nor free are held at 0 (the far field).
        """
        n = self.n_vertices
        fixed = np.asarray(fixed, dtype=np.int64)
        vals = np.asarray(values, dtype=np.float64)
        if vals.ndim == 1:
            vals = vals[:, None]
        if vals.shape[0] != fixed.size or (fixed.size and (fixed.min() < 0 or fixed.max() >= n)):
            raise InvalidValueError(
                "fixed/values", (fixed.shape, vals.shape), f"(k,) vertex ids < {n} and (k, m) values"
            )
        known = np.zeros((n, vals.shape[1]))
        known[fixed] = vals
        is_fixed = np.zeros(n, bool)
        is_fixed[fixed] = True
        free = np.flatnonzero(~is_fixed) if free is None else np.setdiff1d(np.asarray(free, np.int64), fixed)
        out = known.copy()
        if free.size == 0:
            return out
        if self._q is None:
            lmat, lt = self._numpy_operators()
            rhs = -lt.matvec(lmat.matvec(known) * self._inv_area[:, None])[free]
            out[free] = _solve_numpy(lmat, lt, self._inv_area, free, rhs)
            return out
        from scipy.sparse.linalg import splu

        q = self._q
        rows = q[free]  # type: ignore[index]
        out[free] = splu(rows[:, free].tocsc()).solve(np.asarray(rows @ known))
        out[free] *= -1.0
        return out


def biharmonic_fill(
    vertices: np.ndarray,
    faces: np.ndarray,
    fixed: np.ndarray,
    values: np.ndarray,
    free: np.ndarray | None = None,
) -> np.ndarray:
    """(n, k) float64 biharmonic fields equal to ``values`` (len(fixed), k) on vertex ids ``fixed``.

    One-shot :meth:`BiharmonicSystem.fill`: ``vertices`` (n, 3) metres, ``faces`` (m, 3) vertex ids.
    """
    return BiharmonicSystem(vertices, faces).fill(fixed, values, free)
