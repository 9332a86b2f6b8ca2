"""The registry of hinge effects: a torque on the load is a law in physics and one entry.

An :class:`Effect` declares its parameters and its law ``torque(angle, speed, *params)``
with ``slopes(...) -> (dT/dangle, dT/dspeed)`` (the load's deployed angle [rad] and
speed [rad/s]; T along deployment [N*m]); a conservative one (gravity) names the
energy line its work goes to instead of the dissipation, and an angle-dependent one
lists where its stiffness takes a value (the rest test's search for an equilibrium).
Its columns, presence bit, config keys, the packer's refusals and the kernel's sums
(:func:`registered_torque`, :func:`registered_terms`, :func:`registered_level`,
generated below: numba cannot loop over functions of different types) derive from
:data:`REGISTRY` (docs/architecture.md, "How to add an effect").
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

from ecdsim.physics.gravity import (
    gravity_level_angle,
    gravity_level_count,
    gravity_load_slopes,
    gravity_load_torque,
    gravity_work,
)
from ecdsim.physics.mechanics import bearing_drag_slopes, bearing_drag_torque

FIRST_COLUMN, FIRST_BIT = 36, 4096  # after layout.EFFECTS and its bits (checked there)


@dataclass(frozen=True)
class Parameter:
    """A parameter: its ``effects`` key, config key ``section.key`` (None: the problem's
    field of its name, which the caller derives: gravity's from ``[load.gravity]``), SI
    unit, a typical value (the registry's tests use it), its absent value, least allowed
    value, and whether a value off ``absent`` makes the effect present (``switch``)."""

    name: str
    config: str | None
    unit: str
    example: float
    absent: float = 0.0
    minimum: float = 0.0
    switch: bool = True


@dataclass(frozen=True)
class Effect:
    """A torque on the load: its law and slopes (plain functions of physics/).

    ``stored``: the :class:`~ecdsim.dynamics.energy.EnergyBalance` line that takes a
    conservative effect's work ``work(start, end, *params)`` against it (its power is then
    not dissipated); None: dissipative, its power ``-T omega`` in the damper's account.
    ``level_count(slope, lo, hi, *params)`` and ``level_angle(slope, lo, hi, i, *params)``:
    the candidate angles in ``[lo, hi]`` where an angle-dependent effect's stiffness
    ``dT/dangle`` is ``-slope`` (where a push at rest can turn); None: it has none."""

    name: str
    parameters: tuple[Parameter, ...]
    torque: Callable[..., float]
    slopes: Callable[..., tuple[float, float]]
    closed_form: bool = False  # the closed form's linear segment models it
    stored: str | None = None
    work: Callable[..., Any] | None = None
    level_count: Callable[..., int] | None = None
    level_angle: Callable[..., float] | None = None


REGISTRY: tuple[Effect, ...] = (
    # The worked example of docs/architecture.md: a viscous hinge-bearing drag.
    Effect(
        "bearing_drag",
        (Parameter("bearing_drag", "load.bearing_drag", "N*m*s/rad", example=0.5),),
        bearing_drag_torque,
        bearing_drag_slopes,
    ),
    # A ground test's gravity, T = -W sin(theta_0 + phi) (physics/gravity.py): predict
    # sets W and theta_0 from [load.gravity] (mass, CG radius, offload, release angle).
    Effect(
        "gravity",
        (
            Parameter("gravity_amplitude", None, "N*m", example=2.0),
            Parameter("gravity_angle", None, "rad", 1.0, minimum=-math.inf, switch=False),
        ),
        gravity_load_torque,
        gravity_load_slopes,
        stored="gravity_work",
        work=gravity_work,
        level_count=gravity_level_count,
        level_angle=gravity_level_angle,
    ),
)

PARAMETERS = tuple(p for e in REGISTRY for p in e.parameters)
COLUMN = {p.name: FIRST_COLUMN + i for i, p in enumerate(PARAMETERS)}
END_COLUMN = FIRST_COLUMN + len(PARAMETERS)
BIT = {e.name: FIRST_BIT << i for i, e in enumerate(REGISTRY)}
REGISTERED_BITS = sum(BIT.values())
CLOSED_FORM_BITS = sum(BIT[e.name] for e in REGISTRY if e.closed_form)


def check(values: Mapping[str, Any]) -> None:
    """Refuse an unknown parameter or a value below its minimum (ValueError)."""
    import numpy as np

    known = {p.name: p for p in PARAMETERS}
    for name, value in values.items():
        if name not in known:
            raise ValueError(f"unknown effect parameter {name!r}; known: {sorted(known)}")
        if not np.all(np.asarray(value, dtype=float) >= known[name].minimum):
            raise ValueError(f"{name} must be >= {known[name].minimum:g} {known[name].unit}")


def config_values(spec: object) -> dict[str, Any]:
    """The registered parameters a config gives (``section.key``), absent ones left out."""
    found = {p.name: getattr(getattr(spec, p.config.split(".")[0]), p.config.split(".")[1])
             for p in PARAMETERS if p.config is not None}  # fmt: skip
    return {name: value for name, value in found.items() if value is not None}


def problem_values(problem: object) -> dict[str, Any]:
    """A problem's registered parameters: its ``effects`` and, for a parameter without a
    config key, the problem's field of its name where set (gravity's)."""
    fields = {p.name: getattr(problem, p.name, None) for p in PARAMETERS if p.config is None}
    values: dict[str, Any] = {k: v for k, v in fields.items() if v is not None}
    values.update(getattr(problem, "effects", {}))
    return values


def columns(values: Mapping[str, Any]) -> dict[int, Any]:
    """The case table's registered columns from a problem's :func:`problem_values`."""
    return {COLUMN[p.name]: values.get(p.name, p.absent) for p in PARAMETERS}


def presence(row: Any) -> list[tuple[int, Any]]:
    """Each effect's bit and whether a switching parameter is off its absent value, from
    one row of floats or the table's columns (``table.T``)."""
    found: list[tuple[int, Any]] = []
    for effect in REGISTRY:
        present: Any = False
        for p in effect.parameters:
            if p.switch:
                present = present | (row[COLUMN[p.name]] != p.absent)
        found.append((BIT[effect.name], present))
    return found


