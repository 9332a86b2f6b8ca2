"""A wing's deployment on the dynamic core: pack the wing, run the kernel, read it back.

:func:`deploy_wing` solves a :class:`~ecdsim.wing.model.Wing` at each temperature with
the kernel's event loop for N hinges (:mod:`ecdsim.wing.kernel.loop`: the
friction machine, RODAS4 and the dense-output locator, the chain's equations of
:mod:`ecdsim.wing.kernel.equations`) and returns a
:class:`~ecdsim.wing.result.WingResult`.

The wing's path models (gates closed by default, as every path of the kernel): per
hinge a spring (linear or table, less a resistive table), the ECD's damping through its
gear ratio (Eq. 3 with the linear law or the Kloss roll-off, BG), its self-heating (one
node, or rotor and housing; from a warm start or not), its Coulomb friction ``FECD_T``
with the hinge friction ``FS_T`` and their breakaway (stick-slip; with the ECD's
Stribeck speed, falling from the breakaway to the kinetic value with speed), a lossy gear
(its efficiency forward or back-driven by the power flow at its hinge), the rotor and gear
train reflected to the hinge, a rigid or compliant latch, the stowed stop; cables rigid
or elastic; a ground test's gravity and offload. An ECD with an effect the wing's path
does not model yet (lost motion, a compliant gear) is refused in one
line naming the hinge and the key (:class:`WingUnsupported`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ecdsim._types import FloatArray
from ecdsim.dynamics.damping import KlossEddy, LinearEddy
from ecdsim.dynamics.kernel.build import resolve_name, substituted
from ecdsim.dynamics.params import DynamicParameters
from ecdsim.dynamics.problem import DynamicDomainError
from ecdsim.dynamics.problem import _eddy_law as eddy_law
from ecdsim.physics import chain
from ecdsim.physics import eddy as eddy_laws
from ecdsim.physics.cable import cable_energy
from ecdsim.physics.thermal import factor_log_from_rise, temperature_from_factor_log
from ecdsim.wing.kernel import layout as W
from ecdsim.wing.model import Hinge, Wing
from ecdsim.wing.result import LatchEvent, WingCase, WingEnergy, WingEvent, WingResult

DEFAULT_RTOL = 1e-8
MAX_EVENTS = 2000
# Absolute tolerances as fractions of rtol: angles [rad], speeds [rad/s], energies [J].
ATOL_ANGLE = 1e-3
ATOL_ENERGY = 1e-3
ATOL_LOG = 1e-2  # the damper's log temperature state [K]
POINTS = 20_000  # the points buffer's first size (enlarged and run again when full)


class WingUnsupported(ValueError):
    """A wing with an effect the wing's solver does not model (one line, the key named)."""


@dataclass(frozen=True)
class _Groups:
    """Hinges joined by rigid cables: each hinge's group and factor (phi = factor psi)."""

    of: tuple[int, ...]
    factor: tuple[float, ...]
    first: tuple[int, ...]

    @property
    def count(self) -> int:
        return len(self.first)


def _groups(wing: Wing) -> _Groups:
    n = wing.size
    root = list(range(n))
    factor = [1.0] * n
    for c in sorted(wing.cables, key=lambda c: c.inboard):
        if c.rigid:
            root[c.inboard + 1] = root[c.inboard]
            factor[c.inboard + 1] = factor[c.inboard] * c.ratio
    roots = sorted(set(root))
    of = tuple(roots.index(r) for r in root)
    return _Groups(of, tuple(factor), tuple(roots))


