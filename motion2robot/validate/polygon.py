"""Signed distance from points to the convex hull of small point sets, vectorised over frames.

For P <= ~10 points per frame the hull edges are found by brute force: the ordered pair (i, j)
is a counter-clockwise hull edge when every other active point lies on its left. The signed
distance is positive inside (distance to the nearest edge) and negative outside (minus the
distance to the nearest edge segment); with fewer than 3 non-collinear points the hull is a
segment or a point and every query point is outside (or on it, 0). Frames without any active
point give NaN.
"""

from __future__ import annotations

import functools

import numpy as np

_EPS = 1e-9


@functools.lru_cache(maxsize=4)
def _pairs(P: int) -> tuple[np.ndarray, np.ndarray]:
    i, j = np.meshgrid(np.arange(P), np.arange(P), indexing="ij")
    keep = i != j
    return i[keep], j[keep]


def signed_distance(points: np.ndarray, active: np.ndarray, query: np.ndarray) -> np.ndarray:
    """points (T, P, 2), active (T, P) bool, query (T, 2) or (T, Q, 2) -> (T,) or (T, Q) metres
    (NaN for frames without an active point and for NaN queries)."""
    single = query.ndim == 2
    q = query[:, None, :] if single else query
    _T, P, _ = points.shape
    i, j = _pairs(P)
    px, py = points[..., 0], points[..., 1]
    ax, ay = px[:, i], py[:, i]  # (T, E)
    ex, ey = px[:, j] - ax, py[:, j] - ay
    length = np.sqrt(ex * ex + ey * ey)
    # cross of each edge with every point: (T, E, P)
    cross = ex[..., None] * (py[:, None, :] - ay[..., None]) - ey[..., None] * (px[:, None, :] - ax[..., None])
    tol = 1e-7 * np.maximum(length, _EPS)[..., None]
    inactive = ~active[:, None, :]
    edge = active[:, i] & active[:, j] & (length > _EPS) & ((cross >= -tol) | inactive).all(axis=-1)
    # a genuine polygon needs an edge with some active point strictly on its left
    area = (edge & ((cross > tol) & ~inactive).any(axis=-1)).any(axis=1)
    any_edge = edge.any(axis=1)
    safe_len = np.maximum(length, _EPS)
    # queries against the candidate edges: (T, Q, E)
    qx = q[..., 0][..., None] - ax[:, None, :]
    qy = q[..., 1][..., None] - ay[:, None, :]
    exq, eyq, lq = ex[:, None, :], ey[:, None, :], safe_len[:, None, :]
    line = (exq * qy - eyq * qx) / lq
    s = np.clip((qx * exq + qy * eyq) / (lq * lq), 0.0, 1.0)
    dx, dy = qx - s * exq, qy - s * eyq
    seg = np.sqrt(dx * dx + dy * dy)
    e = edge[:, None, :]
    inside = (any_edge & area)[:, None] & np.where(e, line >= 0, True).all(axis=-1)
    d_in = np.where(e, line, np.inf).min(axis=-1)
    d_out = np.where(e, seg, np.inf).min(axis=-1)
    n_act = active.sum(axis=1)
    centre = np.where(active[..., None], points, 0.0).sum(axis=1) / np.maximum(n_act, 1)[:, None]  # one point
    d_pt = np.linalg.norm(q - centre[:, None, :], axis=-1)
    d_out = np.where(any_edge[:, None], d_out, d_pt)
    out = np.where(inside, d_in, -d_out)
    out[n_act == 0] = np.nan
    out[np.isnan(q).any(axis=-1)] = np.nan
    return out[:, 0] if single else out
