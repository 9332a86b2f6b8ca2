"""The registry of hinge effects: a torque on the load is a law in physics and one entry.

An :class:`Effect` declares its parameters and its law ``torque(angle, speed, *params)``
with ``slopes(...) -> (dT/dangle, dT/dspeed)`` (the load's deployed angle [rad] and
speed [rad/s]; T along deployment [N*m]). Its columns, presence bit, config keys, the
packer's refusals and the kernel's sum :func:`registered_terms` (generated below: numba
cannot loop over functions of different types) derive from :data:`REGISTRY`
(docs/architecture.md, "How to add an effect").
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

from ecdsim.physics.mechanics import bearing_drag_slopes, bearing_drag_torque

FIRST_COLUMN, FIRST_BIT = 38, 8192  # after layout.EFFECTS and its bits (checked there)


@dataclass(frozen=True)
class Parameter:
    """A parameter: its ``effects`` key, config key ``section.key``, SI unit, a typical
    value (the registry's tests use it), its absent value and least allowed value."""

    name: str
    config: str
    unit: str
    example: float
    absent: float = 0.0
    minimum: float = 0.0


@dataclass(frozen=True)
class Effect:
    """A torque on the load: its law and slopes (plain functions of physics/)."""

    name: str
    parameters: tuple[Parameter, ...]
    torque: Callable[..., float]
    slopes: Callable[..., tuple[float, float]]
    closed_form: bool = False  # the closed form's linear segment models it


REGISTRY: tuple[Effect, ...] = (
    # The worked example of docs/architecture.md: a viscous hinge-bearing drag.
    Effect(
        "bearing_drag",
        (Parameter("bearing_drag", "load.bearing_drag", "N*m*s/rad", example=0.5),),
        bearing_drag_torque,
        bearing_drag_slopes,
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
             for p in PARAMETERS}  # fmt: skip
    return {name: value for name, value in found.items() if value is not None}


def columns(values: Mapping[str, Any]) -> dict[int, Any]:
    """The case table's registered columns from a problem's ``effects``."""
    return {COLUMN[p.name]: values.get(p.name, p.absent) for p in PARAMETERS}


def presence(row: Any) -> list[tuple[int, Any]]:
    """Each effect's bit and whether a parameter is off its absent value, from one row
    of floats or the table's columns (``table.T``)."""
    found: list[tuple[int, Any]] = []
    for effect in REGISTRY:
        present: Any = False
        for p in effect.parameters:
            present = present | (row[COLUMN[p.name]] != p.absent)
        found.append((BIT[effect.name], present))
    return found


def _generate() -> None:
    """Write :func:`registered_terms` from the registry: the torque and slopes of each
    effect present (its bit in the case's effects, column FIRST_COLUMN - 1)."""
    lines = ["def registered_terms(cw, angle, speed):", "    t = a = s = 0.0"]
    lines += [f"    bits = int(cw[{FIRST_COLUMN - 1}])"] if REGISTRY else []
    for i, effect in enumerate(REGISTRY):
        args = ", ".join(f"cw[{COLUMN[p.name]}]" for p in effect.parameters)
        globals()[f"_torque_{i}"], globals()[f"_slopes_{i}"] = effect.torque, effect.slopes
        lines += [
            f"    if bits & {BIT[effect.name]}:",
            f"        t += _torque_{i}(angle, speed, {args})",
            f"        da, ds = _slopes_{i}(angle, speed, {args})",
            "        a += da",
            "        s += ds",
        ]
    # Compiled under this file's name, for numba's on-disk cache (whose key includes a
    # digest of this file: kernel.build.source_digest).
    exec(compile("\n".join([*lines, "    return t, a, s", ""]), __file__, "exec"), globals())


_generate()
registered_terms: Callable[[Any, float, float], tuple[float, float, float]]
