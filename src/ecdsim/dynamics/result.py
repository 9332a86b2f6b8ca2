"""The dynamic solver's result: summary arrays, events, energy balance and time series.

Every summary array has the problem's batch shape (temperatures x samples). Time series
are re-evaluated on demand from the recorded segments (exact for closed-form segments,
scipy's dense output for integrated ones), so they cost nothing unless asked for.
``to_pandas`` imports pandas lazily: it is not a dependency of ecdsim.
"""

from __future__ import annotations

import importlib
import io
import math
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from ecdsim._types import BoolArray, FloatArray
from ecdsim.dynamics.energy import _TERMS as _TERMS
from ecdsim.dynamics.energy import EnergyBalance as EnergyBalance
from ecdsim.physics.eddy import damper_side_torque
from ecdsim.physics.friction import stribeck_excess

if TYPE_CHECKING:
    from matplotlib.figure import Figure

EVENT_KINDS = (
    "release",  # t = 0
    "breakaway",  # motion starts from rest: drive exceeds static friction
    "stick",  # at rest with drive within static friction: stays for good
    "zero_speed",  # the speed fell to zero while moving
    "engage",  # the lost motion closed: the damper side engages
    "breakpoint",  # a breakpoint of a tabulated spring
    "arrive",  # end of travel reached (speed is the arrival speed)
    "latch",  # caught at the end of travel (restitution 0)
    "settle",  # rebounds died out against the end stop
    "start_stop",  # moving backward, hit the start of travel
    "stop_time",  # the stop time was reached
    "creep",  # asymptotic approach to the static equilibrium (time = inf)
    "event_limit",  # too many events: the run was cut short
    "horizon",  # the integrator reached its time horizon without an event
    "separate",  # compliant backlash: the mesh's flanks part (contact lost)
    "contact",  # compliant backlash: the flanks meet again (contact regained)
    "power_flow",  # the power through a lossy gear reversed (forward <-> back-driven)
)
STATUSES = (
    "running",
    "latched",
    "settled",
    "stuck",
    "creep",
    "stop_time",
    "event_limit",
    "horizon",
)


def _json_float(value: float) -> float | None:
    return float(value) if math.isfinite(value) else None


@dataclass(frozen=True)
class EventLog:
    """Every event of every case, sorted by case then time (flat arrays).

    Attributes
    ----------
    case : flat index of the case in the batch
    time : time of the event [s] (inf for an asymptotic approach to rest)
    kind : index into :data:`EVENT_KINDS`
    angle : deployed angle at the event [rad]
    speed : load speed at the event (before any jump it causes) [rad/s]
    """

    case: NDArray[np.intp]
    time: FloatArray
    kind: NDArray[np.int8]
    angle: FloatArray
    speed: FloatArray

    def names(self) -> list[str]:
        """The kinds as names."""
        return [EVENT_KINDS[k] for k in self.kind]

    def count(self, kind: str, case: int | None = None) -> int:
        """How many events of ``kind`` (in one flat case, or in all)."""
        mask = self.kind == EVENT_KINDS.index(kind)
        if case is not None:
            mask &= self.case == case
        return int(np.count_nonzero(mask))

    def for_case(self, case: int) -> list[dict[str, Any]]:
        """One case's events as JSON-ready dictionaries."""
        rows = np.flatnonzero(self.case == case)
        return [
            {
                "kind": EVENT_KINDS[self.kind[r]],
                "time_s": _json_float(self.time[r]),
                "angle_rad": float(self.angle[r]),
                "speed_rad_s": float(self.speed[r]),
            }
            for r in rows
        ]