def stored_work(table: Any, bits: Any, start: Any, end: Any) -> dict[str, Any]:
    """The conservative effects' work from ``start`` to ``end`` by their energy line
    (0 in a case without the effect), for the lines of effects some case has."""
    import numpy as np

    lines: dict[str, Any] = {}
    for effect in REGISTRY:
        present = (bits.astype(np.int64) & BIT[effect.name]) != 0
        if effect.stored is None or effect.work is None or not np.any(present):
            continue
        params = [table[:, COLUMN[p.name]] for p in effect.parameters]
        work = np.where(present, effect.work(start, end, *params), 0.0)
        lines[effect.stored] = lines.get(effect.stored, 0.0) + work
    return lines


def _generate() -> None:
    """Write the kernel's sums from the registry, one ``if bits & BIT:`` block per effect
    present (its bit in the case's effects, column FIRST_COLUMN - 1):
    ``registered_torque(cw, angle, speed) -> (T, p)``, the torque and the power into the
    damper's account (``-T omega`` of the dissipative effects); ``registered_terms`` the
    same with their slopes, ``(T, dT/dangle, dT/dspeed, p, dp/dangle, dp/dspeed)``;
    ``registered_level(cw, slope, lo, hi, i)``, candidate i of the angles where an
    effect's stiffness is ``-slope`` (NaN past the last)."""
    head = [f"    bits = int(cw[{FIRST_COLUMN - 1}])"] if REGISTRY else []
    torque = ["def registered_torque(cw, angle, speed):", "    t = p = 0.0", *head]
    terms = ["def registered_terms(cw, angle, speed):", "    t = a = s = p = pa = ps = 0.0", *head]
    level = ["def registered_level(cw, slope, lo, hi, i):", *head]
    for k, effect in enumerate(REGISTRY):
        args = ", ".join(f"cw[{COLUMN[p.name]}]" for p in effect.parameters)
        names = {"torque": effect.torque, "slopes": effect.slopes,
                 "count": effect.level_count, "angle": effect.level_angle}  # fmt: skip
        globals().update({f"_{name}_{k}": law for name, law in names.items()})
        test = f"    if bits & {BIT[effect.name]}:"
        lost = effect.stored is None  # dissipative: its power goes to the damper's account
        torque += [test, f"        x = _torque_{k}(angle, speed, {args})", "        t += x"]
        torque += ["        p -= x * speed"] if lost else []
        terms += [
            test,
            f"        x = _torque_{k}(angle, speed, {args})",
            f"        da, ds = _slopes_{k}(angle, speed, {args})",
            "        t += x",
            "        a += da",
            "        s += ds",
        ]
        terms += (
            ["        p -= x * speed", "        pa -= da * speed", "        ps -= x + ds * speed"]
            if lost
            else []
        )
        if effect.level_count is not None:
            level += [
                test,
                f"        n = _count_{k}(slope, lo, hi, {args})",
                "        if i < n:",
                f"            return _angle_{k}(slope, lo, hi, i, {args})",
                "        i -= n",
            ]
    source = [*torque, "    return t, p", "", *terms, "    return t, a, s, p, pa, ps", ""]
    source += [*level, "    return math.nan", ""]
    # Compiled under this file's name, for numba's on-disk cache (whose key includes a
    # digest of this file: kernel.build.source_digest).
    exec(compile("\n".join(source), __file__, "exec"), globals())


_generate()
registered_torque: Callable[[Any, float, float], tuple[float, float]]
registered_terms: Callable[[Any, float, float], tuple[float, float, float, float, float, float]]
registered_level: Callable[[Any, float, float, float, int], float]
