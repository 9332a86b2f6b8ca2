"""Plots of the dynamic method: angle and speed against time with the events marked,
and the damper's temperature when self-heating is modelled (``ecdsim deploy --plot``).

Each curve is one temperature, sampled on its own time grid, which contains every event
time exactly (:meth:`ecdsim.dynamics.result.DynamicResult.default_times`). Events are
marked where they happen: a stick (the mechanism comes to rest for good), an impact on an
end stop that rebounds, the latch at the end of travel (or the rebounds settling on the
stop), and the damper engaging after lost motion. matplotlib is imported lazily, through
:mod:`ecdsim.plotting`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from ecdsim._types import FloatArray
from ecdsim.deployment import Prediction
from ecdsim.dynamics.result import EVENT_KINDS, DynamicResult, TimeSeries
from ecdsim.dynamics.sequence import SequenceResult
from ecdsim.plotting import _figure, plot_title, save_figure, temperature_colors
from ecdsim.units_display import Shown, UnitSystem

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure


@dataclass(frozen=True)
class _Marker:
    """How one kind of event is drawn, and its legend text."""

    symbol: str
    size: float
    label: str


# Drawn in this order, so that a latch at the instant of arrival shows on top.
MARKERS: dict[str, _Marker] = {
    "engage": _Marker("D", 6.0, "damper engages (lost motion closed)"),
    "impact": _Marker("^", 8.0, "impact on a stop (rebounds)"),
    "stick": _Marker("X", 9.0, "sticks (at rest for good)"),
    "creep": _Marker(">", 8.0, "creeps to rest (only asymptotically)"),
    "settle": _Marker("s", 7.0, "settles on the end stop"),
    "latch": _Marker("o", 7.0, "latch at the end of travel"),
}


_OUTCOMES = {
    "latched": "latched",
    "settled": "settled",  # rebounds died out on the end stop
    "stuck": "stuck",
    "creep": "creeps to rest",
    "stop_time": "stop time reached",
    "event_limit": "cut short (events)",
    "horizon": "cut short (horizon)",
    "running": "running",
}


@dataclass(frozen=True)
class DynamicTables:
    """The dynamic method's results as two tables of strings and the notes under them.

    "end of travel": outcome, latch speed and kinetic energy, impacts and rebound, where
    and when it stuck; "damper": when it engaged (lost motion), its peak temperature
    (self-heating), the housing's, the compliant mesh's torques. Columns that would only
    repeat a constant are left out and said in ``notes`` instead; ``damper_rows`` is
    empty when every one of its columns is.
    """

    end_title: str
    end_headers: list[str]
    end_rows: list[list[str]]
    damper_title: str
    damper_headers: list[str]
    damper_rows: list[list[str]]
    notes: list[str]


def _fmt(value: float | None) -> str:
    from ecdsim.formatting import format_number

    return format_number(value, 4, signed_inf=False)


def dynamic_tables(cases: list[dict[str, Any]], u: Shown) -> DynamicTables:
    """:class:`DynamicTables` of the cases of ``Prediction.to_dict()`` (each with its
    ``"dynamic"`` block), in ``u``'s units; ``ecdsim deploy`` prints them, the report
    shows them."""
    dyn = [case["dynamic"] for case in cases]
    temps = [case["temperature_C"] for case in cases]
    impacts = any(d["impacts"] > 0 or d["rebound_speed_rad_s"] != 0.0 for d in dyn)
    stuck = any(d["stuck"] for d in dyn)
    engage = any((d["engagement_time_s"] or 0.0) > 0.0 for d in dyn)
    heated = any(d["max_damper_temperature_C"] != t for d, t in zip(dyn, temps, strict=True))
    mesh = "max_mesh_torque_Nm" in dyn[0]  # a compliant gear mesh (compliant backlash)
    headers = [
        u.head("T", "temperature", "\n"),
        "outcome",
        "latch\nspeed\n[rad/s]",
        u.head("KE at\nlatch", "energy", "\n"),
    ]
    headers += ["im-\npacts", "rebound\n[rad/s]"] if impacts else []
    headers += ["stuck\nat\n[deg]", "stuck\nat\n[s]"] if stuck else []
    rows = []
    for d, t in zip(dyn, temps, strict=True):
        arrived = d["deployment_time_s"] is not None
        row = [
            u.num(t, "temperature"),
            "cannot start"
            if d["stuck"] and d["stuck_angle_rad"] == 0.0
            else _OUTCOMES.get(d["status"], d["status"]),
            _fmt(d["end_speed_rad_s"]) if arrived else "-",
            u.num(d["end_kinetic_energy_J"], "energy") if arrived else "-",
        ]
        if impacts:
            row += [str(d["impacts"]), _fmt(d["rebound_speed_rad_s"])]
        if stuck:
            when = d["stuck_time_s"]
            row += [
                _fmt(math.degrees(d["stuck_angle_rad"])) if d["stuck"] else "-",
                ("inf" if when is None else _fmt(when)) if d["stuck"] else "-",
            ]
        rows.append(row)
    damper_headers: list[str] = []
    damper_rows: list[list[str]] = []
    if engage or heated or mesh:
        damper_headers = [u.head("T", "temperature", "\n")]
        damper_headers += ["engaged at\n[s]"] if engage else []
        damper_headers += [u.head("peak damper\nT", "temperature", "\n")] if heated else []
        housing = heated and "final_housing_temperature_C" in dyn[0]  # two-node heating
        damper_headers += [u.head("housing T\nat end", "temperature", "\n")] if housing else []
        if mesh:
            damper_headers += [u.head("mesh\ntorque\npeak", "torque", "\n")]
            damper_headers += [u.head("mesh\ntorque\nlatched", "torque", "\n")]
        for d, t in zip(dyn, temps, strict=True):
            row = [u.num(t, "temperature")]
            row += [_fmt(d["engagement_time_s"])] if engage else []
            row += [u.num(d["max_damper_temperature_C"], "temperature")] if heated else []
            row += [u.num(d["final_housing_temperature_C"], "temperature")] if housing else []
            if mesh:
                row += [u.num(d["max_mesh_torque_Nm"], "torque")]
                row += [u.num(d["latch_mesh_torque_Nm"], "torque")]
            damper_rows.append(row)
    said = ["latch: speed and kinetic energy on arrival at the end of travel"]
    if not impacts:
        said.append("no impacts (no rebound)")
    if not stuck:
        said.append("never stuck")
    if not engage:
        said.append("no lost motion (engaged at release)")
    if not heated:
        said.append("damper at the ambient temperature (no self-heating)")
    return DynamicTables(
        "Dynamic method: end of travel",
        headers,
        rows,
        "Dynamic method: damper",
        damper_headers,
        damper_rows,
        said,
    )


def dynamic_result(prediction: Prediction) -> DynamicResult | None:
    """The dynamic method's full result, with its time series recorded; None without it."""
    from ecdsim.dynamics.method import DynamicSolution
    from ecdsim.dynamics.solver import solve_dynamic

    solution = prediction.solutions.get("dynamic")
    if not isinstance(solution, DynamicSolution):
        return None
    result = solution.result
    if result.trajectory is None:  # a large batch is solved without recording
        result = solve_dynamic(solution.problem, record=True)
    return result


