"""Tables of sizing results as plain rows of strings (the CLI renders them with rich).

Each function returns ``(title, headers, rows)``; no printing here.
"""

from __future__ import annotations

import math

import numpy as np

from ecdsim.formatting import format_number
from ecdsim.sizing.fluid import DeadbandDeployment, FluidComparison
from ecdsim.sizing.ratio import RatioIntervals
from ecdsim.sizing.search import CandidateResult, SearchResult

Table = tuple[str, list[str], list[list[str]]]


def percent(value: float | None) -> str:
    """A margin as a signed percentage."""
    if value is None:
        return "-"
    if math.isinf(value):
        return "inf"
    return f"{100.0 * value:+.1f} %"


def requirements_table(result: SearchResult) -> Table:
    """The requirements in words."""
    r = result.requirements
    rows = [[name, limit] for name, limit in r.describe()]
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


def candidates_table(result: SearchResult) -> Table:
    """The ranked candidates: pass/fail, mass, worst margin, times, spread, torque margin."""
    temps = result.requirements.temperatures
    headers = [
        "#",
        "damper + gearbox N:1",
        "pass",
        "mass [kg]",
        "worst margin",
        "t [s] at " + " / ".join(f"{t:g}" for t in temps) + " degC",
        "spread [s]",
        "torque margin",
        "at [deg, degC]",
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
                    format_number(c.candidate.mass, none="unknown"),
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
                format_number(c.candidate.mass, none="unknown"),
                percent(c.margin),
                " / ".join(format_number(t) for t in c.deployment_time),
                format_number(c.spread),
                format_number(c.torque_margin),
                f"{angle:.0f}, {format_number(c.torque_margin_temperature)}",
            ]
        )
    title = "Candidates, ranked: pass, then mass (unknown last), worst margin, time spread"
    return title, headers, rows


def checks_table(candidate: CandidateResult) -> Table:
    """Each requirement's pass/fail and margin for one candidate."""
    rows = [
        [
            o.label,
            o.result,
            percent(o.margin),
            "-" if o.cannot_start else f"{format_number(o.value)} {o.unit}",
            format_number(o.temperature_C),
        ]
        for o in candidate.checks
    ]
    title = f"Requirements for #{candidate.rank} {candidate.candidate.label}"
    return title, ["requirement", "result", "margin", "value (worst)", "at T [degC]"], rows


# Column headings of the resistive torques, in the order of margin.RESISTIVE_TYPES.
_KIND_HEADERS = {
    "ecd_friction": "FECD",
    "system_friction": "FS",
    "damping": "damping",
    "inertia": "inertia",
    "spring": "spring",
    "harness": "harness",
}


def torque_margin_table(candidate: CandidateResult) -> Table:
    """The torque margin at each temperature with its terms (docs/sizing.md section 5).

    Every torque is in N*m at the ECD input, unfactored, at the angle where the margin is
    smallest; ``sum f*R`` is the factored sum the drive is divided by.
    """
    kinds = [k for k in _KIND_HEADERS if any(k in m.resistive for m in candidate.torque_margins)]
    headers = ["T [degC]", "at [deg]", "drive"]
    headers += [_KIND_HEADERS[k] for k in kinds] + ["sum f*R", "TM"]
    rows = []
    for m in candidate.torque_margins:
        row = [format_number(m.temperature_C), f"{math.degrees(m.angle):.0f}"]
        row += [format_number(m.drive)]
        row += [format_number(m.resistive.get(k, 0.0)) for k in kinds]
        row += [format_number(m.factored), format_number(m.margin)]
        rows.append(row)
    title = (
        f"Torque margin TM = drive / sum(f*R) - 1 of #{candidate.rank} "
        f"{candidate.candidate.label} [N*m at the ECD input]"
    )
    return title, headers, rows


def intervals_table(intervals: RatioIntervals) -> Table:
    """The exact feasible gear-ratio intervals, and each check's own."""
    rows = [
        [
            "all requirements",
            f"{i.low:.6g} to {i.high:.6g}",
            f"{i.low_limited_by} / {i.high_limited_by}",
        ]
        for i in intervals.intervals
    ]
    if not intervals.intervals:
        rows.append(["all requirements", "none in the scanned range", "-"])
    for name, found in intervals.by_check.items():
        text = ", ".join(f"{i.low:.6g} to {i.high:.6g}" for i in found) or "none"
        rows.append([name, text, ""])
    low, high = intervals.ratio_range
    title = (
        f"Gear ratios N meeting the requirements: {intervals.damper} + {intervals.gearbox} "
        f"(exact roots; scanned {low:g} to {high:g}, {intervals.n_grid} points)"
    )
    return title, ["check", "N interval(s)", "limited by (low / high)"], rows


def _time(side: DeadbandDeployment, i: int) -> str:
    return format_number(float(side.damped_time[i]))


def fluid_table(comparison: FluidComparison) -> Table:
    """ECD against fluid damper at each temperature."""
    inertia = comparison.fluid.free_time is not None
    unit = "N*m*s/rad" if comparison.exponent == 1.0 else f"N*m*(s/rad)^{comparison.exponent:g}"
    headers = [
        "T [degC]",
        "BECD [N*m*s/rad]",
        f"fluid c [{unit}]",
        "ECD t [s]",
        "fluid t (damped) [s]",
    ]
    if inertia:
        headers += ["fluid deadband t [s]", "engage speed [rad/s]", "fluid total [s]"]
    headers += ["fluid / ECD"]
    rows = []
    for i, t in enumerate(comparison.temperatures):
        ecd_t = comparison.ecd.total_time if inertia else comparison.ecd.damped_time
        fluid_t = comparison.fluid.total_time if inertia else comparison.fluid.damped_time
        assert ecd_t is not None
        assert fluid_t is not None
        ratio = float(fluid_t[i] / ecd_t[i]) if np.isfinite(ecd_t[i] * fluid_t[i]) else None
        row = [
            format_number(float(t)) + (" (extrapolated)" if comparison.extrapolated[i] else ""),
            format_number(float(comparison.ecd_damping_rate[i])),
            format_number(float(comparison.fluid_coefficient[i])),
            format_number(float(ecd_t[i])),
            _time(comparison.fluid, i),
        ]
        if inertia:
            assert comparison.fluid.free_time is not None
            assert comparison.fluid.engage_speed is not None
            row += [
                format_number(float(comparison.fluid.free_time[i])),
                format_number(float(comparison.fluid.engage_speed[i])),
                format_number(float(fluid_t[i])),
            ]
        row.append(format_number(ratio, 3))
        rows.append(row)
    title = (
        f"ECD against {comparison.name}, matched at {comparison.match_temperature:g} degC "
        f"({comparison.law.describe()}; deadband {np.degrees(comparison.fluid.deadband):.3g} deg)"
    )
    return title, headers, rows
