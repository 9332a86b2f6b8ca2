"""What a wing's deployment returns: per temperature, each hinge's motion, latches, energy.

The wing's solver (built on the dynamic core; docs/wing.md says what remains) fills a
:class:`WingResult`: one :class:`WingCase` per analysis temperature with each hinge's
deployed angle and speed against time, the events (which hinge latches, sticks, breaks
away, when), each latch's arrival speed, the wing's kinetic energy then and the latch's
peak torque or impulse, the deployment time (the last latch), the hinges left stuck and
the energy account. ``to_dict()`` is the JSON (SI, keys with units, ``inf`` as null),
``to_dataframe()`` the tidy time series.

Angles are deployed angles (0 at release, each hinge's travel at its latch), as for a
single hinge (docs/wing.md).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ecdsim._types import FloatArray
from ecdsim._version import __version__

# Every event a wing's run may record, with its meaning (docs/wing.md, results).
EVENT_KINDS: dict[str, str] = {
    "release": "t = 0: the wing is released",
    "breakaway": "a hinge at rest starts moving (its holding torque exceeded the breakaway)",
    "stick": "a hinge at rest stays at rest (its holding torque is within the breakaway)",
    "zero_speed": "a moving hinge's speed fell to zero",
    "latch": "a hinge reached its deployed angle and its rigid latch caught it",
    "rebound": "a hinge bounced off its rigid latch (restitution > 0)",
    "settle": "a hinge's rebounds died out: it is latched",
    "latch_engage": "a hinge reached its deployed angle: its compliant latch engages",
    "start_stop": "a hinge moving back reached its stowed angle (the stowed stop)",
    "slack": "a strand of a cable loop slackened",
    "taut": "a slack strand of a cable loop is taut again",
    "creep": "the wing approaches rest asymptotically (time infinity)",
    "stop_time": "the run reached its stop time",
    "event_limit": "the run was cut short by its event limit",
    "power_flow": "a hinge's lossy gear switched its power flow (forward or back-driven)",
    "gear_engage": "a hinge's lost motion closed: its damper side engages (a plastic impact)",
}

# How a case ends.
STATUSES: dict[str, str] = {
    "latched": "every hinge latched",
    "stuck": "the wing came to rest for good with a hinge short of its latch",
    "creep": "the wing approaches rest short of a latch, at time infinity",
    "stop_time": "the stop time came first",
    "event_limit": "cut short by the event limit",
}


def _finite_or_none(value: float) -> float | None:
    return float(value) if math.isfinite(value) else None


@dataclass(frozen=True)
class WingEvent:
    """One event of a wing's run.

    Attributes
    ----------
    time : when [s] (inf for the asymptotic ``creep``)
    kind : one of :data:`EVENT_KINDS`
    hinge : the hinge's index (0: the root), None for an event of the whole wing
    """

    time: float
    kind: str
    hinge: int | None = None

    def __post_init__(self) -> None:
        if self.kind not in EVENT_KINDS:
            raise ValueError(f"unknown wing event {self.kind!r}; expected one of {EVENT_KINDS}")


@dataclass(frozen=True)
class LatchEvent:
    """One hinge's latching.

    Attributes
    ----------
    hinge : the hinge's index (0: the root)
    time : when the hinge first reached its deployed angle [s]
    speed : its deployed-angle speed on arrival [rad/s]
    kinetic_energy : the whole wing's kinetic energy on arrival [J]
    impact_loss : kinetic energy lost in the rigid latch's impacts (all its rebounds
        included) [J]; 0 for a compliant latch (its damping is ``latch_dissipation``)
    peak_torque : the compliant latch's largest torque [N*m]; None for a rigid latch
    impulse : the rigid latch's angular impulse at the hinge on arrival [N*m*s]; None for
        a compliant latch
    """

    hinge: int
    time: float
    speed: float
    kinetic_energy: float
    impact_loss: float = 0.0
    peak_torque: float | None = None
    impulse: float | None = None


@dataclass(frozen=True)
class WingEnergy:
    """The energy account of one case [J]; per-hinge terms are arrays root first.

    Balance: ``spring_work + gravity_work + initial_kinetic = damper_dissipation +
    friction_dissipation + latch_dissipation + impact_loss + gear_loss + engagement_loss +
    final_kinetic + cable_elastic + latch_elastic`` (sums over the hinges), closing to the solver's
    accuracy (:attr:`error`).

    Attributes
    ----------
    spring_work : work of each hinge's net drive (spring less resistive table)
    damper_dissipation : energy each hinge's ECD dissipated (BECD_T and beyond)
    friction_dissipation : energy each hinge's friction (FECD_T + FS_T, with its
        Stribeck excess where the ECD has a Stribeck speed) dissipated
    latch_dissipation : energy each compliant latch's damping dissipated
    impact_loss : kinetic energy lost in each hinge's rigid latch impacts
    gravity_work : work of the offloaded weights in a ground test (0 in flight)
    initial_kinetic : the wing's kinetic energy at release
    final_kinetic : its kinetic energy at the end
    cable_elastic : the cables' elastic energy at the end less at release
    latch_elastic : the compliant latches' elastic energy at the end
    gear_loss : energy each hinge's lossy gear lost in its mesh (``gearbox.efficiency``:
        the power through the mesh times ``1/eta_f - 1`` forward, ``1 - eta_b``
        back-driven); None: no lossy gear (zeros)
    engagement_loss : kinetic energy lost where each hinge's lost motion closed (the
        plastic impact of its damper side); None: none (zeros)
    """

    spring_work: FloatArray
    damper_dissipation: FloatArray
    friction_dissipation: FloatArray
    latch_dissipation: FloatArray
    impact_loss: FloatArray
    gravity_work: float = 0.0
    initial_kinetic: float = 0.0
    final_kinetic: float = 0.0
    cable_elastic: float = 0.0
    latch_elastic: float = 0.0
    gear_loss: FloatArray | None = None
    engagement_loss: FloatArray | None = None

    @property
    def engagement_losses(self) -> FloatArray:
        """Each hinge's engagement loss [J] (zeros without lost motion)."""
        if self.engagement_loss is None:
            return np.zeros(np.shape(self.spring_work))
        return self.engagement_loss

    @property
    def mesh_loss(self) -> FloatArray:
        """Each hinge's gear loss [J] (zeros without a lossy gear)."""
        if self.gear_loss is None:
            return np.zeros(np.shape(self.spring_work))
        return self.gear_loss

    @property
    def supplied(self) -> float:
        """Energy put in: drive work, gravity's work and the kinetic energy at release [J]."""
        return float(np.sum(self.spring_work)) + self.gravity_work + self.initial_kinetic

    @property
    def accounted(self) -> float:
        """Where it went: dissipations, losses, kinetic and elastic energy at the end [J]."""
        return (
            float(
                np.sum(self.damper_dissipation)
                + np.sum(self.friction_dissipation)
                + np.sum(self.latch_dissipation)
                + np.sum(self.impact_loss)
                + np.sum(self.mesh_loss)
                + np.sum(self.engagement_losses)
            )
            + self.final_kinetic
            + self.cable_elastic
            + self.latch_elastic
        )

    @property
    def error(self) -> float:
        """``|supplied - accounted|`` relative to the largest term [-] (0 for no energy)."""
        terms = [
            *np.abs(self.spring_work),
            *self.damper_dissipation,
            *self.friction_dissipation,
            *self.latch_dissipation,
            *self.impact_loss,
            *self.mesh_loss,
            *self.engagement_losses,
            abs(self.gravity_work),
            self.initial_kinetic,
            self.final_kinetic,
            abs(self.cable_elastic),
            self.latch_elastic,
        ]
        scale = max(float(t) for t in terms)
        if scale == 0.0:
            return 0.0
        return abs(self.supplied - self.accounted) / scale

    def to_dict(self, hinges: tuple[str, ...]) -> dict[str, Any]:
        """The account as JSON: per-hinge terms keyed by hinge name, totals [J]."""

        def per_hinge(values: FloatArray) -> dict[str, float]:
            return {name: float(v) for name, v in zip(hinges, values, strict=True)}

        return {
            "spring_work": per_hinge(self.spring_work),
            "damper_dissipation": per_hinge(self.damper_dissipation),
            "friction_dissipation": per_hinge(self.friction_dissipation),
            "latch_dissipation": per_hinge(self.latch_dissipation),
            "impact_loss": per_hinge(self.impact_loss),
            "gear_loss": per_hinge(self.mesh_loss),
            "engagement_loss": per_hinge(self.engagement_losses),
            "gravity_work": self.gravity_work,
            "initial_kinetic": self.initial_kinetic,
            "final_kinetic": self.final_kinetic,
            "cable_elastic": self.cable_elastic,
            "latch_elastic": self.latch_elastic,
        }


