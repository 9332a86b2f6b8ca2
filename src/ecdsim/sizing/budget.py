"""Torque budgets as flight programs keep them (docs/qualification.md).

A budget sets the drive's minimum available torque against the resistive torques, each
with the uncertainty factor of its kind::

    margin       = available / sum_i(f_i * T_i) - 1
    torque_ratio = available / sum_i(T_i)

The kinds are the user's (``known``/``unknown``, ECSS-E-ST-33-01C's kinds, a program's
own), factors may differ per program phase, and the arithmetic is that of the ECSS torque
margin of docs/sizing.md section 5 (:mod:`ecdsim.sizing.factored`, one implementation).

Two sources fill a budget:

* a budget file (``[budget]`` with ``available`` and ``[[budget.torque]]``):
  :func:`budget_from_file`;
* a deployment config: :func:`budget_from_config` takes every resistive torque the model
  holds (the ECD's Coulomb friction, its damping at a stated speed, the hinge friction,
  a ground test's gravity, resistive tables, a lossy mesh's loss) at every temperature,
  the spring's torque as the available torque, at the point of the travel where the
  margin is lowest (:func:`ecdsim.sizing.margin.margin_over_travel`), plus the config's
  own ``[[budget.torque]]`` entries. Simulation and budget are then one document.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from ecdsim._types import ArrayLike, FloatArray, as_float
from ecdsim._version import __version__
from ecdsim.sizing.factored import factored_sum, margin_over, torque_ratio
from ecdsim.sizing.margin import (
    MarginOverTravel,
    MarginSettings,
    factor_of,
    margin_over_travel,
)

if TYPE_CHECKING:
    from ecdsim.config import Config
    from ecdsim.config.budget_file import BudgetFile
    from ecdsim.config.budget_schema import BudgetSpec
    from ecdsim.deployment import Prediction


class BudgetError(ValueError):
    """A budget that cannot be built from a config; the message names the key."""


# Verdicts of one margin (JSON "verdict"); the second is the case programs grant waivers on.
POSITIVE = "positive margin"
WAIVER = "negative margin, torque ratio above 1"
NEGATIVE = "negative margin, torque ratio at or below 1"

# How each model torque is named in a budget filled from a config.
MODEL_NAMES = {
    "ecd_friction": "ECD friction FECD_T",
    "system_friction": "hinge friction FS_T",
    "damping": "ECD damping BECD_T * omega",
    "resistive_table": "resistive table",
    "gravity": "gravity (ground test)",
    "gear_loss": "gear mesh loss",
    "inertia": "inertia allowance",
    "spring": "resisting spring allowance",
    "harness": "harness allowance",
}


@dataclass(frozen=True)
class BudgetTerm:
    """One resistive torque of a budget.

    Attributes
    ----------
    name : what it is
    kind : its uncertainty kind (the factor's key)
    value : the unfactored torque [N*m]; one value per temperature from a config
    source : "budget" (entered) or "model" (computed from the config)
    """

    name: str
    kind: str
    value: FloatArray
    source: str = "budget"


@dataclass(frozen=True)
class PhaseMargin:
    """A budget under one phase's factors, at every temperature.

    Arrays have the temperatures' shape (``()`` for a budget file).

    Attributes
    ----------
    phase : the phase's name, "" for a budget without phases
    factors : the factor of each kind [-]; a kind not listed counts 1
    available : the available (driving) torque [N*m]
    terms : the resistive torques
    angle : the deployed angle of the budget [rad] (from a config: where the margin is
        lowest), None for a budget file
    """

    phase: str
    factors: Mapping[str, float]
    available: FloatArray
    terms: tuple[BudgetTerm, ...]
    angle: FloatArray | None = None

    def factor(self, term: BudgetTerm) -> float:
        """The factor of a term's kind [-] (1 where no factor is given)."""
        return float(self.factors.get(term.kind, 1.0))

    @property
    def total(self) -> FloatArray:
        """``sum_i(T_i)`` [N*m]."""
        return factored_sum((1.0, t.value) for t in self.terms)

    @property
    def factored(self) -> FloatArray:
        """``sum_i(f_i * T_i)`` [N*m]."""
        return factored_sum((self.factor(t), t.value) for t in self.terms)

    @property
    def margin(self) -> FloatArray:
        """``available / sum_i(f_i T_i) - 1`` [-]."""
        return margin_over(self.available, self.factored)

    @property
    def torque_ratio(self) -> FloatArray:
        """``available / sum_i(T_i)`` [-]."""
        return torque_ratio(self.available, self.total)

    def verdicts(self) -> list[str]:
        """Each temperature's verdict: positive margin, or negative with the torque ratio
        above 1 (a waiver case) or not."""
        margin = np.atleast_1d(self.margin)
        ratio = np.atleast_1d(np.broadcast_to(self.torque_ratio, margin.shape))
        return [
            POSITIVE if m >= 0.0 else (WAIVER if r > 1.0 else NEGATIVE)
            for m, r in zip(margin, ratio, strict=True)
        ]


@dataclass(frozen=True)
class TorqueBudget:
    """A torque budget under each phase's factors.

    Attributes
    ----------
    name : the budget's (or the config's) name
    source : the file it came from
    temperatures : the temperatures of a budget from a config [degC]; None for a file
    phases : the budget under each phase's factors
    factors_applied : False when every factor is 1 ("no factors applied")
    available_source : where the available torque comes from, in words
    notes : remarks the output repeats (what is left out, and why)
    """

    name: str
    source: str
    temperatures: tuple[float, ...] | None
    phases: tuple[PhaseMargin, ...]
    factors_applied: bool
    available_source: str
    notes: tuple[str, ...] = ()

    def lowest(self) -> tuple[float, float]:
        """The smallest margin and the smallest torque ratio over phases and temperatures."""
        margins = [float(np.min(p.margin)) for p in self.phases]
        ratios = [float(np.min(p.torque_ratio)) for p in self.phases]
        return min(margins), min(ratios)

    def failures(self) -> list[str]:
        """One line per phase and temperature with a negative margin (``--fail-on margin``)."""
        lines = []
        for phase in self.phases:
            margin = np.atleast_1d(phase.margin)
            ratio = np.atleast_1d(np.broadcast_to(phase.torque_ratio, margin.shape))
            for i, (m, r, verdict) in enumerate(zip(margin, ratio, phase.verdicts(), strict=True)):
                if m >= 0.0:
                    continue
                where = f" at {self.temperatures[i]:g} degC" if self.temperatures else ""
                label = f" (phase {phase.phase})" if phase.phase else ""
                lines.append(f"margin: {m:+.4g}{where}{label}: {verdict} (torque ratio {r:.4g})")
        return lines

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form, SI (docs/qualification.md); infinities as null."""

        def number(x: float) -> float | None:
            return float(x) if math.isfinite(x) else None

        def at(values: FloatArray, i: int) -> float:
            flat = np.atleast_1d(values)
            return float(flat[i] if flat.size > 1 else flat[0])

        count = 1 if self.temperatures is None else len(self.temperatures)
        phases = []
        for phase in self.phases:
            verdicts = phase.verdicts()
            cases = []
            for i in range(count):
                torques = [
                    {
                        "name": t.name,
                        "kind": t.kind,
                        "source": t.source,
                        "factor": phase.factor(t),
                        "value_Nm": at(t.value, i),
                        "factored_Nm": phase.factor(t) * at(t.value, i),
                    }
                    for t in phase.terms
                ]
                cases.append(
                    {
                        "temperature_C": None
                        if self.temperatures is None
                        else self.temperatures[i],
                        "angle_rad": None if phase.angle is None else at(phase.angle, i),
                        "available_Nm": at(phase.available, i),
                        "torques": torques,
                        "sum_Nm": at(phase.total, i),
                        "factored_sum_Nm": at(phase.factored, i),
                        "margin": number(at(phase.margin, i)),
                        "torque_ratio": number(at(phase.torque_ratio, i)),
                        "verdict": verdicts[min(i, len(verdicts) - 1)],
                    }
                )
            # A list, not a table keyed by kind: the kinds are the user's (open names).
            factors = [{"kind": k, "factor": float(f)} for k, f in phase.factors.items()]
            phases.append({"phase": phase.phase or None, "factors": factors, "cases": cases})
        margin, ratio = self.lowest()
        return {
            "ecdsim_version": __version__,
            "kind": "torque_budget",
            "name": self.name,
            "source": self.source,
            "temperatures_C": None if self.temperatures is None else list(self.temperatures),
            "factors_applied": self.factors_applied,
            "available_source": self.available_source,
            "margin": number(margin),
            "torque_ratio": number(ratio),
            "waiver_case": any(WAIVER in p.verdicts() for p in self.phases),
            "phases": phases,
            "notes": list(self.notes),
        }


def _applied(phases: Mapping[str, Mapping[str, float]]) -> bool:
    return any(f != 1.0 for factors in phases.values() for f in factors.values())


def budget_from_file(budget: BudgetFile) -> TorqueBudget:
    """The budget of a validated budget file (one value per torque, no temperatures)."""
    spec = budget.spec.budget
    terms = tuple(
        BudgetTerm(entry.name, entry.kind, as_float(entry.value)) for entry in spec.torque
    )
    factors = spec.phase_factors()
    phases = tuple(
        PhaseMargin(name, factors[name], as_float(spec.available), terms) for name in factors
    )
    return TorqueBudget(
        name=spec.name or budget.spec.title,
        source=budget.source,
        temperatures=None,
        phases=phases,
        factors_applied=_applied(factors),
        available_source="budget.available",
        notes=() if terms else ("the budget lists no resistive torque",),
    )


def margin_points(prediction: Prediction, settings: MarginSettings) -> MarginOverTravel:
    """The torque margin's terms at every point of the travel of a prediction's exact
    solution (the call ``ecdsim size`` and Monte Carlo make, docs/sizing.md section 5)."""
    problem = prediction.problem
    solution = prediction.solutions["exact"]
    efficiency = prediction.system.ecd.gearbox.efficiency
    return margin_over_travel(
        problem.angles,
        problem.torques,
        ecd_friction=prediction.ecd.ecd_friction,
        system_friction=prediction.system_friction,
        damping_rate=problem.damping_rate,
        stalled=solution.stalled,
        stall_angle=solution.stall_angle,
        settings=settings,
        resistance=prediction.resistance,
        gravity_amplitude=problem.gravity_amplitude if problem.has_gravity else None,
        gravity_angle=problem.gravity_angle if problem.has_gravity else None,
        forward_efficiency=None if efficiency is None else prediction.ecd.forward_efficiency,
    )


@dataclass(frozen=True)
class _Settings:
    """Where a config's budget takes its kinds, factors and damping speed."""

    phases: dict[str, dict[str, float]]  # phase -> kind -> factor
    kinds: dict[str, str]  # model term -> kind
    damping_speed: float | None
    allowances: dict[str, float]
    entries: tuple[tuple[str, str, float], ...]  # (name, kind, value [N*m])
    available: float | None
    origin: str
    exclude: tuple[str, ...] = ()


def _settings(config: Config) -> _Settings:
    """The budget settings of a config: its ``[budget]``, else its
    ``[requirements.torque_margin]`` (the ECSS kinds and factors), else no factors."""
    spec: BudgetSpec | None = getattr(config.spec, "budget", None)
    requirements = config.spec.requirements
    margin = None
    if requirements is not None:
        from ecdsim.sizing.requirements import Requirements

        margin = Requirements.from_spec(requirements).margin
    if spec is not None:
        speed = (
            spec.damping_speed
            if spec.damping_speed_given
            else (margin.damping_speed if margin is not None else 0.0)
        )
        return _Settings(
            phases=spec.phase_factors(),
            kinds=dict(spec.model_kinds),
            damping_speed=speed,
            allowances={},
            entries=tuple((e.name, e.kind, e.value) for e in spec.torque),
            available=spec.available,
            origin="[budget]",
            exclude=tuple(spec.exclude),
        )
    if margin is not None:
        factors = {kind: factor_of(kind, margin.factors) for kind in MODEL_NAMES}
        return _Settings(
            phases={"": factors},
            kinds={},
            damping_speed=margin.damping_speed,
            allowances=dict(margin.allowances),
            entries=(),
            available=None,
            origin="[requirements.torque_margin]",
        )
    return _Settings({"": {}}, {}, 0.0, {}, (), None, "no [budget]: no factors applied")


def _kind_factor(term: str, settings: _Settings, phase: str) -> tuple[str, float]:
    """The kind of a model term and its factor in ``phase``; BudgetError where a budget
    with factors gives none for it."""
    kind = settings.kinds.get(term, term)
    factors = settings.phases[phase]
    if kind in factors:
        return kind, float(factors[kind])
    given = any(settings.phases.values())
    if given and settings.origin == "[budget]":
        known = sorted({k for f in settings.phases.values() for k in f})
        where = f" in phase {phase}" if phase else ""
        raise BudgetError(
            f"budget.model_kinds.{term}: the model's {MODEL_NAMES[term]} "
            f"has kind {kind!r}, which has no factor{where}; map it to one of "
            f'{", ".join(known)} (e.g. model_kinds = {{ {term} = "{known[0]}" }})'
        )
    return kind, 1.0


def _picker(index: Any, shape: tuple[int, ...]) -> Any:
    """A function taking each array's value at ``index`` along axis 0 (the point of the
    travel where the margin is lowest), arrays broadcast to ``shape`` first."""

    def pick(values: ArrayLike) -> FloatArray:
        full = np.broadcast_to(as_float(values), shape)
        return as_float(np.take_along_axis(full, index, axis=0)[0])

    return pick


def budget_from_config(config: Config, temperatures: Sequence[float]) -> TorqueBudget:
    """The budget a config's model fills at each temperature [degC] (module docstring).

    Raises :class:`BudgetError` (a user error naming the key) where a model torque has
    no factor, and :class:`~ecdsim.deployment.ModelDomainError` where the model has no
    meaning.
    """
    from ecdsim.deployment import predict

    settings = _settings(config)
    temps = tuple(float(t) for t in temperatures)
    prediction = predict(config.system, as_float(temps), ("exact",))
    base = MarginSettings(
        factors={}, allowances=settings.allowances, damping_speed=settings.damping_speed
    )
    points = margin_points(prediction, base)
    notes: list[str] = []
    resistive = dict(points.resistive)
    for term in settings.exclude:
        if resistive.pop(term, None) is not None:
            notes.append(
                f"{MODEL_NAMES[term]}: excluded ([budget] exclude), already inside the "
                "available torque"
            )
    if settings.damping_speed == 0.0:
        resistive.pop("damping", None)
        notes.append(
            "damping: no speed stated (damping_speed in [budget] or "
            "[requirements.torque_margin]), so the damping torque is not in the budget"
        )
    speed_text = (
        "the deployment's own speed"
        if settings.damping_speed is None
        else f"{settings.damping_speed:g} rad/s"
    )
    drive = (
        points.drive
        if settings.available is None
        else as_float(np.full(points.drive.shape, settings.available))
    )
    phases = []
    for name in settings.phases:
        model = []
        for term, values in resistive.items():
            kind, factor = _kind_factor(term, settings, name)
            label = MODEL_NAMES.get(term, term)
            if term == "damping":
                label = f"ECD damping BECD_T at {speed_text}"
            model.append((term, label, kind, factor, values))
        user = [
            (name_, kind, float(settings.phases[name].get(kind, 1.0)), value)
            for name_, kind, value in settings.entries
        ]
        # The margin at every point of the travel with these factors: the budget is taken
        # where it is lowest (with constant torques, at the spring's minimum).
        factored = factored_sum(
            [(f, v) for _, _, _, f, v in model] + [(f, v) for _, _, f, v in user]
        )
        margin = margin_over(drive, factored)
        index = np.argmin(np.where(points.valid, margin, np.inf), axis=0)[np.newaxis]
        pick = _picker(index, margin.shape)
        terms = [BudgetTerm(label, kind, pick(v), "model") for _, label, kind, _, v in model]
        terms += [
            BudgetTerm(n, k, as_float(np.full(len(temps), v)), "budget") for n, k, _, v in user
        ]
        phases.append(
            PhaseMargin(
                phase=name,
                factors=dict(settings.phases[name]),
                available=pick(drive),
                terms=tuple(terms),
                angle=pick(points.angle),
            )
        )
    available_source = (
        "budget.available" if settings.available is not None else "spring torque ([load])"
    )
    factors_applied = any(p.factor(t) != 1.0 for p in phases for t in p.terms)
    return TorqueBudget(
        name=config.system.name,
        source=config.source,
        temperatures=temps,
        phases=tuple(phases),
        factors_applied=factors_applied,
        available_source=available_source,
        notes=(f"kinds and factors from {settings.origin}", *notes),
    )