def check_supported(wing: Wing) -> None:
    """Refuse what the wing's solver does not model, in one line naming the key."""
    if wing.size > W.NMAX:
        raise WingUnsupported(
            f"wing.panels: {wing.size} panels; the wing's solver takes up to {W.NMAX}"
        )
    for i, hinge in enumerate(wing.hinges):
        ecd = hinge.ecd
        if ecd is None:
            continue
        at = f"wing.hinges[{i}] ({hinge.name}): its ECD's"
        if ecd.gear_stiffness is not None:
            raise WingUnsupported(
                f"{at} gearbox.stiffness is not modelled by the wing's solver yet "
                "(docs/wing.md); remove it to solve the wing without it"
            )
        if ecd.lost_motion > 0.0 and ecd.stribeck_speed is not None:
            raise WingUnsupported(
                f"{at} gearbox.lost_motion with damper.stribeck_speed is not modelled by "
                "the wing's solver yet (docs/wing.md); remove one"
            )
        if ecd.ecd.gearbox.efficiency is not None and ecd.stribeck_speed is not None:
            # The single hinge refuses the pair too (its Stribeck excess mixes the ECD's
            # friction, through the mesh, with the hinge's, not).
            raise WingUnsupported(
                f"{at} gearbox.efficiency with damper.stribeck_speed is not modelled (a "
                "lossy gear takes Coulomb friction only, as on a single hinge); remove one"
            )


def _law(hinge: Hinge, temperature: float) -> dict[int, float]:
    """Hinge j's ECD law at the hinge: the single hinge's eddy law (linear, or Kloss with
    roll-off; :func:`ecdsim.dynamics.problem.eddy_law`), N, BG, and its heating."""
    ecd = hinge.ecd
    if ecd is None:
        return {W.H_LAW: float(eddy_laws.LINEAR), W.H_RATIO: 1.0, W.H_FA: 1.0, W.H_HR: math.inf}
    params = DynamicParameters(load_inertia=1.0, rolloff=ecd.rolloff, thermal=ecd.thermal)
    try:
        law = eddy_law(ecd.ecd.damper, params, np.asarray([temperature]))
    except DynamicDomainError as exc:
        raise WingUnsupported(f"wing.hinges ({hinge.name}): {exc}") from None
    state = ecd.ecd.at(temperature)
    values = {
        W.H_RATIO: float(np.asarray(state.gear_ratio)),
        W.H_BG: float(np.asarray(state.gearbox_damping_rate)),
        W.H_COEF: float(np.asarray(law.coefficient)),
        W.H_FA: max(float(np.asarray(law.factor(temperature))), 0.0),
        W.H_HR: math.inf,
    }
    if isinstance(law, LinearEddy):
        values[W.H_LAW] = float(eddy_laws.LINEAR)
        values[W.H_LA] = float(np.asarray(law.damping_rate))
    elif isinstance(law, KlossEddy):
        values[W.H_LAW] = float(eddy_laws.KLOSS)
        values[W.H_LA] = float(np.asarray(law.peak_torque))
        values[W.H_LB] = float(np.asarray(law.reference_peak_speed))
    thermal = ecd.thermal
    if thermal is not None:
        values[W.H_HC] = float(np.asarray(thermal.heat_capacity))
        values[W.H_HR] = float(np.asarray(thermal.thermal_resistance))
        rise = float(np.asarray(thermal.initial_rotor_rise))
        if rise != 0.0:
            # A warm start (the single hinge's _check_start and its kernel's S0): the log
            # state of the rise, which must lie below the damping law's zero.
            if float(np.asarray(law.factor(temperature + rise))) <= 0.0:
                raise WingUnsupported(
                    f"wing.hinges ({hinge.name}): damper.thermal.initial_rotor_rise: "
                    f"{rise:g} K puts the damper at or beyond the temperature where its "
                    "damping law reaches zero"
                )
            values[W.H_S0] = float(factor_log_from_rise(rise, values[W.H_FA], values[W.H_COEF]))
        if thermal.housing_heat_capacity is not None:
            values[W.H_HCH] = float(np.asarray(thermal.housing_heat_capacity))
            values[W.H_HRHE] = float(np.asarray(thermal.housing_thermal_resistance))
            values[W.H_H0] = float(np.asarray(thermal.initial_housing_rise))
    return values


