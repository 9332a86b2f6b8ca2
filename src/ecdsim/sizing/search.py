"""Catalogue search: every damper x every gearbox ratio x every temperature in one pass.

The candidates are stacked along a leading batch axis of one :class:`~ecdsim.model.Ecd`
whose parameters are arrays (shape ``(n_candidates, 1)``), so a single call of
:func:`ecdsim.deployment.predict` with the exact solver evaluates Eq. 1-4 and the exact
deployment for the whole catalogue over the requirement temperatures (batch shape
``(n_candidates, n_temperatures)``). No formula is repeated here: every number comes from
the model objects, the solver and :mod:`ecdsim.sizing.requirements` /
:mod:`ecdsim.sizing.margin`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from ecdsim._types import ArrayLike, BoolArray, FloatArray, as_float
from ecdsim._version import __version__
from ecdsim.deployment import Prediction, predict
from ecdsim.model import (
    DeploymentSystem,
    Ecd,
    Gearbox,
    HighSpeedDamper,
    Load,
    TemperatureLaw,
)
from ecdsim.physics.assembly import damper_torque
from ecdsim.sizing.catalogue import ILLUSTRATIVE, Catalogue, DamperEntry, GearboxEntry
from ecdsim.sizing.margin import TorqueMarginTerms, margin_over_travel
from ecdsim.sizing.requirements import (
    Requirements,
    max_time_margin,
    min_time_margin,
    stall_margin,
    upper_limit_margin,
)


@dataclass(frozen=True)
class StackedTemperatureLaw:
    """Several temperature laws stacked on a new leading axis (one per candidate).

    ``law(T)`` has shape ``(n_laws, *shape(T))``, so that it broadcasts against model
    parameters of shape ``(n_laws, 1)``.
    """

    laws: tuple[TemperatureLaw, ...]

    def __call__(self, temperature: ArrayLike) -> FloatArray:
        """Each law at T [degC], stacked."""
        t = as_float(temperature)
        return as_float(np.stack([np.broadcast_to(law(t), t.shape) for law in self.laws]))

    def out_of_range(self, temperature: ArrayLike) -> BoolArray:
        """Each law's out-of-range flags at T [degC], stacked."""
        t = as_float(temperature)
        return np.stack([np.broadcast_to(law.out_of_range(t), t.shape) for law in self.laws])

    def describe(self) -> str:
        """One-line description."""
        return f"{len(self.laws)} stacked laws"


def _column(values: Sequence[float]) -> FloatArray:
    return as_float(values).reshape(-1, 1)


def stack_ecd(dampers: Sequence[HighSpeedDamper], gearboxes: Sequence[Gearbox]) -> Ecd:
    """One array-valued ECD whose leading axis runs over (damper, gearbox) pairs.

    Dampers rated at different reference temperatures are re-referred to the first one's:
    BD' = BD_T at the common reference (the model's own law) and c' = c * BD / BD', which
    gives the same BD_T at every T (BD' (1 + c' (T - T')) = BD (1 + c (T - T_ref))).
    The gearbox damping is resolved against each candidate's damper by the model
    (``Gearbox.damping_rate_for``). Linear-range limits are left out (checked per
    candidate by the search); lost motion is reported, not modelled (quasi-static).
    """
    if len(dampers) != len(gearboxes) or not dampers:
        raise ValueError("give one gearbox per damper, at least one pair")
    reference = dampers[0].reference_temperature
    rates, coefficients = [], []
    for damper in dampers:
        bd_common = float(damper.damping_rate_at(reference))
        if not bd_common > 0.0:
            raise ValueError(f"BD_T <= 0 at the common reference temperature {reference:g} degC")
        rates.append(bd_common)
        c = float(np.asarray(damper.damping_temperature_coefficient))
        coefficients.append(c * float(np.asarray(damper.damping_rate)) / bd_common)
    stacked = HighSpeedDamper(
        damping_rate=_column(rates),
        coulomb_friction=_column([float(np.asarray(d.coulomb_friction)) for d in dampers]),
        lubrication_friction=StackedTemperatureLaw(tuple(d.lubrication_friction for d in dampers)),
        reference_temperature=reference,
        damping_temperature_coefficient=_column(coefficients),
    )
    gearbox = Gearbox(
        ratio=_column([float(np.asarray(g.ratio)) for g in gearboxes]),
        coulomb_friction=_column([float(np.asarray(g.coulomb_friction)) for g in gearboxes]),
        damping_rate=_column(
            [float(g.damping_rate_for(d)) for g, d in zip(gearboxes, dampers, strict=True)]
        ),
    )
    return Ecd(stacked, gearbox)


