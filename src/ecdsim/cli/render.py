"""Render a prediction as tables (rich) or JSON; both read the same result dictionary."""

from __future__ import annotations

import json
import math
from typing import Any

from ecdsim.cli import display
from ecdsim.config.placeholder import JSON_KEY as PLACEHOLDER_KEY
from ecdsim.config.placeholder import TITLE as PLACEHOLDER_TITLE
from ecdsim.deployment import Prediction
from ecdsim.formatting import describe_method, format_number
from ecdsim.methods import SOLVERS
from ecdsim.units_display import Shown, UnitSystem


def to_json(prediction: Prediction, units: UnitSystem = "si", placeholder: bool = False) -> str:
    """The stable JSON document of ``ecdsim deploy --json`` (SI; ``display_units`` noted;
    ``"placeholder_load": true`` when the config's load is a marked placeholder)."""
    document = prediction.to_dict()
    document["display_units"] = units
    if placeholder:
        document[PLACEHOLDER_KEY] = True
    return json.dumps(document, indent=2, sort_keys=True, allow_nan=False)


def _percent(fraction: float | None) -> str:
    """A relative difference in percent, signed, one decimal; "0.0" rather than "-0.0"."""
    if fraction is None:
        return "-"
    text = f"{100.0 * fraction:+.1f}"
    return "0.0" if text in ("+0.0", "-0.0") else text


def _fmt(value: float | None, digits: int = 4) -> str:
    return format_number(value, digits, signed_inf=False)


def print_tables(
    prediction: Prediction, units: UnitSystem = "si", placeholder: bool = False
) -> None:
    """Print the component table and the deployment table on stdout, in ``units``; with
    ``placeholder`` (a marked stand-in load) the deployment table's title says so."""
    from rich.markup import escape
    from rich.table import Table

    u = Shown(units)
    document = prediction.to_dict()
    cases: list[dict[str, Any]] = document["cases"]
    console = display.make_console()

    ecd = Table(title="ECD referred to the input shaft (Eq. 1-4)", title_justify="left")
    for header in (
        u.head("T", "temperature"),
        u.head("BD_T", "damping_rate"),
        u.head("BT_T", "damping_rate"),
        u.head("FT_T", "torque"),
        u.head("BECD", "damping_rate"),
        u.head("FECD", "torque"),
        u.head("FS", "torque"),
    ):
        ecd.add_column(escape(header), justify="right")
    for case in cases:
        c = case["components"]
        ecd.add_row(
            u.num(case["temperature_C"], "temperature"),
            u.num(c["damper_damping_rate_Nms_per_rad"], "damping_rate"),
            u.num(c["high_speed_total_damping_rate_Nms_per_rad"], "damping_rate"),
            u.num(c["high_speed_total_friction_Nm"], "torque"),
            u.num(case["damping_rate_Nms_per_rad"], "damping_rate"),
            u.num(case["friction_Nm"], "torque"),
            u.num(case["system_friction_Nm"], "torque"),
        )
    # The summary (BECD, FECD, FS) stays; the components behind it go first at 80 columns.
    display.show(console, ecd, drop=("BD_T", "BT_T", "FT_T"))

    # With [load.gravity] the configured system is the ground test; flight follows below.
    title = "Deployment (ground test, 1 g)" if "ground_test" in document else "Deployment"
    if placeholder:
        title += f": {PLACEHOLDER_TITLE}"
    table = Table(title=title, title_justify="left")
    table.add_column(escape(u.head("T", "temperature")), justify="right")
    methods = document["methods"]
    for name in methods:
        table.add_column(escape(f"{name}\nt [s]"), justify="right")
    table.add_column(escape("start speed\n[rad/s]"), justify="right")
    table.add_column(escape("end speed\n[rad/s]"), justify="right")
    if "difference" in cases[0]:
        table.add_column(escape("paper - exact\n[s]"), justify="right")
        table.add_column(escape("rel.\n[%]"), justify="right")
    table.add_column("stall", justify="left", no_wrap=False)
    reference = "exact" if "exact" in methods else methods[0]
    for case in cases:
        row = [u.num(case["temperature_C"], "temperature")]
        row += [
            _fmt(case[m]["deployment_time_s"] if not case[m]["stalled"] else math.inf)
            for m in methods
        ]
        row += [
            _fmt(case[reference]["start_speed_rad_s"]),
            _fmt(case[reference]["end_speed_rad_s"]),
        ]
        if "difference" in case:
            diff = case["difference"]
            row.append(_fmt(diff["deployment_time_s"]))
            rel = diff["relative"]
            row.append(_percent(rel))
        row.append(stall_text(case, methods))
        table.add_row(*row)
    # The difference in seconds goes first: it follows from the two time columns, while
    # the relative difference is the paper's figure of merit (docs/model.md).
    drop = ("paper - exact", "rel.", "start speed")
    display.show(console, table, drop=drop, wrap=("stall",))
    labels = "; ".join(f"{m} = {describe_method(m, SOLVERS[m].label)}" for m in methods)
    said = f"methods: {labels}. Speeds from the {reference} method"
    if "difference" in cases[0]:
        said += "; rel. = (paper - exact) / exact, the paper's error in percent"
    display.note(console, said)
    if "dynamic" in methods:
        print_dynamic_table(console, cases, u)
    if "ground_test" in document:
        print_ground_test_table(console, document["ground_test"], methods, u)