def _gear(hinge: Hinge, temperature: float) -> dict[int, float]:
    """Hinge j's gear: eta_f, eta_b and FECD_T through an ideal gear (FT N), an ideal
    gear's 1, 1 and FECD_T; its lost motion, and the ECD's friction and breakaway
    (which join the hinge's once the lost motion closes)."""
    ecd = hinge.ecd
    if ecd is None:
        return {W.H_ETAF: 1.0, W.H_ETAB: 1.0, W.H_FQ: 0.0, W.H_MESHED: 1.0}
    state = ecd.ecd.at(temperature)
    forward = float(np.asarray(state.forward_efficiency))
    friction = float(np.asarray(state.ecd_friction))
    return {
        W.H_ETAF: forward,
        W.H_ETAB: float(np.asarray(state.backward_efficiency)),
        W.H_FQ: friction * forward,
        W.H_GAP: ecd.lost_motion,
        W.H_MESHED: 0.0 if ecd.lost_motion > 0.0 else 1.0,
        W.H_FE: friction,
        W.H_FEB: ecd.static_friction_factor * friction,
    }


def _stribeck(hinge: Hinge, kinetic: float, breakaway: float) -> dict[int, float]:
    """Hinge j's Stribeck speed and excess (the single hinge's: the ECD's
    ``stribeck_speed`` at the hinge shaft, over the excess ``F_brk - F_C`` of the ECD's
    and the hinge's frictions together; none without a Stribeck speed)."""
    speed = None if hinge.ecd is None else hinge.ecd.stribeck_speed
    if speed is None or not math.isfinite(float(speed)):
        return {W.H_WST: math.inf, W.H_EXCESS: 0.0}
    return {W.H_WST: float(speed), W.H_EXCESS: max(breakaway - kinetic, 0.0)}


def _nodes(hinge: Hinge) -> int:
    """Hinge j's heating states: 0 (no heating), 1 (the damper) or 2 (rotor and housing)."""
    if hinge.ecd is None or hinge.ecd.thermal is None:
        return 0
    return 2 if hinge.ecd.thermal.two_node else 1


def _hinge_words(
    cw: FloatArray,
    wing: Wing,
    j: int,
    temperature: float,
    groups: _Groups,
    heated: int,
    arrays: dict[str, FloatArray],
    table_points: int,
) -> int:
    """Hinge j's fields at one temperature (``arrays``: the wing's chain arrays; its
    drive table's points); returns the heating states so far."""
    hinge = wing.hinges[j]
    for field, value in _law(hinge, temperature).items():
        cw[W.hinge(field, j)] = value
    cw[W.hinge(W.H_AUX, j)] = -1.0
    cw[W.hinge(W.H_HOUSING, j)] = -1.0
    nodes = _nodes(hinge)
    if nodes > 0:
        cw[W.hinge(W.H_AUX, j)] = 2 * groups.count + heated
    if nodes == 2:
        cw[W.hinge(W.H_HOUSING, j)] = 2 * groups.count + heated + 1
    state = hinge.at(temperature)
    values = {
        W.H_MASS: arrays["mass"][j],
        W.H_CGA: arrays["cg_along"][j],
        W.H_CGB: arrays["cg_across"][j],
        W.H_INERTIA: arrays["inertia"][j],
        W.H_LENGTH: arrays["length"][j],
        W.H_OFFLOAD: arrays["offload"][j],
        W.H_STOWED: hinge.stowed_angle,
        W.H_SIGN: hinge.direction,
        W.H_TRAVEL: hinge.travel,
        W.H_JD: hinge.ecd.reflected_inertia if hinge.ecd is not None else 0.0,
        W.H_DAMPING: float(state.damping_rate),
        W.H_FRICTION: float(state.kinetic_friction),
        W.H_BREAKAWAY: float(state.breakaway_friction),
        W.H_LATCH_K: hinge.latch.stiffness or 0.0,
        W.H_LATCH_C: hinge.latch.damping,
        W.H_RESTITUTION: hinge.latch.restitution,
        W.H_GROUP: groups.of[j],
        W.H_FACTOR: groups.factor[j],
        W.H_POINTS: table_points,
        **_stribeck(hinge, float(state.kinetic_friction), float(state.breakaway_friction)),
        **_gear(hinge, temperature),
    }
    for field, value in values.items():
        cw[W.hinge(field, j)] = value
    if values[W.H_MESHED] == 0.0:  # in its lost motion: the ECD's friction idles
        cw[W.hinge(W.H_FRICTION, j)] -= values[W.H_FE]
        cw[W.hinge(W.H_BREAKAWAY, j)] -= values[W.H_FEB]
    return heated + nodes