@dataclass(frozen=True)
class Limits:
    """Catalogue limits per candidate (shape ``(n_candidates,)``); NaN where none is given.

    Attributes
    ----------
    damper_max_torque : largest torque at the damper shaft [N*m]
    damper_max_linear_speed : end of the damper's linear range, shaft speed [rad/s]
    damper_max_linear_torque : end of the damper's linear range, eddy-current torque [N*m]
    gearbox_max_output_torque : largest torque at the gearbox's slow shaft [N*m]
    """

    damper_max_torque: FloatArray
    damper_max_linear_speed: FloatArray
    damper_max_linear_torque: FloatArray
    gearbox_max_output_torque: FloatArray

    @classmethod
    def of(cls, pairs: Sequence[tuple[DamperEntry, GearboxEntry]]) -> Limits:
        """The limits of (damper, gearbox) pairs."""

        def column(values: Sequence[float | None]) -> FloatArray:
            return as_float([np.nan if v is None else v for v in values])

        return cls(
            damper_max_torque=column([d.max_torque for d, _ in pairs]),
            damper_max_linear_speed=column([d.damper.max_linear_speed for d, _ in pairs]),
            damper_max_linear_torque=column([d.damper.max_linear_torque for d, _ in pairs]),
            gearbox_max_output_torque=column([g.max_output_torque for _, g in pairs]),
        )


@dataclass(frozen=True)
class Check:
    """One requirement or catalogue limit over the candidates and temperatures.

    Attributes
    ----------
    name : stable machine name ("max_deployment_time", "no_stall", ...)
    label : the requirement in words, with its limit
    unit : unit of ``values``
    values : the checked quantity, shape (n_candidates, n_temperatures)
    margins : its margin (>= 0 is met; docs/sizing.md), same shape
    applicable : False for candidates without this limit, shape (n_candidates,)
    cannot_start : True where the mechanism cannot start, so that a torque check has no
        running torque to check (``values`` then holds the torque the ECD holds at rest,
        which keeps the margin continuous in N); None for checks this does not concern
    """

    name: str
    label: str
    unit: str
    values: FloatArray
    margins: FloatArray
    applicable: BoolArray
    cannot_start: BoolArray | None = None

    def worst(self) -> FloatArray:
        """Smallest margin over the temperatures, per candidate; +inf where not applicable."""
        return as_float(np.where(self.applicable, np.min(self.margins, axis=-1), np.inf))

    def worst_index(self) -> FloatArray:
        """Index of the temperature with the smallest margin, per candidate."""
        return np.asarray(np.argmin(self.margins, axis=-1))