@dataclass(frozen=True)
class WingCase:
    """A wing's deployment at one temperature.

    Attributes
    ----------
    temperature : T [degC]
    time : sample times [s], shape (m,), increasing
    angle : each hinge's deployed angle at those times [rad], shape (m, n)
    speed : each hinge's deployed-angle speed [rad/s], shape (m, n)
    events : the run's events in time order
    latches : one record per latched hinge, in the order they latched
    status : how the run ended, one of :data:`STATUSES`
    stuck_hinges : the hinges at rest for good short of their latch at the end, root
        first (empty when every hinge latched)
    energy : the energy account
    peak_damper_temperature : each hinge's damper's peak temperature [degC] over the
        run where its heating is modelled (``[damper.thermal]``), None where it is not
        (empty: not computed, e.g. by a reference)
    """

    temperature: float
    time: FloatArray
    angle: FloatArray
    speed: FloatArray
    events: tuple[WingEvent, ...]
    latches: tuple[LatchEvent, ...]
    status: str
    stuck_hinges: tuple[int, ...]
    energy: WingEnergy
    peak_damper_temperature: tuple[float | None, ...] = ()

    def __post_init__(self) -> None:
        if self.status not in STATUSES:
            raise ValueError(f"unknown status {self.status!r}; expected one of {STATUSES}")
        m = self.time.shape[0]
        if self.angle.ndim != 2 or self.angle.shape[0] != m or self.speed.shape != self.angle.shape:
            raise ValueError("angle and speed must have shape (len(time), hinges)")

    @property
    def hinges(self) -> int:
        """The number of hinges."""
        return int(self.angle.shape[1])

    @property
    def sequence(self) -> tuple[int, ...]:
        """The hinges in the order they latched."""
        return tuple(latch.hinge for latch in self.latches)

    @property
    def deployment_time(self) -> float:
        """When the last hinge latched [s]; inf unless every hinge latched."""
        if len({latch.hinge for latch in self.latches}) < self.hinges:
            return math.inf
        return max(latch.time for latch in self.latches)

    @property
    def stalled(self) -> bool:
        """True when the wing came to rest (or creeps) with a hinge short of its latch."""
        return self.status in ("stuck", "creep")

    @property
    def max_speed(self) -> FloatArray:
        """Each hinge's largest |speed| over the recorded samples [rad/s]."""
        return np.asarray(np.max(np.abs(self.speed), axis=0), dtype=float)