def _words(wing: Wing, temperature: float, stop_time: float, max_events: int) -> FloatArray:
    """The wing's words at one temperature (:mod:`ecdsim.wing.kernel.layout`)."""
    n = wing.size
    groups = _groups(wing)
    tables = [h.load.drive.breakpoints(h.travel, temperature) for h in wing.hinges]
    points = max(int(np.asarray(a).shape[0]) for a, _ in tables)
    cw = np.zeros(W.words(points))
    arrays = wing.chain_arrays()
    elastic = [c for c in wing.cables if not c.rigid]
    gravity = wing.ground_test.gravity if wing.ground_test is not None else (0.0, 0.0)
    cw[W.W_N], cw[W.W_M], cw[W.W_C], cw[W.W_K] = n, groups.count, len(elastic), points
    cw[W.W_AUX] = sum(_nodes(h) for h in wing.hinges)
    cw[W.W_GX], cw[W.W_GY] = gravity
    cw[W.W_MAX_EVENTS] = max_events
    cw[W.W_STOP] = stop_time
    heated = 0
    for j in range(n):
        angles, torques = (np.asarray(a, dtype=float).reshape(-1) for a in tables[j])
        heated = _hinge_words(cw, wing, j, temperature, groups, heated, arrays, angles.shape[0])
        for p in range(points):
            q = min(p, angles.shape[0] - 1)
            cw[W.table_angle(points, j, p)] = angles[q]
            cw[W.table_torque(points, j, p)] = torques[q]
    _group_words(cw, wing, groups)
    for c, item in enumerate(elastic):
        cw[W.cable(W.C_IN, c)] = item.inboard
        cw[W.cable(W.C_RATIO, c)] = item.ratio
        cw[W.cable(W.C_K, c)] = item.stiffness
        cw[W.cable(W.C_SLACK, c)] = item.slack_torque
    return cw


def _group_words(cw: FloatArray, wing: Wing, groups: _Groups) -> None:
    """Each group's fields: its friction and breakaway (its hinges' through their
    factors), travel in psi, latch kind and first hinge."""
    for g, first in enumerate(groups.first):
        members = [j for j in range(wing.size) if groups.of[j] == g]
        cw[W.group(W.G_FRICTION, g)] = sum(
            groups.factor[j] * cw[W.hinge(W.H_FRICTION, j)] for j in members
        )
        cw[W.group(W.G_BREAKAWAY, g)] = sum(
            groups.factor[j] * cw[W.hinge(W.H_BREAKAWAY, j)] for j in members
        )
        cw[W.group(W.G_TRAVEL, g)] = wing.hinges[first].travel / groups.factor[first]
        cw[W.group(W.G_RIGID, g)] = 1.0 if wing.hinges[first].latch.rigid else 0.0
        cw[W.group(W.G_FIRST, g)] = first