@dataclass(frozen=True)
class Evaluation:
    """Every check of a batch of candidates at the requirement temperatures.

    Arrays have shape (n_candidates, n_temperatures).

    Attributes
    ----------
    temperatures : T [degC], shape (n_temperatures,)
    prediction : the exact deployment of every candidate at every temperature
    checks : the requirements and catalogue limits, with margins
    input_torque : peak ECD reaction at its input shaft, FECD_T + BECD_T * omega_max [N*m];
        where the mechanism cannot start, the torque it holds at rest, max(T_s - FS_T, 0)
    cannot_start : True where the spring cannot start the deployment (stall at angle 0)
    damper_shaft_speed : peak damper shaft speed, N * omega_max [rad/s]
    damper_shaft_torque : peak damper torque at its shaft, BD_T * omega_d + FD + FL_T [N*m]
    torque_margin : smallest torque margin over the travel [-]
    torque_margin_angle : deployed angle where it occurs [rad]
    torque_margin_terms : every term of that smallest margin (drive, resistive torques
        by kind, factored sum), each of shape (n_candidates, n_temperatures)
    """

    temperatures: FloatArray
    prediction: Prediction
    checks: tuple[Check, ...]
    input_torque: FloatArray
    cannot_start: BoolArray
    damper_shaft_speed: FloatArray
    damper_shaft_torque: FloatArray
    torque_margin: FloatArray
    torque_margin_angle: FloatArray
    torque_margin_terms: TorqueMarginTerms

    def check(self, name: str) -> Check:
        """The check called ``name``."""
        for check in self.checks:
            if check.name == name:
                return check
        raise KeyError(f"no check {name!r}; evaluated: {[c.name for c in self.checks]}")

    def overall(self) -> FloatArray:
        """Smallest margin over every check and temperature, per candidate (+inf if none)."""
        n = self.prediction.problem.batch_shape[0]
        worst = [c.worst() for c in self.checks]
        return as_float(np.min(np.stack(worst), axis=0)) if worst else np.full(n, np.inf)

    def passed(self) -> BoolArray:
        """True where every check holds at every temperature."""
        return np.asarray(self.overall() >= 0.0)


