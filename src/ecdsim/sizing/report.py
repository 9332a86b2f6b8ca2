"""Tables of sizing results as plain rows of strings (the CLI renders them with rich).

Each function returns ``(title, headers, rows)``; no printing here. Each takes the
display units as a :class:`~ecdsim.units_display.Shown` (SI by default).
"""

from __future__ import annotations

import math

import numpy as np

from ecdsim.formatting import format_number
from ecdsim.sizing.fluid import DeadbandDeployment, FluidComparison
from ecdsim.sizing.ratio import SCAN_RANGE, Interval, RatioIntervals
from ecdsim.sizing.search import CandidateResult, SearchResult
from ecdsim.units_display import KIND_BY_SI_UNIT, Shown, convert_text

SI = Shown()

Table = tuple[str, list[str], list[list[str]]]


def percent(value: float | None) -> str:
    """A margin as a signed percentage."""
    if value is None:
        return "-"
    if math.isinf(value):
        return "inf"
    return f"{100.0 * value:+.1f} %"


def requirements_table(result: SearchResult, u: Shown = SI) -> Table:
    """The requirements in words."""
    r = result.requirements
    rows = [[name, limit] for name, limit in r.describe(u.system)]
    m = r.margin
    factors = ", ".join(f"{k} {v:g}" for k, v in m.factors.items())
    rows.append(
        [
            "torque margin factors",
            factors if m.factors_applied else "none applied (all 1)",
        ]
    )
    speed = {
        "deployment": "deployment's own speed",
        "none": "none (speed 0)",
        "fixed": f"{m.damping_speed or 0.0:g} rad/s",
    }[m.damping_mode]
    rows.append(["damping torque in margin at", speed])
    return "Requirements", ["requirement", "limit"], rows


def _temps(temps: tuple[float, ...] | list[float], u: Shown) -> str:
    """Temperatures [degC] as "-40 / 77 / 212 degF" in ``u``'s unit."""
    shown = " / ".join(u.num(float(t), "temperature") for t in temps)
    return f"{shown} {u.unit('temperature')}"


def _quantity(value: float, si_unit: str, u: Shown) -> str:
    """A value in ``si_unit`` shown in ``u``'s system, with its unit ("4.2 lbf*in")."""
    kind = KIND_BY_SI_UNIT.get(si_unit)
    if kind is None:
        return f"{format_number(value)} {si_unit}".rstrip()
    return u.text(value, kind)


def candidates_table(result: SearchResult, u: Shown = SI) -> Table:
    """The ranked candidates: pass/fail, mass, worst margin, times, spread, torque margin."""
    temps = result.requirements.temperatures
    headers = [
        "#",
        "damper + gearbox N:1",
        "pass",
        u.head("mass", "mass"),
        "worst margin",
        "t [s] at " + _temps(temps, u),
        "spread [s]",
        "torque margin",
        f"at [deg, {u.unit('temperature')}]",
    ]
    rows = []
    for c in result.candidates:
        label = c.candidate.label + (" *" if c.candidate.illustrative else "")
        if c.error is not None:
            rows.append(
                [
                    str(c.rank),
                    label,
                    "error",
                    u.num(c.candidate.mass, "mass"),
                    c.error,
                    "",
                    "",
                    "",
                    "",
                ]
            )
            continue
        angle = np.degrees(c.torque_margin_angle or 0.0)
        rows.append(
            [
                str(c.rank),
                label,
                "yes" if c.passed else "no",
                u.num(c.candidate.mass, "mass"),
                percent(c.margin),
                " / ".join(format_number(t) for t in c.deployment_time),
                format_number(c.spread),
                format_number(c.torque_margin),
                f"{angle:.0f}, {u.num(c.torque_margin_temperature, 'temperature')}",
            ]
        )
    title = "Candidates, ranked: pass, then mass (unknown last), worst margin, time spread"
    return title, headers, rows


# Each check's margin in words (sizing.requirements, docs/sizing.md): >= 0 is met.
MARGIN_DEFINITIONS = {
    "min_deployment_time": "1 - t_min / t",
    "max_deployment_time": "t_max / t - 1",
    "max_end_speed": "(v_max - v) / v_max",
    "max_input_torque": "(limit - torque) / limit",
    "no_stall": "(least spring torque - friction) / friction",
    "min_torque_margin": "TM - TM_min",
    "damper_max_torque": "(max - torque) / max",
    "damper_linear_speed": "(limit - speed) / limit",
    "damper_linear_torque": "(limit - torque) / limit",
    "gearbox_max_output_torque": "(max - torque) / max",
}