def print_ground_test_table(
    console: Any, ground: dict[str, Any], methods: list[str], u: Shown
) -> None:
    """Flight (0 g) against the ground test (1 g, offloaded), per temperature and method."""
    offload = 100.0 * ground["offload"]
    title = f"Flight (0 g) against ground test (1 g, {offload:.3g} % offloaded)"
    headers = [u.head("T", "temperature"), "method", "flight t\n[s]", "test t\n[s]"]
    headers += ["test - flight\n[s]", "rel.\n[%]"]
    rows = []
    for case in ground["cases"]:
        for name in methods:
            m = case[name]
            rel = m["relative"]
            rows.append(
                [
                    u.num(case["temperature_C"], "temperature"),
                    name,
                    _fmt(
                        m["flight_deployment_time_s"]
                        if m["flight_deployment_time_s"] is not None
                        else math.inf
                    ),
                    _fmt(
                        m["test_deployment_time_s"]
                        if m["test_deployment_time_s"] is not None
                        else math.inf
                    ),
                    _fmt(m["test_minus_flight_s"]),
                    _percent(rel),
                ]
            )
    _simple_table(console, title, headers, rows)
    display.note(
        console,
        "gravity torque m g r (1 - offload) sin(theta_0 + phi), positive opposing "
        f"deployment: {_fmt(ground['torque_at_release_Nm'])} N*m at release, "
        f"{_fmt(ground['torque_at_latch_Nm'])} N*m at the latch "
        f"(m = {_fmt(ground['mass_kg'])} kg, r = {_fmt(ground['cg_radius_m'])} m); "
        "inf = stalls",
    )


def _stop_text(outcome: dict[str, Any], method: str) -> str | None:
    """Where one method's deployment stops for good, or None if it reaches the end."""
    if method == "dynamic" and outcome.get("stuck"):
        angle = outcome["stuck_angle_rad"]  # also a stop after a rebound off the end
    elif outcome["stalled"]:
        angle = outcome["stall_angle_rad"]
    else:
        return None
    # Degrees, as the plots, the explorer and the warnings give an angle (issue 26 item 4).
    return "cannot start" if angle == 0.0 else f"at {math.degrees(angle):.3g} deg"


def stall_text(case: dict[str, Any], methods: list[str]) -> str:
    """The stall cell of one temperature: "no" only if no method stalls or sticks.

    Methods that agree are named once ("cannot start", "at 84.8 deg"); otherwise each
    method that stops is ("dynamic: at 85.9 deg").
    """
    stops = {m: _stop_text(case[m], m) for m in methods}
    found = {m: text for m, text in stops.items() if text is not None}
    if not found:
        return "no"
    if len(found) == len(methods) and len(set(found.values())) == 1:
        return next(iter(found.values()))
    return "; ".join(f"{m}: {text}" for m, text in found.items())


def print_dynamic_table(console: Any, cases: list[dict[str, Any]], u: Shown | None = None) -> None:
    """The dynamic method's own results, in two tables that each fit 80 columns
    (:func:`ecdsim.plotting_dynamic.dynamic_tables`, which the report shows too)."""
    from ecdsim.plotting_dynamic import dynamic_tables

    tables = dynamic_tables(cases, u or Shown())
    _simple_table(console, tables.end_title, tables.end_headers, tables.end_rows)
    if tables.damper_rows:
        _simple_table(console, tables.damper_title, tables.damper_headers, tables.damper_rows)
    display.note(console, "; ".join(tables.notes))


def _simple_table(console: Any, title: str, headers: list[str], rows: list[list[str]]) -> None:
    from rich.markup import escape
    from rich.table import Table

    table = Table(title=title, title_justify="left")
    for header in headers:
        table.add_column(escape(header), justify="left" if header == "outcome" else "right")
    for row in rows:
        table.add_row(*row)
    display.show(console, table, wrap=("outcome",))