def evaluate(
    ecd: Ecd, load: Load, requirements: Requirements, limits: Limits | None = None
) -> Evaluation:
    """Evaluate every requirement for an array-valued ECD (leading axis = candidates).

    One call of :func:`ecdsim.deployment.predict` with the exact solver; the margins come
    from :mod:`ecdsim.sizing.requirements` and :mod:`ecdsim.sizing.margin`. Raises
    :class:`~ecdsim.deployment.ModelDomainError` where a damping rate is <= 0.
    """
    temps = as_float(requirements.temperatures)
    prediction = predict(DeploymentSystem(ecd, load, "sizing"), temps, ("exact",))
    solution = prediction.solutions["exact"]
    state = prediction.ecd
    problem = prediction.problem
    shape = problem.batch_shape

    def full(value: ArrayLike) -> FloatArray:
        return as_float(np.broadcast_to(as_float(value), shape))

    time = full(solution.deployment_time)
    end_speed = full(solution.end_speed)
    peak = full(solution.max_speed)
    # A mechanism that cannot start (stall at the first angle) has no running input
    # torque: the ECD then holds what the spring applies beyond the system friction, never
    # its own friction capacity FECD_T (which can exceed the spring torque). That held
    # torque equals FECD_T + BECD_T * 0 at the start boundary, so the margin stays
    # continuous in N; the outputs say "cannot start" instead of a value.
    stall_angle = np.broadcast_to(solution.stall_angle, shape)
    cannot_start = np.broadcast_to(solution.stalled, shape) & (stall_angle <= problem.angles[0])
    held = np.maximum(problem.torques[0] - prediction.system_friction, 0.0)
    running = state.ecd_friction + state.ecd_damping_rate * peak
    input_torque = full(np.where(cannot_start, held, running))
    shaft_speed = full(peak * state.gear_ratio)
    eddy = full(damper_torque(state.damper_damping_rate, shaft_speed))
    shaft_torque = full(eddy + state.damper_friction + state.lubrication_friction)
    terms = margin_over_travel(
        problem.angles,
        problem.torques,
        ecd_friction=state.ecd_friction,
        system_friction=prediction.system_friction,
        damping_rate=problem.damping_rate,
        stalled=solution.stalled,
        stall_angle=solution.stall_angle,
        settings=requirements.margin,
        resistance=prediction.resistance,
        # A ground test's gravity (docs/sizing.md); None in flight, as before.
        gravity_amplitude=problem.gravity_amplitude if problem.has_gravity else None,
        gravity_angle=problem.gravity_angle if problem.has_gravity else None,
        forward_efficiency=(None if ecd.gearbox.efficiency is None else state.forward_efficiency),
    ).at_minimum()
    terms = TorqueMarginTerms(
        margin=full(terms.margin),
        angle=full(terms.angle),
        drive=full(terms.drive),
        resistive={kind: full(torque) for kind, torque in terms.resistive.items()},
        factored=full(terms.factored),
    )
    torque_margin, torque_margin_angle = terms.margin, terms.angle
    everyone = np.ones(shape[0], dtype=bool)
    r = requirements
    checks: list[Check] = []
    if r.min_deployment_time is not None:
        label = f"deployment time >= {r.min_deployment_time:g} s"
        margins = min_time_margin(time, r.min_deployment_time)
        checks.append(Check("min_deployment_time", label, "s", time, margins, everyone))
    if r.max_deployment_time is not None:
        label = f"deployment time <= {r.max_deployment_time:g} s"
        margins = max_time_margin(time, r.max_deployment_time)
        checks.append(Check("max_deployment_time", label, "s", time, margins, everyone))
    if r.max_end_speed is not None:
        label = f"end speed <= {r.max_end_speed:g} rad/s"
        margins = upper_limit_margin(end_speed, r.max_end_speed)
        checks.append(Check("max_end_speed", label, "rad/s", end_speed, margins, everyone))
    if r.max_input_torque is not None:
        label = f"ECD input torque <= {r.max_input_torque:g} N*m"
        margins = upper_limit_margin(input_torque, r.max_input_torque)
        checks.append(
            Check("max_input_torque", label, "N*m", input_torque, margins, everyone, cannot_start)
        )
    if r.no_stall:
        net = full(np.min(problem.torques, axis=0) - problem.friction)
        margins = full(stall_margin(problem.torques, problem.friction))
        checks.append(Check("no_stall", "no stall", "N*m", net, margins, everyone))
    if r.min_torque_margin is not None:
        label = f"torque margin >= {r.min_torque_margin:g}"
        margins = full(torque_margin - r.min_torque_margin)
        values = full(torque_margin)
        checks.append(Check("min_torque_margin", label, "-", values, margins, everyone))
    if limits is not None:
        catalogue_checks = [
            ("damper_max_torque", "damper torque <= catalogue max", "N*m", shaft_torque,
             limits.damper_max_torque),
            ("damper_linear_speed", "damper speed <= linear-range limit", "rad/s", shaft_speed,
             limits.damper_max_linear_speed),
            ("damper_linear_torque", "damper eddy torque <= linear-range limit", "N*m", eddy,
             limits.damper_max_linear_torque),
            ("gearbox_max_output_torque", "gearbox torque <= catalogue max", "N*m",
             input_torque, limits.gearbox_max_output_torque),
        ]  # fmt: skip
        for name, label, unit, values, limit in catalogue_checks:
            given = np.broadcast_to(np.isfinite(limit), (shape[0],))
            if np.any(given):
                margins = full(upper_limit_margin(values, as_float(limit).reshape(-1, 1)))
                held = cannot_start if unit == "N*m" else None
                checks.append(Check(name, label, unit, values, margins, np.array(given), held))
    return Evaluation(
        temperatures=temps,
        prediction=prediction,
        checks=tuple(checks),
        input_torque=input_torque,
        cannot_start=np.asarray(cannot_start),
        damper_shaft_speed=shaft_speed,
        damper_shaft_torque=shaft_torque,
        torque_margin=torque_margin,
        torque_margin_angle=torque_margin_angle,
        torque_margin_terms=terms,
    )


