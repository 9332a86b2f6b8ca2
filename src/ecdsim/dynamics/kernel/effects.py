"""The registry of hinge effects: an effect is one declaration here and a law in physics.

An :class:`Effect` declares its parameters (their config keys, SI units and the value
at which the effect is absent) and its torque on the load, a law of
:mod:`ecdsim.physics` ``torque(angle, speed, *parameters) -> T`` with its slopes
``slopes(angle, speed, *parameters) -> (dT/dangle, dT/dspeed)`` (angle the load's
deployed angle [rad], speed its speed [rad/s], T along deployment [N*m]). Everything
else is derived from :data:`REGISTRY`:

* the case table's columns (one per parameter, after ``layout.EFFECTS``), each effect's
  presence bit (a parameter off its absent value) and the paths that model it
  (``layout.KERNEL_EFFECTS``; ``layout.CLOSED_FORM_EFFECTS`` only where declared);
* the config keys ``[section] key`` read into ``DynamicParameters.effects`` and the
  ``DynamicProblem.effects`` the packer reads (:func:`config_values`, :func:`columns`);
* the kernel's sums :func:`registered_torque` and :func:`registered_terms`, generated
  below from the declarations (numba cannot loop over functions of different types) and
  compiled like every kernel function (:mod:`ecdsim.dynamics.kernel.build`): the hinge
  adds the torque to the load's forces, its slopes to the Jacobian, and its power
  ``-T speed`` to the hinge's dissipation, so that the energy balance closes;
* the refusals: a path that does not list an effect's bit does not take the case.

docs/architecture.md, "How to add an effect", walks through the bearing drag below.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

# The first column after layout.EFFECTS and the first bit after the built-in effects'
# (layout checks both at import).
FIRST_COLUMN = 38
FIRST_BIT = 8192


@dataclass(frozen=True)
class Parameter:
    """One parameter of an effect: its name (the ``effects`` key of DynamicParameters
    and DynamicProblem), its config key ``section.key``, its SI unit, a typical value
    (the registry's tests run every effect at it), the value at which the effect is
    absent (the default); values below ``minimum`` are refused."""

    name: str
    config: str
    unit: str
    example: float
    absent: float = 0.0
    minimum: float = 0.0


@dataclass(frozen=True)
class Effect:
    """A torque on the load written once: its law, slopes and parameters."""

    name: str
    parameters: tuple[Parameter, ...]
    torque: Callable[..., float]
    slopes: Callable[..., tuple[float, float]]
    closed_form: bool = False  # the closed form's linear segment models it


REGISTRY: tuple[Effect, ...] = ()

PARAMETERS: tuple[Parameter, ...] = tuple(p for e in REGISTRY for p in e.parameters)
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
    values: dict[str, Any] = {}
    for p in PARAMETERS:
        section, key = p.config.split(".")
        value = getattr(getattr(spec, section), key, None)
        if value is not None:
            values[p.name] = value
    return values


def columns(values: Mapping[str, Any]) -> dict[int, Any]:
    """The case table's registered columns from a problem's ``effects``."""
    return {COLUMN[p.name]: values.get(p.name, p.absent) for p in PARAMETERS}


def presence(row: Any) -> list[tuple[int, Any]]:
    """Each effect's bit and whether it is present, from a row of floats or the table's
    columns (``table.T``): a parameter off its absent value."""
    found: list[tuple[int, Any]] = []
    for effect in REGISTRY:
        present: Any = False
        for p in effect.parameters:
            present = present | (row[COLUMN[p.name]] != p.absent)
        found.append((BIT[effect.name], present))
    return found


def _generate() -> None:
    """Write :func:`registered_torque` and :func:`registered_terms` from the registry:
    for each effect present (its bit in the case's effects), its law at its columns."""
    torque = ["def registered_torque(cw, angle, speed):", "    total = 0.0"]
    terms = ["def registered_terms(cw, angle, speed):", "    t = a = s = 0.0"]
    if REGISTRY:
        torque.append(f"    bits = int(cw[{FIRST_COLUMN - 1}])")
        terms.append(f"    bits = int(cw[{FIRST_COLUMN - 1}])")
    for i, effect in enumerate(REGISTRY):
        args = ", ".join(f"cw[{COLUMN[p.name]}]" for p in effect.parameters)
        globals()[f"_torque_{i}"] = effect.torque
        globals()[f"_slopes_{i}"] = effect.slopes
        test = f"    if bits & {BIT[effect.name]}:"
        torque += [test, f"        total += _torque_{i}(angle, speed, {args})"]
        terms += [
            test,
            f"        t += _torque_{i}(angle, speed, {args})",
            f"        da, ds = _slopes_{i}(angle, speed, {args})",
            "        a += da",
            "        s += ds",
        ]
    source = "\n".join([*torque, "    return total", "", *terms, "    return t, a, s", ""])
    # Compiled against this file's name, so that numba's on-disk cache can locate it
    # (build.source_digest covers this file: the generated source follows it).
    exec(compile(source, __file__, "exec"), globals())


_generate()
registered_torque: Callable[[Any, float, float], float]
registered_terms: Callable[[Any, float, float], tuple[float, float, float]]
