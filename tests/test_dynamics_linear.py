"""The closed-form segment ``J x'' + B x' + k x = a`` against hand solutions and scipy.

The kernel's closed form (:mod:`ecdsim.dynamics.kernel.closed`), run as plain Python
(the compiled kernel is the same source; tests/test_dynamics_kernel.py holds the two
together).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from ecdsim.dynamics.kernel import closed


class _State:
    """x, v, acceleration and int v^2 of a segment at one time."""

    def __init__(self, values: tuple[float, float, float, float]) -> None:
        self.x, self.v, self.acceleration, self.speed_squared_integral = values


def _state(j: float, b: float, k: float, a: float, w0: float, t: float) -> _State:
    return _State(closed.evaluate(closed.prepare(j, b, k, a, w0), t, True))


def _reference(j: float, b: float, k: float, a: float, w0: float, t: float) -> np.ndarray:
    """x, v and int v^2 by DOP853 at rtol 1e-13 (non-stiff cases only)."""
    sol = solve_ivp(
        lambda _t, y: [y[1], (a - k * y[0] - b * y[1]) / j, y[1] ** 2],
        (0.0, t),
        [0.0, w0, 0.0],
        method="DOP853",
        rtol=1e-13,
        atol=1e-15,
    )
    return np.asarray(sol.y[:, -1])


# (J, B, k, a, w0, t): overdamped (the paper's J = 5 and J = 20), strongly overdamped,
# underdamped, undamped, exactly and nearly critical (both sides), rising torque (k < 0),
# constant torque (k = 0), a coasting spin-down (a = k = 0), and decelerating motion.
CASES = [
    (5.0, 23.65, 1.369, 2.725, 0.0, 10.0),
    (20.0, 23.65, 1.369, 2.725, 0.0, 30.0),
    (0.05, 23.65, 1.369, 2.725, 0.0, 3.0),
    (100.0, 23.65, 1.369, 2.725, 0.1, 40.0),
    (5.0, 0.0, 1.369, 1.0, 0.5, 3.0),
    (1.0, 2.0, 1.0, 1.0, 0.2, 5.0),
    (1.0, 2.0, 1.0 + 1e-9, 1.0, 0.2, 5.0),
    (1.0, 2.0, 1.0 - 1e-9, 1.0, 0.2, 5.0),
    (1.0, 2.0, 1.0 + 1e-3, 1.0, 0.2, 5.0),
    (5.0, 23.65, -1.0, 2.0, 0.1, 3.0),
    (5.0, 23.65, 0.0, 2.0, 0.1, 3.0),
    (1.0, 2.0, 0.0, 0.0, 1.0, 5.0),
    (2.0, 3.0, 0.5, -1.0, 2.0, 0.7),
]


@pytest.mark.parametrize(("j", "b", "k", "a", "w0", "t"), CASES)
def test_closed_form_matches_tight_integration(
    j: float, b: float, k: float, a: float, w0: float, t: float
) -> None:
    state = _state(j, b, k, a, w0, t)
    ref = _reference(j, b, k, a, w0, t)
    scale_x = max(abs(ref[0]), 1e-3)
    scale_v = max(abs(ref[1]), abs(w0), abs(a) / max(b, 1e-9) if b > 0 else 1.0)
    # DOP853 at rtol 1e-13 carries ~1e-12 relative global error over these spans.
    assert abs(state.x - ref[0]) < 1e-10 * scale_x
    assert abs(state.v - ref[1]) < 1e-10 * scale_v
    assert abs(state.speed_squared_integral - ref[2]) < 1e-10 * max(abs(ref[2]), 1e-6)


def test_hand_solutions() -> None:
    # Critically damped x'' + 2x' + x = a (J = 1, B = 2, k = 1):
    # x = a (1 - e^-t (1 + t)) + w0 t e^-t.
    a, w0, t = 1.0, 0.2, 3.0
    state = _state(1.0, 2.0, 1.0, a, w0, t)
    hand_x = a * (1 - math.exp(-t) * (1 + t)) + w0 * t * math.exp(-t)
    hand_v = a * t * math.exp(-t) + w0 * (1 - t) * math.exp(-t)
    # Exact formulas on both sides; only rounding differs.
    assert state.x == pytest.approx(hand_x, rel=1e-14)
    assert state.v == pytest.approx(hand_v, rel=1e-13)
    # Undamped J x'' + k x = a: x = (a/k)(1 - cos wt) + (w0/w) sin wt, w = sqrt(k/J).
    j, k, a, w0, t = 2.0, 8.0, 1.0, 0.5, 1.3
    omega = math.sqrt(k / j)
    state = _state(j, 0.0, k, a, w0, t)
    assert state.x == pytest.approx(
        a / k * (1 - math.cos(omega * t)) + w0 / omega * math.sin(omega * t), rel=1e-13
    )
    # No spring (k = 0): v = a/B + (w0 - a/B) e^{-Bt/J}; x and int v^2 by hand.
    j, b, a, w0, t = 5.0, 20.0, 3.0, 1.0, 0.8
    tau = j / b
    drift = a / b
    decay = math.exp(-t / tau)
    state = _state(j, b, 0.0, a, w0, t)
    assert state.v == pytest.approx(drift + (w0 - drift) * decay, rel=1e-14)
    assert state.x == pytest.approx(drift * t + (w0 - drift) * tau * (1 - decay), rel=1e-14)
    hand_v2 = (
        drift**2 * t
        + 2 * drift * (w0 - drift) * tau * (1 - decay)
        + (w0 - drift) ** 2 * tau / 2 * (1 - decay**2)
    )
    assert state.speed_squared_integral == pytest.approx(hand_v2, rel=1e-13)
    # Rising torque without damping (k < 0): x = (a/k)(1 - cosh lt) + (w0/l) sinh lt.
    j, k, a, w0, t = 1.0, -4.0, 1.0, 0.1, 0.9
    lam = math.sqrt(-k / j)
    state = _state(j, 0.0, k, a, w0, t)
    assert state.x == pytest.approx(
        a / k * (1 - math.cosh(lam * t)) + w0 / lam * math.sinh(lam * t), rel=1e-13
    )


def test_series_and_modal_forms_agree_at_the_switch() -> None:
    # Near critical damping the series form is used below |h| t = 0.05, the modal form
    # above; both are accurate to ~1e-14 there, so they must agree across the switch.
    for k in (1.0 - 1e-4, 1.0 + 1e-4):
        seg = closed.prepare(1.0, 2.0, k, 1.0, 0.3)
        h = math.sqrt(abs(seg[7]))  # h^2 = p^2 - q
        t_switch = closed.NEAR_CRITICAL / h
        below = closed.evaluate(seg, t_switch * (1 - 1e-12), True)
        above = closed.evaluate(seg, t_switch * (1 + 1e-12), True)
        for column in (0, 1, 3):  # x, v, int v^2
            assert below[column] == pytest.approx(above[column], rel=1e-12)


def test_stiff_segment_is_finite_and_tends_to_quasi_static() -> None:
    # J/B = 4e-11 s against a 30 s deployment: the fast mode must underflow cleanly (no
    # RuntimeWarning: pytest turns warnings into errors) and x(t) must approach the
    # quasi-static exponential (a/k)(1 - e^{-kt/B}) to O(J k / B^2) = 1e-12.
    j, b, k, a, t = 1e-9, 23.65, 1.369, 2.725, 20.0
    state = _state(j, b, k, a, 0.0, t)
    quasi = a / k * (1 - math.exp(-k * t / b))
    assert state.x == pytest.approx(quasi, rel=1e-9)


def test_zero_speed_times_by_hand() -> None:
    # k = 0, decelerating: v = (w0 - a/B) e^{-Bt/J} + a/B = 0 at t = (J/B) ln(1 + B w0/(-a)).
    j, b, a, w0 = 5.0, 20.0, -3.0, 1.0
    seg = closed.prepare(j, b, 0.0, a, w0)
    hand = j / b * math.log(1 + b * w0 / -a)
    assert closed.zero_speed_time(seg) == pytest.approx(hand, rel=1e-14)
    # Undamped, from rest with a > 0: the speed returns to zero after half a period.
    seg = closed.prepare(1.0, 0.0, 1.5, 0.5, 0.0)
    assert closed.zero_speed_time(seg) == pytest.approx(math.pi / math.sqrt(1.5), rel=1e-14)
    # Overdamped from rest towards an equilibrium: the speed never returns to zero.
    seg = closed.prepare(5.0, 23.65, 1.369, 2.725, 0.0)
    assert math.isinf(closed.zero_speed_time(seg))
    assert closed.limit_position(seg) == pytest.approx(2.725 / 1.369, rel=1e-15)


@pytest.mark.parametrize(("j", "b", "k", "a", "w0", "t"), CASES)
def test_event_times_land_on_their_events(
    j: float, b: float, k: float, a: float, w0: float, t: float
) -> None:
    seg = closed.prepare(j, b, k, a, w0)
    t_zero = closed.zero_speed_time(seg)
    # (A zero of speed where e^{-pt} has underflowed cannot be checked by sign: skip those.)
    if math.isfinite(t_zero) and seg[5] * t_zero < 600.0:
        v_zero = closed.evaluate(seg, t_zero, False)[1]
        v_before = closed.evaluate(seg, t_zero * (1 - 1e-6), False)[1]
        # The root is a sign change of v to rounding: |v| ~ eps * speed scale there.
        assert abs(v_zero) < 1e-12 * max(abs(w0), abs(a) / j * t_zero, 1e-300)
        assert v_before > 0.0
    half = 0.5 * closed.evaluate(seg, t, False)[0]
    if half > 0.0:
        kind, duration, *_ = closed.advance(seg, half, math.inf)
        assert kind == closed.REACH
        x_at = closed.evaluate(seg, duration, False)[0]
        # Newton converges to a few ulp of the time; x then matches to ~1e-15 relative.
        assert x_at == pytest.approx(half, rel=1e-13)


def test_advance_gives_every_outcome() -> None:
    # Four segments: one reaches its length, one stops (ZERO), one runs out of time (CAP),
    # one creeps to its equilibrium short of the length (REST).
    outcomes = [
        closed.advance(closed.prepare(5.0, 23.65, 1.369, 2.725, 0.0), 1.57, math.inf),
        closed.advance(closed.prepare(2.0, 3.0, 0.5, -1.0, 2.0), 10.0, math.inf),
        closed.advance(closed.prepare(5.0, 23.65, 1.369, 2.725, 0.0), 1.57, 1.0),
        closed.advance(closed.prepare(5.0, 23.65, 1.369, 1.0, 0.0), 1.57, math.inf),
    ]
    assert [o[0] for o in outcomes] == [closed.REACH, closed.ZERO, closed.CAP, closed.REST]
    assert outcomes[0][2] == 1.57
    assert outcomes[1][3] == 0.0
    assert outcomes[2][1] == 1.0
    assert math.isinf(outcomes[3][1])
    assert outcomes[3][2] == pytest.approx(1.0 / 1.369, rel=1e-15)
