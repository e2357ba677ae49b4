"""Which geom pairs MuJoCo's collision detection tests in a model: the one definition of "pairs
MuJoCo would test" that the checks and the retargeter share.

MuJoCo (``mj_collision``) tests two geoms when one of these holds, in this order:

* they form an explicit ``<contact><pair>`` (tested whatever the rules below say);
* they are on different weld bodies (bodies rigidly attached to each other, ``body_weldid``,
  count as one), and
* unless the model disables ``filterparent``, neither weld body is the other's parent weld body
  (the world's weld body, 0, is exempt from this rule), and
* their bodies are not an explicit ``<contact><exclude>`` pair, and
* their bitmasks match: ``contype1 & conaffinity2 or contype2 & conaffinity1``.

Nothing else is excluded: a body two hinges below another, or below a geometry-less link, is
tested like any other (a "nearest collidable ancestor" rule drops pairs MuJoCo does test).
"""

from __future__ import annotations

import mujoco
import numpy as np


def filterparent_enabled(model: mujoco.MjModel) -> bool:
    return not model.opt.disableflags & int(mujoco.mjtDisableBit.mjDSBL_FILTERPARENT)


def excluded_body_pairs(model: mujoco.MjModel) -> set[tuple[int, int]]:
    """The MJCF's ``<exclude>`` body pairs (a <= b)."""
    out = set()
    for s in model.exclude_signature:
        a, b = int(s) >> 16, int(s) & 0xFFFF
        out.add((min(a, b), max(a, b)))
    return out


def tested_geom_pairs(model: mujoco.MjModel) -> np.ndarray:
    """(ngeom, ngeom) symmetric bool: True where MuJoCo's collision detection tests the geom pair
    (module docstring). Contacts are not disabled here (``mjDSBL_CONTACT`` is the caller's business)."""
    body = model.geom_bodyid.astype(int)
    weld = model.body_weldid.astype(int)[body]
    pweld = model.body_weldid.astype(int)[model.body_parentid.astype(int)[weld]]
    ct, ca = model.geom_contype.astype(np.int64), model.geom_conaffinity.astype(np.int64)
    ok = ((ct[:, None] & ca[None, :]) != 0) | ((ct[None, :] & ca[:, None]) != 0)
    ok &= weld[:, None] != weld[None, :]
    if filterparent_enabled(model):
        nonworld = (weld[:, None] != 0) & (weld[None, :] != 0)
        ok &= ~(nonworld & ((weld[:, None] == pweld[None, :]) | (weld[None, :] == pweld[:, None])))
    excluded = np.zeros((model.nbody, model.nbody), dtype=bool)
    for a, b in excluded_body_pairs(model):
        excluded[a, b] = excluded[b, a] = True
    ok &= ~excluded[body[:, None], body[None, :]]
    for g1, g2 in zip(model.pair_geom1, model.pair_geom2):
        ok[g1, g2] = ok[g2, g1] = True
    np.fill_diagonal(ok, False)
    return ok


def tested_body_pairs(model: mujoco.MjModel, include_world: bool = False) -> frozenset[tuple[int, int]]:
    """Body pairs (a < b) with at least one geom pair MuJoCo tests (pairs with the world body
    left out unless ``include_world``)."""
    g1, g2 = np.nonzero(np.triu(tested_geom_pairs(model), 1))
    b1, b2 = model.geom_bodyid[g1], model.geom_bodyid[g2]
    lo, hi = np.minimum(b1, b2), np.maximum(b1, b2)
    keep = (lo != hi) & ((lo != 0) | include_world)
    return frozenset(zip(lo[keep].tolist(), hi[keep].tolist()))