@dataclass(frozen=True)
class Candidate:
    """One catalogue combination: a damper behind a gearbox at one of its ratios."""

    damper: DamperEntry
    gearbox: GearboxEntry
    ratio: float

    @property
    def mass(self) -> float | None:
        """Damper plus gearbox mass [kg]; None (unknown) if either is not known.

        A damper whose catalogue mass includes a gearbox (``mass_includes_gearbox``, an
        assembly mass) has that mass with that gearbox, and an unknown mass with any other.
        """
        return self._mass()[0]

    @property
    def mass_note(self) -> str | None:
        """Why the mass is unknown, or what an assembly mass includes; None otherwise."""
        return self._mass()[1]

    def _mass(self) -> tuple[float | None, str | None]:
        d, g = self.damper, self.gearbox
        if d.mass_includes_gearbox is not None:
            if d.mass_includes_gearbox == g.name:
                return d.mass, f"assembly mass of {d.name!r} with {g.name!r}"
            return None, (
                f"unknown: {d.name!r} has only an assembly mass (with {d.mass_includes_gearbox!r})"
            )
        if d.mass is not None and g.mass is not None:
            return d.mass + g.mass, None
        missing = [f"{kind} {e.name!r}" for kind, e in (("damper", d), ("gearbox", g))
                   if e.mass is None]  # fmt: skip
        return None, "unknown: no mass for " + " and ".join(missing)

    @property
    def illustrative(self) -> bool:
        """True if either entry is illustrative (invented) data."""
        return self.damper.illustrative or self.gearbox.illustrative

    @property
    def label(self) -> str:
        """``damper + gearbox N:1``."""
        return f"{self.damper.name} + {self.gearbox.name} {self.ratio:g}:1"

    def ecd(self) -> Ecd:
        """The scalar model ECD of this combination."""
        return Ecd(self.damper.damper, self.gearbox.gearbox(self.ratio))


def _optional(value: float) -> float | None:
    return float(value) if np.isfinite(value) else None


@dataclass(frozen=True)
class CheckOutcome:
    """One check's result for one candidate.

    Attributes
    ----------
    name : machine name of the check
    label : the check in words
    margin : smallest margin over the temperatures [-]
    passed : margin >= 0
    temperature_C : temperature of the smallest margin [degC]
    value : the checked quantity there, in ``unit``
    unit : unit of ``value``
    cannot_start : True if the mechanism cannot start at that temperature: a torque
        check then has no running torque ("cannot start"; ``value`` is the torque held
        at rest, and JSON gives null)
    margins : the margin at each requirement temperature, in their order [-]
    values : the checked quantity at each requirement temperature, in ``unit``
    """

    name: str
    label: str
    margin: float
    passed: bool
    temperature_C: float
    value: float
    unit: str
    cannot_start: bool = False
    margins: tuple[float, ...] = ()
    values: tuple[float, ...] = ()

    @property
    def result(self) -> str:
        """``"pass"``, ``"FAIL"`` or ``"cannot start"``."""
        if self.cannot_start:
            return "cannot start"
        return "pass" if self.passed else "FAIL"

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form (infinite numbers become null)."""
        return {
            "name": self.name,
            "label": self.label,
            "margin": _optional(self.margin),
            "passed": self.passed,
            "cannot_start": self.cannot_start,
            "temperature_C": self.temperature_C,
            "value": None if self.cannot_start else _optional(self.value),
            "unit": self.unit,
            "margins": [_optional(m) for m in self.margins],
            "values": [_optional(v) for v in self.values],
        }


@dataclass(frozen=True)
class TorqueMarginAt:
    """The torque margin at one temperature, with its terms (docs/sizing.md section 5).

    Every torque is at the ECD's input shaft, at the angle where the margin is smallest.

    Attributes
    ----------
    temperature_C : T [degC]
    margin : TM = drive / factored - 1 [-]
    angle : deployed angle where it is smallest [rad]
    drive : spring torque there [N*m]
    resistive : unfactored resistive torque by kind there [N*m]
    factored : sum of the factored resistive torques [N*m]
    """

    temperature_C: float
    margin: float
    angle: float
    drive: float
    resistive: dict[str, float]
    factored: float

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form (infinite numbers become null)."""
        return {
            "margin": _optional(self.margin),
            "angle_rad": self.angle,
            "drive_Nm": self.drive,
            "resistive_Nm": dict(self.resistive),
            "factored_resistance_Nm": self.factored,
        }