@dataclass(frozen=True)
class TrajectoryData:
    """What time series are re-evaluated from: the kernel's recorded spans and points.

    Attributes
    ----------
    spans : one row per segment, sorted by case and time (``kernel.layout.SPAN_*``): a
        closed form's constants, or the range of an integrated segment's points
    points : the integrated segments' accepted steps (``kernel.layout.POINT_*``)
    span_start : where each case's spans start in ``spans`` (n_cases + 1)
    initial : each case's state at release: angle, speed, temperature, engaged, 0
    final : each case's final state and the time it holds from (``kernel.sample``)
    display_end : where a plot of each case should end [s]
    table : the cases' constants (``kernel.layout``), for the torques at the samples
    angles : the spring's breakpoints per case (n_cases, points) [rad]
    torques : the net spring torque there [N*m]
    """

    spans: FloatArray
    points: FloatArray
    span_start: FloatArray
    initial: FloatArray
    final: FloatArray
    display_end: FloatArray
    table: FloatArray
    angles: FloatArray
    torques: FloatArray

    def segment_counts(self) -> tuple[NDArray[np.int64], NDArray[np.int64], NDArray[np.int64]]:
        """Per case: closed-form segments, integrated segments, integrator steps."""
        from ecdsim.dynamics.kernel import layout as lay

        n = self.span_start.size - 1
        case = self.spans[:, lay.SPAN_CASE].astype(np.int64)
        closed = self.spans[:, lay.SPAN_KIND] == lay.SPAN_CLOSED
        steps = np.where(closed, 0.0, np.maximum(self.spans[:, lay.SPAN_COUNT] - 1.0, 0.0))
        return (
            np.bincount(case[closed], minlength=n),
            np.bincount(case[~closed], minlength=n),
            np.bincount(case, weights=steps, minlength=n).astype(np.int64),
        )


@dataclass(frozen=True)
class TimeSeries:
    """Sampled states and torques; arrays have shape (n_times, *batch_shape).

    Attributes
    ----------
    time : sample times [s]
    angle : deployed angle [rad]
    speed : load speed [rad/s]
    damper_temperature : [degC]
    spring_torque : spring torque on the load [N*m]
    friction_torque : Coulomb friction torque on the moving parts, opposing the motion
        (with a Stribeck speed, Coulomb plus the Stribeck excess; at rest: the holding
        torque) [N*m]
    damping_torque : ECD damping torque at the input shaft, opposing the motion [N*m]
    engaged : True where the damper is engaged (False during the lost motion)
    """

    time: FloatArray
    angle: FloatArray
    speed: FloatArray
    damper_temperature: FloatArray
    spring_torque: FloatArray
    friction_torque: FloatArray
    damping_torque: FloatArray
    engaged: BoolArray


def _spring_at(angles: FloatArray, torques: FloatArray, phi: FloatArray) -> FloatArray:
    """Piecewise-linear spring torque, each case (column) with its own table; phi (m, n)."""
    out = np.empty_like(phi)
    for j in range(phi.shape[1]):
        out[:, j] = np.interp(phi[:, j], angles[:, j], torques[:, j])
    return out


