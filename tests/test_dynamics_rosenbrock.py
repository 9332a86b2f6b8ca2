"""The vectorised RODAS4 integrator: order of accuracy, error estimate, batch independence."""

from __future__ import annotations

import numpy as np
from scipy.integrate import solve_ivp

from ecdsim.dynamics import rosenbrock
from ecdsim.dynamics.damping import KlossEddy


def _model(n: int = 1) -> rosenbrock.Model:
    # A spring-driven load on a Kloss damper (N = 10, beyond its peak for part of the
    # motion) with adiabatic heating: nonlinear in speed and temperature.
    ones = np.ones(n)
    return rosenbrock.Model(
        inertia=1.0 * ones,
        stiffness=1.5 * ones,
        drive=2.0 * ones,
        ratio=10.0 * ones,
        gearbox_damping=2e-4 * ones,
        heat_capacity=0.5 * ones,
        thermal_resistance=np.full(n, np.inf),
        ambient=25.0 * ones,
        eddy=KlossEddy(0.05 * ones, 30.0 * ones, 0.0039 * ones, 25.0 * ones),
        heating=True,
    )


def _fixed_steps(model: rosenbrock.Model, y0: np.ndarray, t_end: float, n: int) -> np.ndarray:
    y = y0.copy()
    h = np.full(y.shape[1], t_end / n)
    for _ in range(n):
        y, _, sound = rosenbrock._step(model, y, model.rhs(y), h)
        assert np.all(sound)
    return y


def _reference(model: rosenbrock.Model, y0: np.ndarray, t_end: float) -> np.ndarray:
    sol = solve_ivp(
        lambda _t, y: model.rhs(y.reshape(4, 1)).ravel(),
        (0.0, t_end),
        y0.ravel(),
        method="DOP853",
        rtol=1e-13,
        atol=1e-15,
    )
    return np.asarray(sol.y[:, -1])


def test_rodas4_converges_with_order_four() -> None:
    model = _model()
    y0 = np.array([[0.0], [0.0], [25.0], [0.0]])
    t_end = 0.5
    ref = _reference(model, y0, t_end)
    errors = [np.max(np.abs(_fixed_steps(model, y0, t_end, n)[:, 0] - ref)) for n in (20, 40, 80)]
    # Order 4: halving the step divides the global error by 16; allow 12..20 for the
    # pre-asymptotic terms (an order-3 method would give 8). The finest run's error,
    # ~4e-12, stays well above the reference's ~1e-14.
    ratios = np.array(errors[:-1]) / np.array(errors[1:])
    assert np.all((ratios > 12.0) & (ratios < 20.0)), (errors, ratios)


def test_error_estimate_is_of_local_order_four() -> None:
    model = _model()
    y0 = np.array([[0.0], [0.5], [25.0], [0.0]])
    estimates = []
    for h in (0.02, 0.01, 0.005):
        _, error, _ = rosenbrock._step(model, y0, model.rhs(y0), np.array([h]))
        estimates.append(np.max(np.abs(error)))
    # The embedded solution is order 3: its difference from the order-4 one is O(h^4),
    # so halving h divides the estimate by about 16 (allow 10..22).
    ratios = np.array(estimates[:-1]) / np.array(estimates[1:])
    assert np.all((ratios > 10.0) & (ratios < 22.0)), (estimates, ratios)


def test_cases_in_a_batch_do_not_influence_each_other() -> None:
    # Each case has its own step size and error control: solving a case alone or inside
    # a batch of different cases gives the same answer to rounding.
    model = _model(3)
    model = rosenbrock.Model(
        **{**model.__dict__, "drive": np.array([2.0, 0.5, 5.0]), "heating": True}
    )
    y0 = np.stack([np.zeros(3), np.zeros(3), np.full(3, 25.0), np.zeros(3)])
    length, cap = np.full(3, 0.8), np.full(3, np.inf)
    creep, creeps = np.full(3, 1e-12), np.zeros(3, dtype=bool)
    atol, first = np.full((4, 3), 1e-12), np.full(3, 1e-5)
    segments = rosenbrock.Segments(y0, length, cap, creep, creeps, atol, first)
    control = rosenbrock.Control(rtol=1e-9, horizon=1e9, horizon_kind=4)
    batch = rosenbrock.integrate_batch(model, segments, control)
    one = np.array([1])
    alone = rosenbrock.integrate_batch(
        model.take(one),
        rosenbrock.Segments(
            y0[:, one], length[one], cap[one], creep[one], creeps[one], atol[:, one], first[one]
        ),
        control,
    )
    assert batch.kind[1] == alone.kind[0]
    assert batch.duration[1] == alone.duration[0]
    assert np.array_equal(batch.state[:, 1], alone.state[:, 0])