def events_by_kind(result: DynamicResult) -> dict[str, list[tuple[int, float, float, float]]]:
    """The events to mark, by marker kind: (flat case, time [s], angle [rad], speed [rad/s]).

    An ``arrive`` or ``start_stop`` event is an impact (as the result's ``impacts``
    counts them) unless a ``latch`` of the same case happens at the same instant
    (restitution 0: caught on arrival).
    A ``creep`` (an asymptotic approach to rest, at an infinite time) is drawn at the
    end of its curve; other events at an infinite time are not drawn.
    """
    ev = result.events
    names = [EVENT_KINDS[k] for k in ev.kind]
    caught = {
        (int(c), float(t)) for c, t, n in zip(ev.case, ev.time, names, strict=True) if n == "latch"
    }
    out: dict[str, list[tuple[int, float, float, float]]] = {kind: [] for kind in MARKERS}
    for c, t, n, a, s in zip(ev.case, ev.time, names, ev.angle, ev.speed, strict=True):
        if n == "creep" and result.trajectory is not None:
            t = result.trajectory.display_end[int(c)]
        if not math.isfinite(float(t)):
            continue
        row = (int(c), float(t), float(a), float(s))
        if n in ("arrive", "start_stop"):
            if (int(c), float(t)) not in caught:
                out["impact"].append(row)
        elif n in MARKERS and not (n == "engage" and float(t) == 0.0):
            out[n].append(row)
    return out