@dataclass(frozen=True)
class DynamicResult:
    """The full dynamics of every case of a batch.

    Summary arrays (batch shape):

    Attributes
    ----------
    batch_shape : shape of the batch
    temperature : ambient (analysis) temperature [degC]
    deployment_time : first arrival at the end of travel [s]; inf if never
    arrival_speed : speed at that arrival [rad/s]; 0 if never
    arrival_kinetic_energy : kinetic energy at that arrival [J]; 0 if never
    final_time : end of the run [s] (inf for an asymptotic approach to rest)
    final_angle : deployed angle at the end of the run [rad]
    final_speed : speed at the end of the run [rad/s] (the arrival speed when latched)
    final_temperature : damper temperature at the end of the run [degC]
    stuck : True where the mechanism came to rest for good short of latching (static
        friction holds it, or it creeps to its static equilibrium)
    stuck_angle : where it stuck [rad]; NaN if not stuck
    stuck_time : when it stuck [s]; inf for an asymptotic approach; NaN if not stuck
    max_speed : largest forward speed before the first arrival [rad/s]
    max_damper_temperature : highest damper temperature [degC]
    engagement_time : when the lost motion closed [s]; 0 without lost motion, inf if never
    rebound_speed : speed just after the first impact at the end of travel [rad/s]
    impacts : number of rebounding impacts on the stops
    status : index into :data:`STATUSES`, how the run ended
    energy : the energy balance
    events : every event
    trajectory : recorded segments for time series (None if not recorded)
    final_housing_temperature : the housing's temperature at the end of the run with
        two-node heating [degC]; None with one node or none
    max_mesh_torque : compliant backlash only: the largest torque through the gear mesh
        over the run (engagement impacts included) [N*m]; None for a rigid mesh
    latch_mesh_torque : compliant backlash only: the largest mesh torque once the load is
        held at the end of travel, as the damper side overruns it [N*m]
    """

    batch_shape: tuple[int, ...]
    temperature: FloatArray
    deployment_time: FloatArray
    arrival_speed: FloatArray
    arrival_kinetic_energy: FloatArray
    final_time: FloatArray
    final_angle: FloatArray
    final_speed: FloatArray
    final_temperature: FloatArray
    stuck: BoolArray
    stuck_angle: FloatArray
    stuck_time: FloatArray
    max_speed: FloatArray
    max_damper_temperature: FloatArray
    engagement_time: FloatArray
    rebound_speed: FloatArray
    impacts: NDArray[np.int64]
    status: NDArray[np.int8]
    energy: EnergyBalance
    events: EventLog
    trajectory: TrajectoryData | None
    final_housing_temperature: FloatArray | None = None
    max_mesh_torque: FloatArray | None = None
    latch_mesh_torque: FloatArray | None = None

    @property
    def size(self) -> int:
        """Number of cases."""
        return int(np.prod(self.batch_shape)) if self.batch_shape else 1

    @property
    def arrived(self) -> BoolArray:
        """True where the end of travel was reached."""
        return np.asarray(np.isfinite(self.deployment_time))

    @property
    def energy_balance_error(self) -> FloatArray:
        """Relative energy imbalance per case (see :class:`EnergyBalance`)."""
        return self.energy.error

    def status_names(self) -> list[str]:
        """How each case (flat order) ended."""
        return [STATUSES[s] for s in np.ravel(self.status)]

    def _data(self) -> TrajectoryData:
        if self.trajectory is None:
            raise ValueError("this result was solved with record=False: no time series")
        return self.trajectory

    def default_times(self, n_points: int = 501) -> FloatArray:
        """Per-case sample times, shape (n_points, n_cases): 0 to the end of the motion.

        Each case's grid ends at its final time (for an asymptotic approach to rest, ten
        slow time constants after it began) and contains its event times exactly: each
        event replaces the nearest interior grid point.
        """
        data = self._data()
        end = np.where(data.display_end > 0.0, data.display_end, 1.0)
        grid = np.linspace(0.0, 1.0, max(n_points, 3))[:, None] * end[None, :]
        events = self.events
        inside = np.isfinite(events.time) & (events.time > 0.0)
        inside &= events.time < end[events.case]
        for case, time in zip(events.case[inside], events.time[inside], strict=True):
            column = grid[:, case]
            nearest = 1 + int(np.argmin(np.abs(column[1:-1] - time)))
            column[nearest] = time
            column.sort()
        return grid

    def sample(self, times: FloatArray | None = None, n_points: int = 501) -> TimeSeries:
        """States and torques at ``times`` (1-D, shared; or (n_times, n_cases)) [s].

        Without ``times``, :meth:`default_times` is used. The states are re-evaluated
        from the recorded segments (exactly for closed forms, by the integrator's dense
        output otherwise), the torques by the same laws the solver used
        (:mod:`ecdsim.physics`).
        """
        from ecdsim.dynamics.kernel import layout as lay
        from ecdsim.dynamics.kernel.build import backend

        data = self._data()
        grid = self.default_times(n_points) if times is None else np.asarray(times, float)
        if grid.ndim == 1:
            grid = np.broadcast_to(grid[:, None], (grid.size, self.size))
        grid = np.ascontiguousarray(grid, dtype=float)
        states = np.zeros((4, *grid.shape))
        backend().sample_cases(
            grid, data.table, data.spans, data.points, data.span_start, data.initial,
            data.final, states,
        )  # fmt: skip
        angle, speed, temperature, engaged = states[0], states[1], states[2], states[3] != 0.0
        t = data.table
        spring = _spring_at(data.angles.T, data.torques.T, angle)
        ecd, system = t[:, lay.FE], t[:, lay.FS]
        kinetic = np.where(engaged, ecd + system, system)
        static = t[:, lay.FSB] + np.where(engaged, t[:, lay.FEB], 0.0)
        holding = -np.clip(spring, -static, static)
        stribeck_speed = t[:, lay.WST]
        if np.any(np.isfinite(stribeck_speed)):
            # Sliding friction falls from the breakaway to the kinetic value with speed;
            # where w_St is inf the excess is 0.
            finite = np.isfinite(stribeck_speed)
            excess = np.where(finite, np.maximum(static - kinetic, 0.0), 0.0)
            kinetic = (
                kinetic + stribeck_excess(speed, excess, np.where(finite, stribeck_speed, 1.0))[0]
            )
        friction = np.where(speed != 0.0, -np.sign(speed) * kinetic, holding)
        factor = 1.0 + t[:, lay.COEF] * (temperature - t[:, lay.TREF])  # Eq. 1's bracket
        law = int(t[0, lay.LAW]) if t.shape[0] else 0
        torque, _ = damper_side_torque(
            law,
            t[:, lay.LA],
            t[:, lay.LB],
            t[:, lay.LC],
            t[:, lay.RATIO],
            t[:, lay.BG],
            speed,
            factor,
        )
        damping = np.where(engaged, -torque, 0.0)
        shape = (grid.shape[0], *self.batch_shape)

        def shaped(a: NDArray[Any]) -> NDArray[Any]:
            return np.asarray(a).reshape(shape)

        return TimeSeries(
            time=shaped(grid),
            angle=shaped(angle),
            speed=shaped(speed),
            damper_temperature=shaped(temperature),
            spring_torque=shaped(spring),
            friction_torque=shaped(friction),
            damping_torque=shaped(damping),
            engaged=shaped(engaged),
        )

    def case_summary(self, case: int) -> dict[str, Any]:
        """One case (flat index) as a JSON-ready dictionary (SI units in the keys)."""

        def at(a: NDArray[Any]) -> float:
            return float(np.ravel(a)[case])

        e = self.energy
        stuck = bool(np.ravel(self.stuck)[case])
        housing = self.final_housing_temperature
        # Two-node heating only: without a housing node the dictionary is as before.
        extra = {} if housing is None else {"final_housing_temperature_C": at(housing)}
        return extra | {
            "temperature_C": at(self.temperature),
            "status": STATUSES[int(np.ravel(self.status)[case])],
            "deployment_time_s": _json_float(at(self.deployment_time)),
            "end_speed_rad_s": at(self.arrival_speed),
            "end_kinetic_energy_J": at(self.arrival_kinetic_energy),
            "max_speed_rad_s": at(self.max_speed),
            "max_damper_temperature_C": at(self.max_damper_temperature),
            "stuck": stuck,
            "stuck_angle_rad": at(self.stuck_angle) if stuck else None,
            "stuck_time_s": _json_float(at(self.stuck_time)) if stuck else None,
            "final_time_s": _json_float(at(self.final_time)),
            "final_angle_rad": at(self.final_angle),
            "engagement_time_s": _json_float(at(self.engagement_time)),
            "rebound_speed_rad_s": at(self.rebound_speed),
            "impacts": int(np.ravel(self.impacts)[case]),
            "energy_J": {
                "spring_work": at(e.spring_work),
                "initial_kinetic": at(e.initial_kinetic_energy),
                "damper_dissipation": at(e.damper_dissipation),
                "friction_dissipation": at(e.friction_dissipation),
                "engagement_loss": at(e.engagement_loss),
                "impact_loss": at(e.impact_loss),
                "final_kinetic": at(e.final_kinetic_energy),
                "gear_loss": at(e.gear_loss),
                **({} if e.gravity_work is None else {"gravity_work": at(e.gravity_work)}),
                **({} if e.resistive_work is None else {"resistive_work": at(e.resistive_work)}),
                **(
                    {}
                    if e.mesh_dissipation is None or e.elastic_energy is None
                    else {
                        "mesh_dissipation": at(e.mesh_dissipation),
                        "final_elastic": at(e.elastic_energy),
                    }
                ),
            },
            "energy_balance_error": at(e.error),
            **(
                {}
                if self.max_mesh_torque is None or self.latch_mesh_torque is None
                else {
                    "max_mesh_torque_Nm": at(self.max_mesh_torque),
                    "latch_mesh_torque_Nm": at(self.latch_mesh_torque),
                }
            ),
        }

    def to_dict(self, events: bool = True) -> dict[str, Any]:
        """Every case's summary (and events) as a JSON-ready dictionary."""
        cases = []
        for j in range(self.size):
            entry = self.case_summary(j)
            if events:
                entry["events"] = self.events.for_case(j)
            cases.append(entry)
        return {"batch_shape": list(self.batch_shape), "cases": cases}

    def _timeseries_columns(self, n_points: int) -> dict[str, NDArray[Any]]:
        series = self.sample(n_points=n_points)
        n_t = series.time.shape[0]
        flat = self.size
        case = np.broadcast_to(np.arange(flat)[None, :], (n_t, flat))
        temperature = np.broadcast_to(np.ravel(self.temperature)[None, :], (n_t, flat))

        def column(a: NDArray[Any]) -> NDArray[Any]:
            return np.asarray(a).reshape(n_t, flat).T.reshape(-1)

        return {
            "case": column(case),
            "temperature_C": column(temperature),
            "time_s": column(series.time),
            "angle_rad": column(series.angle),
            "speed_rad_s": column(series.speed),
            "damper_temperature_C": column(series.damper_temperature),
            "spring_torque_Nm": column(series.spring_torque),
            "friction_torque_Nm": column(series.friction_torque),
            "damping_torque_Nm": column(series.damping_torque),
            "engaged": column(series.engaged),
        }

    def to_pandas(self, table: str = "timeseries", n_points: int = 501) -> Any:
        """A ``pandas.DataFrame``: ``"timeseries"`` (long format), ``"summary"`` or ``"events"``.

        pandas is imported here and is not an ecdsim dependency (hence the ``Any`` return
        type: no pandas stubs are needed); install it with ``pip install pandas``.
        """
        try:
            # Through importlib: pandas is optional and ships no type stubs here.
            pd = importlib.import_module("pandas")
        except ImportError as exc:  # pragma: no cover - depends on the environment
            raise ImportError(
                "DynamicResult.to_pandas() needs pandas, which ecdsim does not install; "
                "run 'pip install pandas' (or use to_dict() / to_csv())"
            ) from exc
        if table == "timeseries":
            return pd.DataFrame(self._timeseries_columns(n_points))
        if table == "summary":
            rows = []
            for j in range(self.size):
                row = self.case_summary(j)
                energy = row.pop("energy_J")
                row.update({f"energy_{k}_J": v for k, v in energy.items()})
                rows.append(row)
            return pd.DataFrame(rows)
        if table == "events":
            ev = self.events
            return pd.DataFrame(
                {
                    "case": ev.case,
                    "time_s": ev.time,
                    "kind": ev.names(),
                    "angle_rad": ev.angle,
                    "speed_rad_s": ev.speed,
                }
            )
        raise ValueError(f"table must be 'timeseries', 'summary' or 'events', got {table!r}")

    def timeseries_csv(self, n_points: int = 501) -> str:
        """The time series as CSV text: temperature_C, time_s, angle_rad, speed_rad_s,
        damper_temperature_C, one block of rows per case."""
        columns = self._timeseries_columns(n_points)
        names = ("temperature_C", "time_s", "angle_rad", "speed_rad_s", "damper_temperature_C")
        table = np.column_stack([np.asarray(columns[k], dtype=float) for k in names])
        buffer = io.StringIO()
        buffer.write(",".join(names) + "\n")
        np.savetxt(buffer, table, delimiter=",", fmt="%.12g")
        return buffer.getvalue()

    def to_csv(self, path: str | Path, n_points: int = 501) -> Path:
        """Write :meth:`timeseries_csv` atomically to ``path``."""
        from ecdsim.atomic import write_text

        return write_text(path, self.timeseries_csv(n_points))

    def plot(self, n_points: int = 501, max_cases: int = 12) -> Figure:
        """Angle, speed and damper temperature against time for up to ``max_cases`` cases."""
        from matplotlib import colormaps
        from matplotlib.figure import Figure

        series = self.sample(n_points=n_points)
        count = min(self.size, max_cases)
        fig = Figure(figsize=(7.5, 8.0), layout="constrained")
        axes = fig.subplots(3, 1, sharex=True)
        colors = colormaps["turbo"](np.linspace(0.1, 0.9, max(count, 2)))
        n_t = series.time.shape[0]
        for j in range(count):
            time = series.time.reshape(n_t, -1)[:, j]
            temp = float(np.ravel(self.temperature)[j])
            label = f"case {j}, {temp:g} degC"
            axes[0].plot(
                time, np.degrees(series.angle.reshape(n_t, -1)[:, j]), color=colors[j], label=label
            )
            axes[1].plot(time, series.speed.reshape(n_t, -1)[:, j], color=colors[j])
            axes[2].plot(time, series.damper_temperature.reshape(n_t, -1)[:, j], color=colors[j])
        axes[0].set_ylabel("deployed angle [deg]")
        axes[1].set_ylabel("speed [rad/s]")
        axes[2].set_ylabel("damper temperature [degC]")
        axes[2].set_xlabel("time since release [s]")
        for ax in axes:
            ax.grid(True, alpha=0.3)
        axes[0].legend(fontsize="small")
        axes[0].set_title("dynamic deployment")
        return fig