def checks_table(candidate: CandidateResult, u: Shown = SI) -> Table:
    """Each requirement's pass/fail and its margin at every temperature, for one candidate.

    The worst value and where it occurs follow (secondary columns); the margins'
    definitions are in :func:`margin_definitions`.
    """
    temps = candidate.temperatures
    rows = []
    for o in candidate.checks:
        margins = o.margins or tuple(o.margin if t == o.temperature_C else math.nan for t in temps)
        rows.append(
            [
                convert_text(o.label, u.system),
                o.result,
                *("-" if math.isnan(m) else percent(m) for m in margins),
                "-" if o.cannot_start else _quantity(o.value, o.unit, u),
                u.num(o.temperature_C, "temperature"),
            ]
        )
    title = (
        f"Requirements for #{candidate.rank} {candidate.candidate.label}: "
        "margin at each temperature"
    )
    headers = ["requirement", "result", *(u.text(t, "temperature") for t in temps)]
    return title, [*headers, "value (worst)", u.head("at T", "temperature")], rows


def margin_definitions(candidate: CandidateResult, u: Shown = SI) -> list[str]:
    """Lines defining the margins of ``candidate``'s checks (>= 0 is met)."""
    return [
        "margin, >= 0 where met (the smallest over the temperatures decides):",
        *(
            f"  {convert_text(o.label, u.system)}: {MARGIN_DEFINITIONS[o.name]}"
            for o in candidate.checks
            if o.name in MARGIN_DEFINITIONS
        ),
    ]


def recommendation(result: SearchResult, u: Shown = SI) -> list[str]:
    """The recommended candidate (rank 1) and why it ranks first, in words.

    The ranking (:func:`ecdsim.sizing.search.rank_key`): meeting every requirement first,
    then the lighter (an unknown mass after every known one), then the larger worst
    margin, then the smaller spread of deployment times. The reason given is the first
    of these that separates #1 from the next candidate that also meets everything.
    """
    valid = [c for c in result.candidates if c.error is None]
    temps = ", ".join(u.num(t, "temperature") for t in result.requirements.temperatures)
    temps += f" {u.unit('temperature')}"
    if not valid:
        return ["No candidate could be evaluated (see the errors in the table)."]
    best = valid[0]
    label = best.candidate.label + (" (illustrative *)" if best.candidate.illustrative else "")
    worst = min(best.checks, key=lambda o: o.margin) if best.checks else None
    at_worst = (
        ""
        if worst is None
        else f" ({convert_text(worst.label, u.system)}, at "
        f"{u.text(worst.temperature_C, 'temperature')})"
    )
    passing = [c for c in valid if c.passed]
    if not passing:
        return [
            f"No candidate meets every requirement at {temps}. Closest: #{best.rank} "
            f"{label}, worst margin {percent(best.margin)}{at_worst}; the gear-ratio "
            "intervals below show which ratios would."
        ]
    mass = best.candidate.mass
    return [
        f"Recommended: #{best.rank} {label}: meets every requirement at {temps}; "
        f"mass {u.text(mass, 'mass')}; smallest margin "
        f"{percent(best.margin)}{at_worst}.",
        f"Why first: {_why(best, passing, len(valid), u)}",
    ]


def _why(
    best: CandidateResult, passing: list[CandidateResult], evaluated: int, u: Shown = SI
) -> str:
    """The first ranking criterion that puts ``best`` ahead of the next passing one."""
    if len(passing) == 1:
        return f"the only one of the {evaluated} candidates that meets every requirement."
    other = passing[1]
    mass, other_mass = best.candidate.mass, other.candidate.mass
    versus = f"#{other.rank} {other.candidate.label}"
    if mass is not None and other_mass is None:
        return (
            f"the only one of the {len(passing)} that pass with a known mass; {versus} "
            "and the others have no known mass ('-')."
        )
    if mass is not None and other_mass is not None and mass != other_mass:
        return (
            f"the lightest of the {len(passing)} that pass: {u.text(mass, 'mass')} "
            f"against {u.text(other_mass, 'mass')} for {versus}."
        )
    same = "no passing candidate has a known mass" if mass is None else "same mass as " + versus
    if best.margin != other.margin:
        return (
            f"{same}; larger smallest margin, {percent(best.margin)} against "
            f"{percent(other.margin)}."
        )
    if best.spread != other.spread:
        return (
            f"{same} and margin; smaller spread of deployment times, "
            f"{format_number(best.spread)} s against {format_number(other.spread)} s."
        )
    return f"{same}, margin and spread of deployment times: the two are ordered by name."