@dataclass(frozen=True)
class CandidateResult:
    """Everything the search found about one candidate.

    Attributes
    ----------
    candidate : the combination
    rank : 1 = best
    passed : every check holds at every temperature
    margin : smallest margin over every check [-] (None if the model is invalid)
    spread : max - min deployment time over the temperatures [s] (inf if it stalls)
    checks : each check's outcome
    temperatures : T [degC]
    deployment_time : exact deployment time at each T [s] (inf where stalled)
    end_speed : speed at the latch at each T [rad/s]
    input_torque : peak ECD input torque at each T [N*m]
    damping_rate : BECD_T at each T [N*m*s/rad]
    friction : FECD_T at each T [N*m]
    stalled : stall flag at each T
    cannot_start : True at each T where the spring cannot start the deployment
    torque_margins : the torque margin at each T with its terms
    torque_margin : smallest torque margin over travel and temperature [-]
    torque_margin_angle : where it occurs [rad]
    torque_margin_temperature : where it occurs [degC]
    error : why the model could not be evaluated, else None
    warnings : non-fatal findings (negative friction, a friction table extrapolated)
    """

    candidate: Candidate
    rank: int
    passed: bool
    margin: float | None
    spread: float
    checks: tuple[CheckOutcome, ...]
    temperatures: tuple[float, ...]
    deployment_time: tuple[float, ...] = ()
    end_speed: tuple[float, ...] = ()
    input_torque: tuple[float, ...] = ()
    damping_rate: tuple[float, ...] = ()
    friction: tuple[float, ...] = ()
    stalled: tuple[bool, ...] = ()
    cannot_start: tuple[bool, ...] = ()
    torque_margins: tuple[TorqueMarginAt, ...] = ()
    torque_margin: float | None = None
    torque_margin_angle: float | None = None
    torque_margin_temperature: float | None = None
    error: str | None = None
    warnings: tuple[str, ...] = ()

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form (infinite numbers become null)."""
        c = self.candidate
        return {
            "rank": self.rank,
            "damper": c.damper.name,
            "gearbox": c.gearbox.name,
            "ratio": c.ratio,
            "damper_source": c.damper.source,
            "gearbox_source": c.gearbox.source,
            "illustrative": c.illustrative,
            "mass_kg": c.mass,
            "mass_known": c.mass is not None,
            "mass_note": c.mass_note,
            "passed": self.passed,
            "margin": self.margin,
            "deployment_time_spread_s": _optional(self.spread),
            "checks": {o.name: o.to_dict() for o in self.checks},
            "cases": []
            if self.error is not None
            else [
                {
                    "temperature_C": t,
                    "deployment_time_s": _optional(time),
                    "end_speed_rad_s": speed,
                    "input_torque_Nm": None if held else torque,
                    "cannot_start": held,
                    "damping_rate_Nms_per_rad": b,
                    "friction_Nm": f,
                    "stalled": stalled,
                    "torque_margin": margin.to_dict(),
                }
                for t, time, speed, torque, held, b, f, stalled, margin in zip(
                    self.temperatures,
                    self.deployment_time,
                    self.end_speed,
                    self.input_torque,
                    self.cannot_start,
                    self.damping_rate,
                    self.friction,
                    self.stalled,
                    self.torque_margins,
                    strict=True,
                )
            ],
            "torque_margin": {
                "minimum": self.torque_margin,
                "angle_rad": self.torque_margin_angle,
                "temperature_C": self.torque_margin_temperature,
            },
            "lost_motion_rad": c.gearbox.lost_motion,
            "reflected_rotor_inertia_kg_m2": (
                None if c.damper.rotor_inertia is None else c.damper.rotor_inertia * c.ratio**2
            ),
            "error": self.error,
            "warnings": list(self.warnings),
        }


@dataclass(frozen=True)
class SearchResult:
    """The ranked catalogue search.

    Attributes
    ----------
    requirements : what was required
    candidates : every combination, best first
    catalogue_source : the catalogue file
    """

    requirements: Requirements
    candidates: tuple[CandidateResult, ...]
    catalogue_source: str

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form of the whole search (see docs/sizing.md)."""
        r = self.requirements
        return {
            "ecdsim_version": __version__,
            "catalogue": self.catalogue_source,
            "illustrative_label": ILLUSTRATIVE,
            "temperatures_C": list(r.temperatures),
            "requirements": {
                "min_deployment_time_s": r.min_deployment_time,
                "max_deployment_time_s": r.max_deployment_time,
                "max_end_speed_rad_s": r.max_end_speed,
                "max_input_torque_Nm": r.max_input_torque,
                "min_torque_margin": r.min_torque_margin,
                "no_stall": r.no_stall,
                "torque_margin": {
                    "factors": dict(r.margin.factors),
                    "factors_applied": r.margin.factors_applied,
                    "allowances_Nm": dict(r.margin.allowances),
                    "damping_speed_rad_s": r.margin.damping_speed,
                    "damping_speed_mode": r.margin.damping_mode,
                },
            },
            "candidates": [c.to_dict() for c in self.candidates],
        }