def _run(
    cw: FloatArray, rtol: float, backend: str, m: int, n: int, na: int
) -> tuple[FloatArray, ...]:
    """The kernel's run of one case, its buffers enlarged until they hold it."""
    run = substituted_run(backend)
    dm = (0,) * m
    da = (0,) * na
    dq = (0,) * (4 * n)
    atol = np.full(2 * m + na + 4 * n, rtol * ATOL_ANGLE)
    atol[2 * m : 2 * m + na] = rtol * ATOL_LOG
    atol[2 * m + na :] = rtol * ATOL_ENERGY
    settings = np.array([rtol, 0.0 if backend != "scipy" else 1.0])
    size = POINTS
    while True:
        words = cw.copy()
        points = np.zeros((size, 1 + 2 * n))
        events = np.zeros((4 * MAX_EVENTS + 16, W.EVENT_FIELDS))
        latches = np.zeros((n, W.LATCH_FIELDS))
        losses = np.zeros(2 * n)  # each hinge's latch impacts, then its engagement
        y = run(words, settings, atol, points, events, latches, losses, dm, da, dq)
        if words[W.W_OVERFLOW] == 0.0:
            return words, y, points, events, latches, losses
        size *= 4


def substituted_run(backend: str) -> Any:
    """The wing's entry point in a backend (compiled once per process)."""
    from ecdsim.wing.kernel import equations
    from ecdsim.wing.kernel.loop import run_wing

    substitutes = (
        ("derivatives", equations.chain_derivatives),
        ("jacobian", equations.chain_jacobian),
        ("event_value", equations.chain_event_value),
    )
    return substituted(run_wing, backend, "wing", substitutes)


def _case(wing: Wing, temperature: float, rtol: float, stop_time: float, backend: str) -> WingCase:
    n = wing.size
    cw = _words(wing, temperature, stop_time, MAX_EVENTS)
    m = int(cw[W.W_M])
    na = int(cw[W.W_AUX])
    words, y, points, events, latches, losses = _run(cw, rtol, backend, m, n, na)
    used = points[: int(words[W.W_POINTS])]
    time, keep = np.unique(used[:, 0], return_index=True)
    # The last point at a repeated time is the state after its event.
    last = np.searchsorted(used[:, 0], time, side="right") - 1
    del keep
    angle = used[last, 1 : 1 + n]
    speed = used[last, 1 + n :]
    status = W.STATUS_NAMES[int(words[W.W_STATUS])]
    event_rows = events[: int(words[W.W_EVENTS])]
    found = tuple(
        WingEvent(float(t), W.EVENT_NAMES[int(k)], None if h < 0 else int(h))
        for t, k, h in event_rows
    )
    latch_events = []
    for row in latches[: int(words[W.W_LATCHES])]:
        j = int(row[W.LATCH_HINGE])
        rigid = wing.hinges[j].latch.rigid
        latch_events.append(
            LatchEvent(
                hinge=j,
                time=float(row[W.LATCH_TIME]),
                speed=float(row[W.LATCH_SPEED]),
                kinetic_energy=float(row[W.LATCH_KE]),
                impact_loss=float(row[W.LATCH_LOSS]),
                peak_torque=None if rigid else float(words[W.hinge(W.H_PEAK, j)]),
                impulse=float(row[W.LATCH_IMPULSE])
                if rigid and math.isfinite(row[W.LATCH_IMPULSE])
                else None,
            )
        )
    final_phi = np.array(
        [words[W.hinge(W.H_FACTOR, j)] * y[int(words[W.hinge(W.H_GROUP, j)])] for j in range(n)]
    )
    stuck = tuple(
        j
        for j in range(n)
        if status != "latched"
        and words[W.group(W.G_LOCKED, int(words[W.hinge(W.H_GROUP, j)]))] == 0.0
        and words[W.hinge(W.H_ENGAGED, j)] == 0.0
        and status == "stuck"
    )
    energy = _energy(wing, words, y, final_phi, losses, m, n, 2 * m + na)
    return WingCase(
        peak_damper_temperature=_peak_temperatures(words, temperature, n),
        temperature=float(temperature),
        time=time,
        angle=angle,
        speed=speed,
        events=found,
        latches=tuple(latch_events),
        status=status,
        stuck_hinges=stuck,
        energy=energy,
    )


