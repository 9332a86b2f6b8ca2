"""Exact intervals of the gear ratio N that meet every requirement (docs/sizing.md).

For a chosen damper and gearbox, each requirement's margin (smallest over the
requirement temperatures) is a continuous function of N: the deployment time, the end
speed and the torques are smooth in N through BECD = BT * N**2 and FECD = FT * N
(Eq. 3-4), and the margins of :mod:`ecdsim.sizing.requirements` stay finite and
continuous across the stall boundary (where the time margin tends to -1). The procedure:

1. scan N on a geometric grid over the requirement's ``ratio_range`` (one vectorised
   evaluation of all grid points);
2. wherever a requirement's margin changes sign between two grid points, find the root
   with :func:`scipy.optimize.brentq` on the exact solution (not on the grid);
3. each requirement's feasible set is the union of intervals between its roots; the
   answer is the intersection over requirements.

The gearbox keeps its catalogued BG (value or fraction of BD) and FG at every N: a custom
ratio is assumed to be built like the catalogued ones. A feasible window narrower than
the grid spacing could be missed; the grid has ``n_grid`` points (spacing ratio
``(high/low)**(1/(n_grid-1))``).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from ecdsim._types import FloatArray, as_float
from ecdsim.model import Ecd, Load
from ecdsim.sizing.catalogue import DamperEntry, GearboxEntry
from ecdsim.sizing.requirements import Requirements
from ecdsim.sizing.search import Evaluation, Limits, evaluate

DEFAULT_GRID = 400
# brentq stops when the bracket is below XTOL + RTOL * |N|: far below the 1e-6 relative
# steps a user (or a test) needs to step just inside or outside an interval end.
XTOL = 1e-12
RTOL = 1e-12
# Margins are clipped to +-CLIP for root finding only (an infinite margin, e.g. a stall
# margin where the friction is 0, has no root and must not break the interpolation).
CLIP = 1e3


# The "limited by" of an interval end that is only the end of the scanned range.
SCAN_RANGE = "scan range"


@dataclass(frozen=True)
class Interval:
    """A closed interval of gear ratios [low, high].

    Attributes
    ----------
    low : smallest ratio [-]
    high : largest ratio [-]
    low_limited_by : check active at ``low`` ("scan range" if the scan's end)
    high_limited_by : check active at ``high`` ("scan range" if the scan's end)
    """

    low: float
    high: float
    low_limited_by: str
    high_limited_by: str

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form."""
        return {
            "low": self.low,
            "high": self.high,
            "low_limited_by": self.low_limited_by,
            "high_limited_by": self.high_limited_by,
        }


@dataclass(frozen=True)
class RatioIntervals:
    """The gear ratios that meet every requirement, for one damper and gearbox.

    Attributes
    ----------
    damper : damper name
    gearbox : gearbox name
    ratio_range : the scanned range (low, high) [-]
    n_grid : number of scan points
    intervals : the feasible intervals (the intersection over checks)
    by_check : each check's own feasible intervals
    catalogue_ratios : the gearbox's catalogued ratios and whether each is feasible
    grid : the scan grid [-]
    grid_margins : each check's margin on the grid, by check name [-]
    """

    damper: str
    gearbox: str
    ratio_range: tuple[float, float]
    n_grid: int
    intervals: tuple[Interval, ...]
    by_check: dict[str, tuple[Interval, ...]]
    catalogue_ratios: tuple[tuple[float, bool], ...]
    grid: FloatArray
    grid_margins: dict[str, FloatArray]

    def contains(self, ratio: float) -> bool:
        """True if ``ratio`` lies in a feasible interval."""
        return any(i.low <= ratio <= i.high for i in self.intervals)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form (the grid is left out)."""
        return {
            "damper": self.damper,
            "gearbox": self.gearbox,
            "ratio_range": list(self.ratio_range),
            "n_grid": self.n_grid,
            "intervals": [i.to_dict() for i in self.intervals],
            "by_check": {k: [i.to_dict() for i in v] for k, v in self.by_check.items()},
            "catalogue_ratios": [
                {"ratio": r, "feasible": feasible} for r, feasible in self.catalogue_ratios
            ],
        }


def evaluate_ratios(
    damper: DamperEntry,
    gearbox: GearboxEntry,
    load: Load,
    requirements: Requirements,
    ratios: FloatArray,
) -> Evaluation:
    """Every check for the damper behind the gearbox at each ratio (one vectorised pass)."""
    n = as_float(ratios).reshape(-1)
    ecd = Ecd(damper.damper, gearbox.gearbox(n.reshape(-1, 1)))
    limits = Limits.of([(damper, gearbox)] * n.size)
    return evaluate(ecd, load, requirements, limits)


def _margins(evaluation: Evaluation) -> dict[str, FloatArray]:
    return {
        c.name: as_float(np.clip(c.worst(), -CLIP, CLIP))
        for c in evaluation.checks
        if np.all(c.applicable)
    }


def _boundary(function: Callable[[float], float], inside: float, outside: float) -> float:
    """The feasibility boundary between a passing and a failing ratio.

    brentq on the margin when it is strictly positive inside; where the margin is exactly
    0 over a stretch (a torque margin that vanishes by quasi-static equilibrium), the
    boundary of {margin >= 0} is found by bisection on the sign instead.
    """
    from scipy.optimize import brentq

    if function(inside) > 0.0:
        root = brentq(function, inside, outside, xtol=XTOL, rtol=RTOL)
        return float(root)
    a, b = inside, outside
    while abs(b - a) > XTOL + RTOL * abs(a):
        middle = 0.5 * (a + b)
        if function(middle) >= 0.0:
            a = middle
        else:
            b = middle
    return a


def _intervals(
    grid: FloatArray,
    feasible: np.ndarray[Any, np.dtype[np.bool_]],
    roots: dict[int, float],
    reason: dict[int, str],
) -> list[Interval]:
    """Feasible intervals from grid flags and the exact root inside each sign change."""
    out: list[Interval] = []
    start: float | None = float(grid[0]) if feasible[0] else None
    start_reason = "scan range"
    for i in range(len(grid) - 1):
        if feasible[i] == feasible[i + 1]:
            continue
        if feasible[i]:
            assert start is not None
            out.append(Interval(start, roots[i], start_reason, reason[i]))
            start = None
        else:
            start, start_reason = roots[i], reason[i]
    if start is not None:
        out.append(Interval(start, float(grid[-1]), start_reason, "scan range"))
    return out


def _intersect(a: list[Interval], b: list[Interval]) -> list[Interval]:
    out = []
    for x in a:
        for y in b:
            low = max(x.low, y.low)
            high = min(x.high, y.high)
            if low <= high:
                low_by = x.low_limited_by if x.low >= y.low else y.low_limited_by
                high_by = x.high_limited_by if x.high <= y.high else y.high_limited_by
                out.append(Interval(low, high, low_by, high_by))
    return sorted(out, key=lambda i: i.low)


def ratio_intervals(
    damper: DamperEntry,
    gearbox: GearboxEntry,
    load: Load,
    requirements: Requirements,
    n_grid: int = DEFAULT_GRID,
) -> RatioIntervals:
    """The exact intervals of gear ratio N meeting every requirement (module docstring).

    Raises :class:`~ecdsim.deployment.ModelDomainError` if the damper's damping law gives
    BECD <= 0 at a requirement temperature (then no ratio can help).
    """
    low, high = requirements.ratio_range
    grid = as_float(np.geomspace(low, high, n_grid))
    on_grid = _margins(evaluate_ratios(damper, gearbox, load, requirements, grid))

    def margin_of(name: str) -> Callable[[float], float]:
        def function(ratio: float) -> float:
            evaluation = evaluate_ratios(damper, gearbox, load, requirements, as_float([ratio]))
            return float(_margins(evaluation)[name][0])

        return function

    by_check: dict[str, tuple[Interval, ...]] = {}
    for name, margins in on_grid.items():
        feasible = margins >= 0.0
        roots: dict[int, float] = {}
        reasons: dict[int, str] = {}
        function = margin_of(name)
        for i in np.flatnonzero(feasible[:-1] != feasible[1:]):
            inside, outside = (grid[i], grid[i + 1]) if feasible[i] else (grid[i + 1], grid[i])
            roots[int(i)] = _boundary(function, float(inside), float(outside))
            reasons[int(i)] = name
        by_check[name] = tuple(_intervals(grid, feasible, roots, reasons))
    everything = [Interval(float(grid[0]), float(grid[-1]), "scan range", "scan range")]
    for found in by_check.values():
        everything = _intersect(everything, list(found))
    result = RatioIntervals(
        damper=damper.name,
        gearbox=gearbox.name,
        ratio_range=(float(low), float(high)),
        n_grid=n_grid,
        intervals=tuple(everything),
        by_check=by_check,
        catalogue_ratios=(),
        grid=grid,
        grid_margins=on_grid,
    )
    flags = tuple((r, result.contains(r)) for r in gearbox.ratios)
    return RatioIntervals(**{**result.__dict__, "catalogue_ratios": flags})
