"""The planar chain's Lagrangian terms (ecdsim.physics.chain) against independent derivations.

Three references, none of them ecdsim's code: the mass matrix, velocity terms and gravity
forces derived symbolically with sympy from the panels' positions (the textbook recipe,
``M = sum m Jv^T Jv + I Jw^T Jw``, Christoffel symbols, ``Q = -dV/dq``); the planar elbow
manipulator's closed forms for one and two panels typed from the textbook (Spong,
Hutchinson and Vidyasagar 2006, section 7.4.2); and the conservation of energy of a free
chain integrated with scipy. The functions are also compiled with numba from the same
source and must give the same numbers.
"""

from __future__ import annotations

import inspect
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp

from ecdsim._types import FloatArray
from ecdsim.physics import cable, chain

# The same sums in another order: a few ulp of the largest term; 1e-12 of the scale.
ROUNDING = 1e-12


@dataclass(frozen=True)
class Chain:
    mass: FloatArray
    cg_along: FloatArray
    cg_across: FloatArray
    inertia: FloatArray
    length: FloatArray
    offload: FloatArray


def _random_chain(rng: np.random.Generator, n: int) -> Chain:
    return Chain(
        mass=rng.uniform(0.5, 5.0, n),
        cg_along=rng.uniform(0.1, 0.9, n),
        cg_across=rng.uniform(-0.1, 0.1, n),
        inertia=rng.uniform(0.01, 0.5, n),
        length=rng.uniform(0.5, 1.5, n),
        offload=rng.uniform(0.0, 0.9, n),
    )


def _symbolic(n: int) -> dict[str, Callable[..., Any]]:
    """M(q), h(q, q') and Q_g(q) of an n-panel chain derived with sympy."""
    q = sp.symbols(f"q0:{n}")
    dq = sp.symbols(f"dq0:{n}")
    m = sp.symbols(f"m0:{n}")
    a = sp.symbols(f"a0:{n}")
    b = sp.symbols(f"b0:{n}")
    inertia = sp.symbols(f"I0:{n}")
    length = sp.symbols(f"L0:{n}")
    offload = sp.symbols(f"o0:{n}")
    gx, gy = sp.symbols("gx gy")
    x, y = sp.Integer(0), sp.Integer(0)
    theta = sp.Integer(0)
    mass_matrix = sp.zeros(n, n)
    potential = sp.Integer(0)
    for i in range(n):
        theta = theta + q[i]
        cx = x + a[i] * sp.cos(theta) - b[i] * sp.sin(theta)
        cy = y + a[i] * sp.sin(theta) + b[i] * sp.cos(theta)
        jv = sp.Matrix([cx, cy]).jacobian(sp.Matrix(q))
        jw = sp.Matrix([[1 if j <= i else 0 for j in range(n)]])
        mass_matrix += m[i] * jv.T * jv + inertia[i] * jw.T * jw
        potential += -m[i] * (1 - offload[i]) * (gx * cx + gy * cy)
        x = x + length[i] * sp.cos(theta)
        y = y + length[i] * sp.sin(theta)
    velocity = []
    for k in range(n):
        term = sp.Integer(0)
        for i in range(n):
            for j in range(n):
                christoffel = sp.Rational(1, 2) * (
                    sp.diff(mass_matrix[k, j], q[i])
                    + sp.diff(mass_matrix[k, i], q[j])
                    - sp.diff(mass_matrix[i, j], q[k])
                )
                term += christoffel * dq[i] * dq[j]
        velocity.append(term)
    gravity = [-sp.diff(potential, q[k]) for k in range(n)]
    args = (q, dq, m, a, b, inertia, length, offload, gx, gy)
    return {
        "M": sp.lambdify(args, mass_matrix.tolist(), "math"),
        "h": sp.lambdify(args, velocity, "math"),
        "Q": sp.lambdify(args, gravity, "math"),
        "V": sp.lambdify(args, potential, "math"),
    }


@pytest.fixture(scope="module")
def symbolic() -> dict[int, dict[str, Callable[..., Any]]]:
    return {n: _symbolic(n) for n in (1, 2, 3)}