def _peak_temperatures(words: FloatArray, temperature: float, n: int) -> tuple[float | None, ...]:
    """Each heated damper's peak temperature [degC] (None: not heated), from its largest
    log temperature state over the run's steps and events (the temperature grows with
    the state: dT/ds = f > 0, :mod:`ecdsim.physics.thermal`)."""
    peaks: list[float | None] = []
    for j in range(n):
        if words[W.hinge(W.H_AUX, j)] < 0.0:
            peaks.append(None)
            continue
        peaks.append(
            float(
                temperature_from_factor_log(
                    words[W.hinge(W.H_PEAK_LOG, j)],
                    temperature,
                    words[W.hinge(W.H_FA, j)],
                    words[W.hinge(W.H_COEF, j)],
                )
            )
        )
    return tuple(peaks)


def _energy(
    wing: Wing,
    words: FloatArray,
    y: FloatArray,
    phi: FloatArray,
    losses: FloatArray,
    m: int,
    n: int,
    e: int,
) -> WingEnergy:
    """The account: the drives' work (exact on their tables), gravity's, the kernel's
    dissipation quadratures, impact losses, the final kinetic and elastic energies."""
    from ecdsim.wing.kernel.equations import drive_work, kinetic

    spring = np.array([drive_work(words, j, float(phi[j])) for j in range(n)])
    arrays = wing.chain_arrays()
    gravity_work = 0.0
    if wing.ground_test is not None:
        gx, gy = wing.ground_test.gravity
        args = (
            arrays["mass"],
            arrays["cg_along"],
            arrays["cg_across"],
            arrays["length"],
            arrays["offload"],
            gx,
            gy,
        )
        gravity_work = chain.gravity_potential(
            wing.relative_angles(np.zeros(n)), *args
        ) - chain.gravity_potential(wing.relative_angles(phi), *args)
    cable_elastic = 0.0
    for c in wing.cables:
        if c.stiffness is not None and c.slack_torque is not None:
            cable_elastic += cable_energy(c.deflection(phi), c.stiffness, c.slack_torque)
    latch_elastic = sum(
        0.5 * float(h.latch.stiffness) * (phi[j] - h.travel) ** 2
        for j, h in enumerate(wing.hinges)
        if words[W.hinge(W.H_ENGAGED, j)] != 0.0 and h.latch.stiffness is not None
    )
    return WingEnergy(
        spring_work=spring,
        damper_dissipation=y[e : e + n].copy(),
        friction_dissipation=y[e + n : e + 2 * n].copy(),
        latch_dissipation=y[e + 2 * n : e + 3 * n].copy(),
        gear_loss=y[e + 3 * n : e + 4 * n].copy(),
        impact_loss=losses[:n].copy(),
        engagement_loss=losses[n:].copy(),
        gravity_work=float(gravity_work),
        final_kinetic=kinetic(words, y, m),
        cable_elastic=float(cable_elastic),
        latch_elastic=float(latch_elastic),
    )


def deploy_wing(
    wing: Wing,
    temperatures: Sequence[float],
    *,
    rtol: float = DEFAULT_RTOL,
    stop_time: float = math.inf,
    backend: str | None = None,
) -> WingResult:
    """The wing's deployment at each temperature [degC] (module notes).

    ``backend``: ``"numba"`` (the default where available), ``"python"`` (the same
    functions uncompiled) or ``"scipy"`` (scipy's Radau stepping the same equations).
    """
    check_supported(wing)
    name = resolve_name(backend)
    cases = tuple(_case(wing, float(t), rtol, stop_time, name) for t in temperatures)
    hinges = tuple(h.name for h in wing.hinges)
    return WingResult(wing.name, hinges, cases, source=f"ecdsim wing solver ({name})")