def catalogue_candidates(catalogue: Catalogue) -> list[Candidate]:
    """Every damper x every gearbox x every available ratio."""
    return [
        Candidate(d, g, r) for d in catalogue.dampers for g in catalogue.gearboxes for r in g.ratios
    ]


def _flags(evaluation: Evaluation) -> list[tuple[str, BoolArray]]:
    """Non-physical or extrapolated inputs, as (text, mask of shape (n, n_temps))."""
    prediction = evaluation.prediction
    shape = prediction.problem.batch_shape
    temps = evaluation.temperatures
    system = prediction.system
    laws = [
        ("lubrication friction table extrapolated", system.ecd.damper.lubrication_friction),
        ("system friction table extrapolated", system.load.system_friction),
    ]
    found = [
        ("FECD < 0 (friction law outside its range)", prediction.ecd.ecd_friction < 0.0),
        ("FS < 0 (friction law outside its range)", prediction.system_friction < 0.0),
    ] + [(text, law.out_of_range(temps)) for text, law in laws]
    return [(text, np.broadcast_to(np.asarray(mask), shape)) for text, mask in found]


def _results(
    candidates: Sequence[Candidate], evaluation: Evaluation
) -> list[tuple[Candidate, dict[str, Any]]]:
    temps = evaluation.temperatures
    solution = evaluation.prediction.solutions["exact"]
    state = evaluation.prediction.ecd
    shape = evaluation.prediction.problem.batch_shape
    overall = evaluation.overall()
    terms = evaluation.torque_margin_terms
    time = np.broadcast_to(solution.deployment_time, shape)
    stalled = np.broadcast_to(solution.stalled, shape)
    flags = _flags(evaluation)
    out = []
    for i, candidate in enumerate(candidates):
        outcomes = []
        for check in evaluation.checks:
            if not check.applicable[i]:
                continue
            j = int(check.worst_index()[i])
            margin = float(check.margins[i, j])
            held = check.cannot_start is not None and bool(check.cannot_start[i, j])
            outcomes.append(
                CheckOutcome(
                    check.name,
                    check.label,
                    margin,
                    margin >= 0.0,
                    float(temps[j]),
                    float(check.values[i, j]),
                    check.unit,
                    held,
                    tuple(float(m) for m in check.margins[i]),
                    tuple(float(v) for v in check.values[i]),
                )
            )
        spread = float(np.max(time[i]) - np.min(time[i])) if not np.any(stalled[i]) else np.inf
        tm = evaluation.torque_margin[i]
        k = int(np.argmin(tm))
        fields: dict[str, Any] = {
            "passed": bool(overall[i] >= 0.0),
            "margin": _optional(float(overall[i])),
            "spread": spread,
            "checks": tuple(outcomes),
            "temperatures": tuple(float(t) for t in temps),
            "deployment_time": tuple(float(x) for x in time[i]),
            "end_speed": tuple(float(x) for x in np.broadcast_to(solution.end_speed, shape)[i]),
            "input_torque": tuple(float(x) for x in evaluation.input_torque[i]),
            "damping_rate": tuple(
                float(x) for x in np.broadcast_to(state.ecd_damping_rate, shape)[i]
            ),
            "friction": tuple(float(x) for x in np.broadcast_to(state.ecd_friction, shape)[i]),
            "stalled": tuple(bool(x) for x in stalled[i]),
            "cannot_start": tuple(bool(x) for x in evaluation.cannot_start[i]),
            "torque_margins": tuple(
                TorqueMarginAt(
                    temperature_C=float(t),
                    margin=float(terms.margin[i, j]),
                    angle=float(terms.angle[i, j]),
                    drive=float(terms.drive[i, j]),
                    resistive={kind: float(v[i, j]) for kind, v in terms.resistive.items()},
                    factored=float(terms.factored[i, j]),
                )
                for j, t in enumerate(temps)
            ),
            "torque_margin": _optional(float(tm[k])),
            "torque_margin_angle": float(evaluation.torque_margin_angle[i, k]),
            "torque_margin_temperature": float(temps[k]),
            "warnings": tuple(
                f"{text} at {float(t):g} degC"
                for text, mask in flags
                for t, hit in zip(temps, mask[i], strict=True)
                if hit
            ),
        }
        out.append((candidate, fields))
    return out