# Column headings of the resistive torques, in the order of margin.RESISTIVE_TYPES.
_KIND_HEADERS = {
    "ecd_friction": "FECD",
    "system_friction": "FS",
    "damping": "damping",
    "inertia": "inertia",
    "spring": "spring",
    "harness": "harness",
    "resistive_table": "resist.",
    "gravity": "gravity",
    "gear_loss": "gear loss",
}


def torque_margin_table(candidate: CandidateResult, u: Shown = SI) -> Table:
    """The torque margin at each temperature with its terms (docs/sizing.md section 5).

    Every torque is in N*m (lbf*in in US units) at the ECD input, unfactored, at the
    angle where the margin is smallest; ``sum f*R`` is the factored sum the drive is divided by.
    """
    kinds = [k for k in _KIND_HEADERS if any(k in m.resistive for m in candidate.torque_margins)]
    headers = [u.head("T", "temperature"), "at [deg]", "drive"]
    headers += [_KIND_HEADERS[k] for k in kinds] + ["sum f*R", "TM"]
    rows = []
    for m in candidate.torque_margins:
        row = [u.num(m.temperature_C, "temperature"), f"{math.degrees(m.angle):.0f}"]
        row += [u.num(m.drive, "torque")]
        row += [u.num(m.resistive.get(k, 0.0), "torque") for k in kinds]
        row += [u.num(m.factored, "torque"), format_number(m.margin)]
        rows.append(row)
    title = (
        f"Torque margin TM = drive / sum(f*R) - 1 of #{candidate.rank} "
        f"{candidate.candidate.label} [{u.unit('torque')} at the ECD input]"
    )
    return title, headers, rows


# A check's name in words, where no candidate's label is at hand.
PLAIN_NAMES = {
    "min_deployment_time": "shortest deployment time",
    "max_deployment_time": "longest deployment time",
    "max_end_speed": "end speed",
    "max_input_torque": "ECD input torque",
    "no_stall": "no stall",
    "min_torque_margin": "torque margin",
    "damper_max_torque": "damper torque <= catalogue max",
    "damper_linear_speed": "damper speed <= linear-range limit",
    "damper_linear_torque": "damper eddy torque <= linear-range limit",
    "gearbox_max_output_torque": "gearbox torque <= catalogue max",
}
NO_BOUND = "no bound in the scanned range"


def check_labels(
    result: SearchResult, damper: str | None, gearbox: str | None, u: Shown = SI
) -> dict[str, str]:
    """Each check's name in words, as the requirements table says it ("deployment time
    <= 60 s", in ``u``'s units): from a candidate of ``damper`` and ``gearbox`` (any
    ratio), else any candidate, else :data:`PLAIN_NAMES`."""
    labels = dict(PLAIN_NAMES)
    ordered = sorted(
        (c for c in result.candidates if c.error is None),
        key=lambda c: (c.candidate.damper.name, c.candidate.gearbox.name) == (damper, gearbox),
    )
    for candidate in ordered:  # the chosen pair's labels last, so they win
        labels.update({o.name: convert_text(o.label, u.system) for o in candidate.checks})
    return labels


def _ratio(value: float) -> str:
    return format_number(value, 4)


def interval_text(interval: Interval) -> str:
    """A feasible interval in words: "407.1 to 534.8", ">= 407.1" or "<= 729.2" where
    the other end is only the end of the scan, :data:`NO_BOUND` where both are."""
    low = interval.low_limited_by != SCAN_RANGE
    high = interval.high_limited_by != SCAN_RANGE
    if low and high:
        return f"{_ratio(interval.low)} to {_ratio(interval.high)}"
    if low:
        return f">= {_ratio(interval.low)}"
    if high:
        return f"<= {_ratio(interval.high)}"
    return NO_BOUND


def intervals_table(intervals: RatioIntervals, labels: dict[str, str] | None = None) -> Table:
    """The exact feasible gear-ratio intervals, and each check's own, in words.

    An end that is only the end of the scanned range is no bound: it is never printed
    as one ("<= 729.2", not "10 to 729.2"). ``labels``: each check's name in words
    (:func:`check_labels`); :data:`PLAIN_NAMES` by default.
    """
    words = labels if labels is not None else PLAIN_NAMES

    def by(name: str) -> str:
        return NO_BOUND if name == SCAN_RANGE else words.get(name, name.replace("_", " "))

    rows = [
        [
            "all requirements",
            interval_text(i),
            f"low: {by(i.low_limited_by)}; high: {by(i.high_limited_by)}",
        ]
        for i in intervals.intervals
    ]
    if not intervals.intervals:
        rows.append(["all requirements", "none in the scanned range", "-"])
    for name, found in intervals.by_check.items():
        text = ", ".join(interval_text(i) for i in found) or "none in the scanned range"
        rows.append([words.get(name, name), text, ""])
    low, high = intervals.ratio_range
    title = (
        f"Gear ratios N meeting the requirements: {intervals.damper} + {intervals.gearbox} "
        f"(exact roots; scanned {low:g} to {high:g}, {intervals.n_grid} points)"
    )
    return title, ["requirement", "gear ratios N", "limited by"], rows