@pytest.mark.parametrize("n", [1, 2, 3])
def test_terms_equal_the_symbolic_derivation(
    symbolic: dict[int, dict[str, Callable[..., Any]]], n: int
) -> None:
    rng = np.random.default_rng(100 + n)
    for _ in range(20):
        c = _random_chain(rng, n)
        q = rng.uniform(-math.pi, math.pi, n)
        dq = rng.uniform(-3.0, 3.0, n)
        gx, gy = rng.uniform(-10.0, 10.0, 2)
        args = (q, dq, c.mass, c.cg_along, c.cg_across, c.inertia, c.length, c.offload, gx, gy)
        expected_m = np.array(symbolic[n]["M"](*args), dtype=float)
        got_m = chain.mass_matrix(q, c.mass, c.cg_along, c.cg_across, c.inertia, c.length)
        scale = float(np.max(np.abs(expected_m)))
        np.testing.assert_allclose(got_m, expected_m, rtol=0.0, atol=ROUNDING * scale)
        np.testing.assert_allclose(got_m, got_m.T, rtol=0.0, atol=ROUNDING * scale)
        assert np.all(np.linalg.eigvalsh(got_m) > 0.0)
        expected_h = np.array(symbolic[n]["h"](*args), dtype=float)
        got_h = chain.velocity_terms(q, dq, c.mass, c.cg_along, c.cg_across, c.length)
        np.testing.assert_allclose(
            got_h, expected_h, rtol=0.0, atol=ROUNDING * scale * float(np.max(dq**2)) * n
        )
        expected_q = np.array(symbolic[n]["Q"](*args), dtype=float)
        got_q = chain.gravity_forces(
            q, c.mass, c.cg_along, c.cg_across, c.length, c.offload, gx, gy
        )
        weight = float(np.sum(c.mass) * np.sum(c.length) * math.hypot(gx, gy))
        np.testing.assert_allclose(got_q, expected_q, rtol=0.0, atol=ROUNDING * weight)
        potential = chain.gravity_potential(
            q, c.mass, c.cg_along, c.cg_across, c.length, c.offload, gx, gy
        )
        assert potential == pytest.approx(symbolic[n]["V"](*args), abs=ROUNDING * weight)


def test_one_and_two_panels_equal_the_planar_elbow_closed_forms() -> None:
    # Spong, Hutchinson and Vidyasagar 2006, section 7.4.2 (the planar elbow manipulator,
    # centres of gravity on the link lines, gravity along -y), typed here.
    m1, m2, a1, a2, i1, i2, l1, l2, g = 2.0, 1.5, 0.4, 0.6, 0.2, 0.15, 1.1, 1.3, 9.81
    q1, q2, w1, w2 = 0.7, -1.9, 0.8, -1.7
    d11 = m1 * a1**2 + m2 * (l1**2 + a2**2 + 2 * l1 * a2 * math.cos(q2)) + i1 + i2
    d12 = m2 * (a2**2 + l1 * a2 * math.cos(q2)) + i2
    d22 = m2 * a2**2 + i2
    h = -m2 * l1 * a2 * math.sin(q2)
    c1 = h * (2 * w1 * w2 + w2**2)  # h w2^2 + 2 h w1 w2
    c2 = -h * w1**2
    phi1 = (m1 * a1 + m2 * l1) * g * math.cos(q1) + m2 * a2 * g * math.cos(q1 + q2)
    phi2 = m2 * a2 * g * math.cos(q1 + q2)
    q = np.array([q1, q2])
    mass, along = np.array([m1, m2]), np.array([a1, a2])
    across, inertia, length = np.zeros(2), np.array([i1, i2]), np.array([l1, l2])
    np.testing.assert_allclose(
        chain.mass_matrix(q, mass, along, across, inertia, length),
        [[d11, d12], [d12, d22]],
        rtol=1e-14,
    )
    np.testing.assert_allclose(
        chain.velocity_terms(q, np.array([w1, w2]), mass, along, across, length),
        [c1, c2],
        rtol=1e-13,
    )
    # The textbook's equation is D q'' + C q' + phi = tau, so Q_gravity = -phi.
    np.testing.assert_allclose(
        chain.gravity_forces(q, mass, along, across, length, np.zeros(2), 0.0, -g),
        [-phi1, -phi2],
        rtol=1e-13,
    )
    # One panel: a compound pendulum, I_hinge = I + m (a^2 + b^2).
    one = chain.mass_matrix(
        np.array([0.3]),
        np.array([m1]),
        np.array([a1]),
        np.array([0.05]),
        np.array([i1]),
        np.array([l1]),
    )
    assert one[0, 0] == pytest.approx(i1 + m1 * (a1**2 + 0.05**2), rel=1e-15)


