"""Tight scipy reference integrations of the quasi-static equation B dphi/dt = T(phi) - F.

Independent of ecdsim's closed forms: the right-hand side is written here from the paper's
definitions and integrated numerically.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from scipy.integrate import solve_ivp

RTOL = 1e-10
ATOL = 1e-13


def deploy(
    torque: Callable[[float], float],
    friction: float,
    damping: float,
    travel: float,
    t_max: float = 1e4,
) -> tuple[float | None, object]:
    """Time to reach the travel (None if never) and the dense solution."""

    def rhs(_t: float, y: np.ndarray) -> list[float]:
        return [(torque(float(y[0])) - friction) / damping]

    def arrive(_t: float, y: np.ndarray) -> float:
        return float(y[0]) - travel

    arrive.terminal = True  # type: ignore[attr-defined]
    arrive.direction = 1  # type: ignore[attr-defined]
    sol = solve_ivp(
        rhs,
        (0.0, t_max),
        [0.0],
        method="DOP853",
        rtol=RTOL,
        atol=ATOL,
        events=arrive,
        dense_output=True,
    )
    times = sol.t_events[0]
    return (float(times[0]) if len(times) else None), sol