@dataclass(frozen=True)
class WingResult:
    """A wing's deployment over the analysis temperatures.

    Attributes
    ----------
    wing : the wing's name
    hinges : the hinges' names, root first
    cases : one :class:`WingCase` per temperature, in the order asked
    source : what produced it (a method's label, or a reference's)
    """

    wing: str
    hinges: tuple[str, ...]
    cases: tuple[WingCase, ...]
    source: str = "dynamic"

    def __post_init__(self) -> None:
        for case in self.cases:
            if case.hinges != len(self.hinges):
                raise ValueError("every case needs one column per hinge")

    @property
    def temperatures(self) -> tuple[float, ...]:
        """The analysis temperatures [degC]."""
        return tuple(case.temperature for case in self.cases)

    def case_at(self, temperature: float) -> WingCase:
        """The case at ``temperature`` [degC]; KeyError naming the ones there are."""
        for case in self.cases:
            if case.temperature == temperature:
                return case
        raise KeyError(f"no case at {temperature:g} degC; have {list(self.temperatures)}")

    def _case_dict(self, case: WingCase, series: bool) -> dict[str, Any]:
        names = self.hinges
        out: dict[str, Any] = {
            "temperature_C": case.temperature,
            "status": case.status,
            "deployment_time_s": _finite_or_none(case.deployment_time),
            "stalled": case.stalled,
            "sequence": [names[i] for i in case.sequence],
            "stuck_hinges": [names[i] for i in case.stuck_hinges],
            "latches": [
                {
                    "hinge": names[latch.hinge],
                    "time_s": latch.time,
                    "speed_rad_s": latch.speed,
                    "kinetic_energy_J": latch.kinetic_energy,
                    "impact_loss_J": latch.impact_loss,
                    "peak_torque_Nm": latch.peak_torque,
                    "impulse_Nms": latch.impulse,
                }
                for latch in case.latches
            ],
            "final_angle_rad": {
                name: float(v) for name, v in zip(names, case.angle[-1], strict=True)
            },
            "max_speed_rad_s": {
                name: float(v) for name, v in zip(names, case.max_speed, strict=True)
            },
            "peak_damper_temperature_C": {
                name: peak
                for name, peak in zip(names, case.peak_damper_temperature, strict=False)
                if peak is not None
            },
            "energy_J": case.energy.to_dict(names),
            "energy_balance_error": case.energy.error,
            "events": [
                {
                    "time_s": _finite_or_none(event.time),
                    "event": event.kind,
                    "hinge": None if event.hinge is None else names[event.hinge],
                }
                for event in case.events
            ],
        }
        if series:
            out["series"] = {
                "time_s": case.time.tolist(),
                "angle_rad": {n: case.angle[:, i].tolist() for i, n in enumerate(names)},
                "speed_rad_s": {n: case.speed[:, i].tolist() for i, n in enumerate(names)},
            }
        return out

    def to_dict(self, series: bool = False) -> dict[str, Any]:
        """The result as JSON-ready data (SI; keys carry units; inf as null).

        ``series=True`` adds each case's sampled time series.
        """
        return {
            # The document's release and kind (its JSON Schema: wing_deploy, docs/json.md).
            "ecdsim_version": __version__,
            "kind": "wing_deploy",
            "wing": self.wing,
            "source": self.source,
            "hinges": list(self.hinges),
            "cases": [self._case_dict(case, series) for case in self.cases],
        }

    def summary_rows(self) -> list[dict[str, Any]]:
        """One row per temperature: what a sweep's or a Monte Carlo study's table holds
        (SI, units in the column names as everywhere, NaN where there is no value).

        ``status``, ``latched``, ``stalled``, ``deployment_time_s`` (NaN unless every
        hinge latched), ``stuck_hinges`` (how many), ``energy_balance_error``, and per
        hinge j (counted from 0, as the file's ``wing.hinges[j]``): ``hinge_j_latch_time_s``,
        ``hinge_j_latch_speed_rad_s``, ``hinge_j_latch_kinetic_energy_J`` (the wing's, on
        its arrival), ``hinge_j_peak_latch_torque_Nm`` (a compliant latch's),
        ``hinge_j_stuck`` and, where its damper heats, ``hinge_j_peak_damper_temperature_C``.
        """
        rows = []
        for case in self.cases:
            row: dict[str, Any] = {
                "temperature_C": case.temperature,
                "status": case.status,
                "latched": case.status == "latched",
                "stalled": case.stalled,
                "deployment_time_s": case.deployment_time
                if math.isfinite(case.deployment_time)
                else math.nan,
                "stuck_hinges": len(case.stuck_hinges),
                "energy_balance_error": float(case.energy.error),
            }
            first: dict[int, LatchEvent] = {}
            for record in case.latches:
                first.setdefault(record.hinge, record)
            peaks = case.peak_damper_temperature
            for j in range(case.hinges):
                head = f"hinge_{j}_"
                latch = first.get(j)
                row[head + "latch_time_s"] = float(latch.time) if latch else math.nan
                row[head + "latch_speed_rad_s"] = float(latch.speed) if latch else math.nan
                row[head + "latch_kinetic_energy_J"] = (
                    float(latch.kinetic_energy) if latch else math.nan
                )
                torque = latch.peak_torque if latch else None
                row[head + "peak_latch_torque_Nm"] = math.nan if torque is None else float(torque)
                row[head + "stuck"] = j in case.stuck_hinges
                peak = peaks[j] if j < len(peaks) else None
                if peak is not None:
                    row[head + "peak_damper_temperature_C"] = float(peak)
            rows.append(row)
        return rows

    def to_dataframe(self) -> Any:
        """The tidy time series: one row per temperature, hinge and time (pandas).

        Columns ``temperature_C``, ``hinge``, ``time_s``, ``angle_rad``, ``speed_rad_s``.
        Needs pandas (the ``montecarlo`` or ``test`` extra).
        """
        import pandas as pd

        frames = []
        for case in self.cases:
            m, n = case.angle.shape
            frames.append(
                pd.DataFrame(
                    {
                        "temperature_C": np.full(m * n, case.temperature),
                        "hinge": np.repeat(np.array(self.hinges, dtype=object), m),
                        "time_s": np.tile(case.time, n),
                        "angle_rad": case.angle.T.reshape(-1),
                        "speed_rad_s": case.speed.T.reshape(-1),
                    }
                )
            )
        columns = ["temperature_C", "hinge", "time_s", "angle_rad", "speed_rad_s"]
        if not frames:
            return pd.DataFrame(columns=columns)
        return pd.concat(frames, ignore_index=True)[columns]