def test_kinetic_energy_is_half_the_mass_matrix_quadratic_form() -> None:
    rng = np.random.default_rng(7)
    for n in (1, 2, 3, 5):
        c = _random_chain(rng, n)
        q = rng.uniform(-math.pi, math.pi, n)
        dq = rng.uniform(-3.0, 3.0, n)
        m = chain.mass_matrix(q, c.mass, c.cg_along, c.cg_across, c.inertia, c.length)
        expected = 0.5 * float(dq @ m @ dq)
        got = chain.kinetic_energy(q, dq, c.mass, c.cg_along, c.cg_across, c.inertia, c.length)
        assert got == pytest.approx(expected, rel=1e-13)


def _free_chain_energy_drift(c: Chain, q0: FloatArray, dq0: FloatArray, g: float) -> float:
    """Largest relative change of KE + V over 3 s of a free chain in gravity (scipy)."""
    n = q0.shape[0]

    def rhs(_t: float, y: FloatArray) -> FloatArray:
        q, dq = y[:n], y[n:]
        m = chain.mass_matrix(q, c.mass, c.cg_along, c.cg_across, c.inertia, c.length)
        h = chain.velocity_terms(q, dq, c.mass, c.cg_along, c.cg_across, c.length)
        force = chain.gravity_forces(
            q, c.mass, c.cg_along, c.cg_across, c.length, c.offload, 0.0, -g
        )
        return np.concatenate([dq, np.linalg.solve(m, force - h)])

    def energy(y: FloatArray) -> float:
        q, dq = y[:n], y[n:]
        kinetic = chain.kinetic_energy(q, dq, c.mass, c.cg_along, c.cg_across, c.inertia, c.length)
        return kinetic + chain.gravity_potential(
            q, c.mass, c.cg_along, c.cg_across, c.length, c.offload, 0.0, -g
        )

    sol = solve_ivp(
        rhs,
        (0.0, 3.0),
        np.concatenate([q0, dq0]),
        method="DOP853",
        rtol=1e-12,
        atol=1e-12,
        dense_output=True,
    )
    assert sol.success
    values = [energy(sol.sol(t)) for t in np.linspace(0.0, 3.0, 301)]
    scale = max(abs(v) for v in values) + chain.kinetic_energy(
        q0, dq0, c.mass, c.cg_along, c.cg_across, c.inertia, c.length
    )
    return max(abs(v - values[0]) for v in values) / scale


@pytest.mark.parametrize("n", [2, 3])
def test_a_free_chain_conserves_energy(n: int) -> None:
    # A wrong velocity term or gravity force would pump energy in or out; with the right
    # ones the integration at rtol 1e-12 holds KE + V to about 1e-11 of its scale, so
    # 1e-9 is far below what any wrong term (order 1) would give.
    rng = np.random.default_rng(40 + n)
    c = _random_chain(rng, n)
    q0 = rng.uniform(-2.0, 2.0, n)
    dq0 = rng.uniform(-2.0, 2.0, n)
    assert _free_chain_energy_drift(c, q0, dq0, 9.80665) < 1e-9
    # The same test fails for a velocity term off by 10 %: it can fail.
    original = chain.velocity_terms

    def wrong(*args: Any) -> FloatArray:
        return 1.1 * original(*args)

    chain.velocity_terms = wrong  # type: ignore[assignment]
    try:
        assert _free_chain_energy_drift(c, q0, dq0, 9.80665) > 1e-6
    finally:
        chain.velocity_terms = original


def test_outlines_and_positions() -> None:
    q = np.array([math.pi / 2, math.pi, -math.pi])  # a Z-fold stowed against a wall
    length = np.array([1.0, 1.0, 1.0])
    hinges = chain.hinge_positions(q, length)
    np.testing.assert_allclose(hinges, [[0, 0], [0, 1], [0, 0], [0, 1]], atol=1e-15)
    q = np.array([0.3, -0.5, 0.9])
    length = np.array([1.2, 0.8, 1.1])
    hinges = chain.hinge_positions(q, length)
    np.testing.assert_allclose(np.hypot(*np.diff(hinges, axis=0).T), length, rtol=1e-15)
    outlines = chain.panel_outlines(q, length, np.array([0.1, 0.2, 0.0]))
    for i in range(3):
        # Edges along the panel have its length; the ends its thickness.
        corners = outlines[i]
        assert math.dist(corners[0], corners[1]) == pytest.approx(length[i], rel=1e-14)
        assert math.dist(corners[1], corners[2]) == pytest.approx([0.1, 0.2, 0.0][i], abs=1e-15)
        np.testing.assert_allclose((corners[0] + corners[3]) / 2, hinges[i], atol=1e-15)
        np.testing.assert_allclose((corners[1] + corners[2]) / 2, hinges[i + 1], atol=1e-15)
    centres = chain.cg_positions(q, length, np.array([0.6, 0.4, 0.5]), np.array([0.0, 0.1, 0.0]))
    theta = np.cumsum(q)
    expected = hinges[1] + 0.4 * np.array([math.cos(theta[1]), math.sin(theta[1])])
    expected += 0.1 * np.array([-math.sin(theta[1]), math.cos(theta[1])])
    np.testing.assert_allclose(centres[1], expected, atol=1e-15)


