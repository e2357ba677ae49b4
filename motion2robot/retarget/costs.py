"""The names, kinds and weights of the retargeting problem's terms, from their registry.

Every term (name, default weight, hard or soft, residual) is declared in one module of
:mod:`motion2robot.retarget.terms` and registered there in one line; this module derives the
term lists and the :class:`Weights` dataclass from that registry, adding the solver's temporal
weights. Cost = sum over terms of ``weight * ||residual||^2``. Hard constraints (contact, floor,
balance, self-collision) are stiff penalty terms in the solve and are finished by the exact
projection of :func:`motion2robot.retarget.solver.correct`.
"""

from __future__ import annotations

from dataclasses import asdict, field, make_dataclass

from motion2robot.retarget.terms import TERMS

#: Terms evaluated by the compiled per-frame function, in the order of its weight vector
#: (the registry of :mod:`motion2robot.retarget.terms`: one module per term).
FRAME_TERMS: tuple[str, ...] = tuple(t.name for t in TERMS)

#: The terms that are hard constraints (residual zero when satisfied), corrected exactly at the end.
HARD_TERMS: tuple[str, ...] = tuple(t.name for t in TERMS if t.hard)


#: Temporal weights, applied between neighbouring frames by the solver (per-frame units: rad, m),
#: and the LM damping. acceleration: 20x the first tuning: at 5e-3 the LM's few iterations left
#: single-frame second differences of 0.2 rad (100 rad/s^2 at 20 fps, the servo's whole torque on
#: its rotor) in the legs of an MDM throw; 0.1 removes them and tracks as closely (keypoint error
#: 50.8 -> 44 mm). damping: added to the Gauss-Newton normal matrix.
SOLVER_WEIGHTS: tuple[tuple[str, float], ...] = (("velocity", 2e-3), ("acceleration", 0.1), ("damping", 1e-6))


def _frame_vector(self) -> list[float]:
    """Weights of :data:`FRAME_TERMS` in order (the compiled function's ``w`` input)."""
    return [float(getattr(self, t)) for t in FRAME_TERMS]


def _as_dict(self) -> dict[str, float]:
    return asdict(self)


#: Weights of every term (dimensionless; defaults from the terms' declarations) and of the
#: solver's temporal terms: a frozen dataclass with one float field per name.
Weights = make_dataclass(
    "Weights",
    [(t.name, float, field(default=float(t.weight))) for t in TERMS]
    + [(name, float, field(default=value)) for name, value in SOLVER_WEIGHTS],
    frozen=True,
    namespace={"__module__": __name__, "frame_vector": _frame_vector, "as_dict": _as_dict,
               "__doc__": "Weights of every cost term and of the solver's temporal terms (dimensionless)."},
)