def _columns(series: TimeSeries, field: FloatArray) -> tuple[FloatArray, FloatArray]:
    n_t = series.time.shape[0]
    return series.time.reshape(n_t, -1), np.asarray(field).reshape(n_t, -1)


def _mark_events(
    ax: Axes,
    result: DynamicResult,
    quantity: Literal["angle", "speed"],
    colors: list[tuple[float, float, float, float]],
) -> None:
    """The event markers (edged in black, filled in the case's colour) and their legend."""
    for kind, rows in events_by_kind(result).items():
        if not rows:
            continue
        marker = MARKERS[kind]
        for case, time, angle, speed in rows:
            y = math.degrees(angle) if quantity == "angle" else speed
            ax.plot(
                [time],
                [y],
                marker.symbol,
                markersize=marker.size,
                markerfacecolor=colors[case],
                markeredgecolor="black",
                linestyle="none",
                zorder=3,
            )
        # One legend entry per kind of event, in neutral grey.
        ax.plot(
            [],
            [],
            marker.symbol,
            markersize=marker.size,
            markerfacecolor="0.8",
            markeredgecolor="black",
            linestyle="none",
            label=marker.label,
        )


def _result(prediction: Prediction, result: DynamicResult | None) -> DynamicResult:
    found = result if result is not None else dynamic_result(prediction)
    if found is None:
        raise ValueError("the prediction has no dynamic method")
    return found


def plot_dynamic(
    prediction: Prediction,
    quantity: Literal["angle", "speed"],
    units: UnitSystem = "si",
    n_points: int = 801,
    result: DynamicResult | None = None,
) -> Figure:
    """Angle [deg] or speed [rad/s] against time, each temperature, events marked.

    ``result``: the dynamic result with its time series (default: the prediction's).
    """
    result = _result(prediction, result)
    u = Shown(units)
    series = result.sample(n_points=n_points)
    times, values = _columns(series, series.angle if quantity == "angle" else series.speed)
    temps = np.ravel(result.temperature)
    colors = temperature_colors(temps)
    fig = _figure()
    ax = fig.add_subplot()
    for j, temp in enumerate(temps):
        y = np.degrees(values[:, j]) if quantity == "angle" else values[:, j]
        ax.plot(times[:, j], y, color=colors[j], label=u.text(float(temp), "temperature"))
    _mark_events(ax, result, quantity, colors)
    what = "angle" if quantity == "angle" else "load speed"
    ax.set_title(plot_title(prediction.system.name, f"dynamic method, {what} against time"))
    ax.set_xlabel("time since release [s]")
    ax.set_ylabel("deployed angle [deg]" if quantity == "angle" else "load speed [rad/s]")
    ax.set_xlim(left=0.0)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize="small")
    return fig


def heated(result: DynamicResult) -> bool:
    """True when the damper warms above its ambient temperature (self-heating modelled)."""
    return bool(np.any(np.ravel(result.max_damper_temperature) > np.ravel(result.temperature)))


