"""Hand calculations of the paper's example, written out independently of ecdsim.

Each function is the paper's equation typed in plain Python floats, so that tests compare
ecdsim against arithmetic anyone can check on paper, not against ecdsim itself.
"""

from __future__ import annotations

import math

BD, FD, FG, N, BG_FRACTION = 1.3e-4, 7.9e-4, 4.5e-4, 380.0, 0.26
TS, TE, TRAVEL = 3.73, 1.58, 1.57


def becd(t: float) -> float:
    """Eq. 1 and 3 by hand."""
    return (BD * (1.0 - 0.004 * (t - 25.0)) + BG_FRACTION * BD) * N**2


def fecd(t: float) -> float:
    """Eq. 2 and 4 by hand, FL_T = -2.12e-6 T + 2.2e-4."""
    return (FD + (-2.12e-6 * t + 2.2e-4) + FG) * N


def fs(t: float) -> float:
    """FS_T = -0.0044 T + 0.58 (paper section 6)."""
    return -0.0044 * t + 0.58


def paper_time(t: float, ts: float = TS, te: float = TE, travel: float = TRAVEL) -> float:
    """Eq. 8-11 by hand."""
    friction = fecd(t) + fs(t)
    ws = (ts - friction) / becd(t)
    we = (te - friction) / becd(t)
    return travel / ((ws + we) / 2.0)


def exact_time(t: float, ts: float = TS, te: float = TE, travel: float = TRAVEL) -> float:
    """Exact solution of B dphi/dt = Ts - (Ts-Te) phi/travel - F, integrated by hand.

    dt = B dphi / (a - k phi)  =>  t = (B/k) ln(a / (a - k travel)),  k = (Ts - Te)/travel.
    """
    friction = fecd(t) + fs(t)
    a = ts - friction
    k = (ts - te) / travel
    return becd(t) / k * math.log(a / (a - k * travel))