def rank_key(result: CandidateResult) -> tuple[bool, bool, bool, float, float, float, str]:
    """Sort key: valid and passing first, then by mass (unknown after every known one),
    margin (larger first), spread."""
    mass = result.candidate.mass
    margin = result.margin if result.margin is not None else -np.inf
    return (
        result.error is not None,
        not result.passed,
        mass is None,
        0.0 if mass is None else mass,
        -margin,
        result.spread,
        result.candidate.label,
    )


def search(catalogue: Catalogue, load: Load, requirements: Requirements) -> SearchResult:
    """Evaluate and rank every catalogue combination against the requirements.

    All valid candidates are evaluated in one vectorised pass (:func:`evaluate`); a
    candidate whose damping law gives BECD <= 0 at a requirement temperature is reported
    with an error and ranked last.
    """
    candidates = catalogue_candidates(catalogue)
    temps = as_float(requirements.temperatures)
    valid: list[Candidate] = []
    rows: list[tuple[Candidate, dict[str, Any]]] = []
    for candidate in candidates:
        state = candidate.ecd().at(temps)
        bad = ~(np.broadcast_to(state.ecd_damping_rate, temps.shape) > 0.0)
        if np.any(bad):
            where = float(temps[bad][0])
            message = (
                f"the damping law gives BECD <= 0 at {where:g} degC "
                "(the linear temperature law does not reach that far)"
            )
            rows.append(
                (candidate, {"passed": False, "margin": None, "spread": np.inf,
                             "checks": (), "temperatures": tuple(float(t) for t in temps),
                             "error": message})
            )  # fmt: skip
        else:
            valid.append(candidate)
    if valid:
        ecd = stack_ecd(
            [c.damper.damper for c in valid], [c.gearbox.gearbox(c.ratio) for c in valid]
        )
        limits = Limits.of([(c.damper, c.gearbox) for c in valid])
        rows = _results(valid, evaluate(ecd, load, requirements, limits)) + rows
    unranked = [CandidateResult(candidate=c, rank=0, **fields) for c, fields in rows]
    ranked = sorted(unranked, key=rank_key)
    final = tuple(replace(r, rank=i) for i, r in enumerate(ranked, start=1))
    return SearchResult(requirements, final, catalogue.source)


def deployment_time_curves(
    candidates: Sequence[Candidate], load: Load, temperatures: ArrayLike
) -> FloatArray:
    """Exact deployment time of each candidate at each temperature [s] (for plots).

    One vectorised :func:`~ecdsim.deployment.predict` call; shape (n_candidates,
    n_temperatures), +inf where a candidate stalls. Raises
    :class:`~ecdsim.deployment.ModelDomainError` where a damping rate is <= 0.
    """
    ecd = stack_ecd(
        [c.damper.damper for c in candidates], [c.gearbox.gearbox(c.ratio) for c in candidates]
    )
    temps = as_float(temperatures).reshape(-1)
    prediction = predict(DeploymentSystem(ecd, load, "curves"), temps, ("exact",))
    shape = prediction.problem.batch_shape
    return as_float(np.broadcast_to(prediction.solutions["exact"].deployment_time, shape))


__all__ = [
    "Candidate",
    "CandidateResult",
    "Check",
    "CheckOutcome",
    "Evaluation",
    "Limits",
    "SearchResult",
    "StackedTemperatureLaw",
    "TorqueMarginAt",
    "catalogue_candidates",
    "deployment_time_curves",
    "evaluate",
    "rank_key",
    "search",
    "stack_ecd",
]