def plot_damper_temperature(
    prediction: Prediction,
    units: UnitSystem = "si",
    n_points: int = 801,
    result: DynamicResult | None = None,
) -> Figure:
    """The damper's temperature rise above ambient against time, at each ambient
    temperature (self-heating). A rise of a fraction of a kelvin would be a flat line on
    the scale of the temperatures themselves (-40 to 100 degC): the axis is the rise."""
    result = _result(prediction, result)
    u = Shown(units)
    series = result.sample(n_points=n_points)
    times, values = _columns(series, series.damper_temperature)
    temps = np.ravel(result.temperature)
    colors = temperature_colors(temps)
    kelvin = u.value(1.0, "temperature_difference")
    fig = _figure()
    ax = fig.add_subplot()
    for j, temp in enumerate(temps):
        rise = (values[:, j] - float(temp)) * kelvin
        peak = float(np.nanmax(rise)) if np.any(np.isfinite(rise)) else 0.0
        label = (
            f"ambient {u.text(float(temp), 'temperature')}: "
            f"peak +{Shown(units, digits=3).num(peak / kelvin, 'temperature_difference')} "
            f"{u.unit('temperature_difference')}"
        )
        ax.plot(times[:, j], rise, color=colors[j], label=label)
    ax.set_title(plot_title(prediction.system.name, "damper self-heating, rise above ambient"))
    ax.set_xlabel("time since release [s]")
    ax.set_ylabel(u.head("damper temperature above ambient", "temperature_difference"))
    ax.set_xlim(left=0.0)
    ax.set_ylim(bottom=0.0)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize="small")
    return fig


def write_dynamic_plots(
    prediction: Prediction, folder: str | Path, units: UnitSystem = "si"
) -> list[Path]:
    """The dynamic method's plots as PNG files in ``folder`` (none without that method)."""
    result = dynamic_result(prediction)
    if result is None:
        return []
    out = Path(folder)
    written = [
        save_figure(
            plot_dynamic(prediction, quantity, units, result=result),
            out / f"dynamic_{quantity}_vs_time.png",
        )
        for quantity in ("angle", "speed")
    ]
    if heated(result):
        figure = plot_damper_temperature(prediction, units, result=result)
        written.append(save_figure(figure, out / "dynamic_damper_temperature.png"))
    return written


def plot_sequence(result: SequenceResult, system: str, units: UnitSystem = "si") -> Figure:
    """Repeated deployments against the deployment number: the deployment time's change
    from the first deployment (top) and the rotor's start and peak temperatures above the
    deployment temperature (bottom), one colour per temperature. Drifts are fractions of
    a percent and of a kelvin beside tens of seconds and degrees, so both panels show
    changes; the axis is logarithmic from 20 deployments on (the drift settles early)."""
    u = Shown(units)
    temps = result.temperatures
    colors = temperature_colors(temps)
    number = np.arange(1, result.cycle.count + 1)
    fig = _figure(7.5, 6.4)
    top, bottom = fig.subplots(2, 1, sharex=True)
    kelvin = u.value(1.0, "temperature_difference")
    for j, temp in enumerate(temps):
        label = f"T = {u.text(float(temp), 'temperature')}"
        times = result.deployment_time[:, j]
        arrived = np.isfinite(times) & np.isfinite(times[0])
        with np.errstate(invalid="ignore", divide="ignore"):  # stalled (inf): masked below
            change = np.where(arrived, 100.0 * (times / times[0] - 1.0), np.nan)  # a gap
        stalls = "" if np.all(arrived) else " (stalls: no time change)"
        top.plot(number, change, color=colors[j], label=label + stalls)
        for values, style, what in (
            (result.peak_rotor_temperature, "-", "peak"),
            (result.start_rotor_temperature, "--", "start"),
        ):
            rise = (values[:, j] - temp) * kelvin
            bottom.plot(number, rise, style, color=colors[j], label=f"{what}, {label}")
    cycle = result.cycle
    schedule = f"cool-down {cycle.cool_down:g} s, stow {cycle.stow_time:g} s"
    top.set_title(plot_title(system, f"{cycle.count} deployments, {schedule}"))
    top.set_ylabel("deployment time change\nfrom deployment 1 [%]")
    bottom.set_ylabel(u.head("rotor temperature above T", "temperature_difference", sep="\n"))
    bottom.set_xlabel("deployment number [-]")
    if cycle.count >= 20:
        bottom.set_xscale("log")
    bottom.set_xlim(1, max(int(number[-1]), 2))
    for ax in (top, bottom):
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize="small")
    return fig