def _compiled(module: Any, numba: Any) -> dict[str, Any]:
    """Every function of ``module`` compiled by numba from the module's own source.

    As fluids.numba does: the source is executed into a fresh namespace, and each of its
    functions is replaced there by its njit dispatcher, so that the compiled functions
    call each other (numba resolves a global at compile time, from that namespace).
    """
    namespace: dict[str, Any] = {"__name__": module.__name__ + "_compiled"}
    exec(compile(inspect.getsource(module), module.__file__, "exec"), namespace)
    for name, value in list(namespace.items()):
        if inspect.isfunction(value) and value.__module__ == namespace["__name__"]:
            namespace[name] = numba.njit(value)
    return namespace


def test_numba_compiles_the_same_source() -> None:
    import numba  # a test dependency (the suite refuses skips)

    rng = np.random.default_rng(3)
    c = _random_chain(rng, 3)
    q = rng.uniform(-math.pi, math.pi, 3)
    dq = rng.uniform(-3.0, 3.0, 3)
    calls: list[tuple[Callable[..., Any], tuple[Any, ...]]] = [
        (chain.mass_matrix, (q, c.mass, c.cg_along, c.cg_across, c.inertia, c.length)),
        (chain.velocity_terms, (q, dq, c.mass, c.cg_along, c.cg_across, c.length)),
        (
            chain.gravity_forces,
            (q, c.mass, c.cg_along, c.cg_across, c.length, c.offload, 0.5, -9.8),
        ),
        (
            chain.gravity_potential,
            (q, c.mass, c.cg_along, c.cg_across, c.length, c.offload, 0.5, -9.8),
        ),
        (chain.kinetic_energy, (q, dq, c.mass, c.cg_along, c.cg_across, c.inertia, c.length)),
        (chain.panel_outlines, (q, c.length, c.offload)),
        (chain.cg_positions, (q, c.length, c.cg_along, c.cg_across)),
        (cable.cable_torque, (0.03, 100.0, 2.0)),
        (cable.cable_energy, (-0.03, 100.0, 2.0)),
    ]
    compiled_modules = {module.__name__: _compiled(module, numba) for module in (chain, cable)}
    for function, args in calls:
        compiled = compiled_modules[function.__module__][function.__name__]
        # The same operations compiled by LLVM: equal to rounding, not necessarily in
        # the last bit (contractions and the libm may differ).
        np.testing.assert_allclose(compiled(*args), function(*args), rtol=1e-13, atol=1e-13)


def test_cable_law_is_continuous_and_its_energy_integrates_it() -> None:
    stiffness, slack = 250.0, 3.0
    limit = slack / stiffness
    for side in (-1.0, 1.0):
        inside = cable.cable_torque(side * limit * (1 - 1e-12), stiffness, slack)
        outside = cable.cable_torque(side * limit * (1 + 1e-12), stiffness, slack)
        assert inside == pytest.approx(outside, rel=1e-9)
        assert abs(inside) == pytest.approx(slack, rel=1e-9)
    # Beyond the slack point the stiffness is half (one strand carries).
    slope = (
        cable.cable_torque(0.05, stiffness, slack) - cable.cable_torque(0.04, stiffness, slack)
    ) / 0.01
    assert slope == pytest.approx(-stiffness / 2, rel=1e-12)
    # -d(energy)/d(delta) = torque, by central differences on both branches.
    for delta in (-0.05, -0.005, 0.003, 0.02, 0.07):
        step = 1e-6
        derivative = (
            cable.cable_energy(delta + step, stiffness, slack)
            - cable.cable_energy(delta - step, stiffness, slack)
        ) / (2 * step)
        assert -derivative == pytest.approx(cable.cable_torque(delta, stiffness, slack), rel=1e-8)