def _time(side: DeadbandDeployment, i: int) -> str:
    return format_number(float(side.damped_time[i]))


def fluid_table(comparison: FluidComparison, u: Shown = SI) -> Table:
    """ECD against fluid damper at each temperature.

    A viscosity law matched to the ECD shows both dampings; a measured power law (not
    matched) shows both dampers' torque at its reference speed and the exponent n(T).
    Both show the damped phase by the exact solution and by the paper's mean-speed method.
    """
    inertia = comparison.fluid.free_time is not None
    measured = comparison.match_temperature is None
    # The fluid coefficient is a torque per speed^n: its factor is the torque's.
    torque = u.unit("torque")
    rate = u.unit("damping_rate")
    exponent = comparison.exponent
    unit = rate if exponent == 1.0 else f"{torque}*(s/rad)^{exponent:g}"
    speed = comparison.reference_speed
    if measured:
        headers = [
            u.head("T", "temperature"),
            u.head("ECD at w_r", "torque"),
            u.head("fluid at w_r", "torque"),
            "fluid n",
        ]
    else:
        headers = [
            u.head("T", "temperature"),
            u.head("BECD", "damping_rate"),
            f"fluid c [{unit}]",
        ]
    headers += ["ECD t [s]", "fluid t (damped) [s]"]
    if inertia:
        headers += ["fluid deadband t [s]", "engage speed [rad/s]", "fluid total [s]"]
    headers += ["fluid / ECD", "fluid t (paper) [s]"]
    ecd_shock, fluid_shock = comparison.engagement_torques()
    if ecd_shock is not None:
        headers += [u.head("fluid shock", "torque"), u.head("ECD shock", "torque")]
    at_reference = comparison.torques_at_reference()
    rows = []
    for i, t in enumerate(comparison.temperatures):
        ecd_t = comparison.ecd.total_time if inertia else comparison.ecd.damped_time
        fluid_t = comparison.fluid.total_time if inertia else comparison.fluid.damped_time
        assert ecd_t is not None
        assert fluid_t is not None
        ratio = float(fluid_t[i] / ecd_t[i]) if np.isfinite(ecd_t[i] * fluid_t[i]) else None
        label = u.num(float(t), "temperature") + (
            (" *" if measured else " (extrapolated)") if comparison.extrapolated[i] else ""
        )
        if measured:
            assert at_reference is not None
            row = [
                label,
                u.num(float(at_reference[0][i]), "torque"),
                u.num(float(at_reference[1][i]), "torque"),
                format_number(float(comparison.exponents[i]), 3),
            ]
        else:
            row = [
                label,
                u.num(float(comparison.ecd_damping_rate[i]), "damping_rate"),
                u.num(float(comparison.fluid_coefficient[i]), "torque"),
            ]
        row += [format_number(float(ecd_t[i])), _time(comparison.fluid, i)]
        if inertia:
            assert comparison.fluid.free_time is not None
            assert comparison.fluid.engage_speed is not None
            row += [
                format_number(float(comparison.fluid.free_time[i])),
                format_number(float(comparison.fluid.engage_speed[i])),
                format_number(float(fluid_t[i])),
            ]
        row.append(format_number(ratio, 3))
        paper = comparison.fluid.paper_time
        row.append("-" if paper is None else _paper_time(float(paper[i])))
        if ecd_shock is not None and fluid_shock is not None:
            row += [
                u.num(float(fluid_shock[i]), "torque"),
                u.num(float(ecd_shock[i]), "torque"),
            ]
        rows.append(row)
    deadband = f"deadband {np.degrees(comparison.fluid.deadband):.3g} deg"
    if comparison.method != "quasi-static":  # the default is not named
        deadband += f"; {comparison.method} method"
    if measured:
        title = (
            f"ECD against {comparison.name}, measured ({comparison.law.describe()}; {deadband}; "
            f"torques at w_r = {speed:g} rad/s)"
        )
    else:
        assert comparison.match_temperature is not None
        title = (
            f"ECD against {comparison.name}, matched at "
            f"{u.text(comparison.match_temperature, 'temperature')} "
            f"({comparison.law.describe()}; {deadband})"
        )
    return title, headers, rows


def _paper_time(value: float) -> str:
    return "stalls" if not np.isfinite(value) else format_number(value)
