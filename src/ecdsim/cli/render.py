"""Render a prediction as tables (rich) or JSON; both read the same result dictionary."""

from __future__ import annotations

import json
import math
from typing import Any

from ecdsim.deployment import Prediction
from ecdsim.formatting import format_number
from ecdsim.methods import SOLVERS


def to_json(prediction: Prediction) -> str:
    """The stable JSON document of ``ecdsim deploy --json``."""
    return json.dumps(prediction.to_dict(), indent=2, sort_keys=True, allow_nan=False)


def _fmt(value: float | None, digits: int = 4) -> str:
    return format_number(value, digits, signed_inf=False)


def print_tables(prediction: Prediction) -> None:
    """Print the component table and the deployment table on stdout."""
    from rich.console import Console
    from rich.markup import escape
    from rich.table import Table

    document = prediction.to_dict()
    cases: list[dict[str, Any]] = document["cases"]
    console = Console(soft_wrap=False, width=max(120, Console().width))

    ecd = Table(title="ECD referred to the input shaft (Eq. 1-4)", title_justify="left")
    for header in (
        "T [degC]",
        "BD_T [N*m*s/rad]",
        "BT_T [N*m*s/rad]",
        "FT_T [N*m]",
        "BECD [N*m*s/rad]",
        "FECD [N*m]",
        "FS [N*m]",
    ):
        ecd.add_column(escape(header), justify="right")
    for case in cases:
        c = case["components"]
        ecd.add_row(
            _fmt(case["temperature_C"]),
            _fmt(c["damper_damping_rate_Nms_per_rad"]),
            _fmt(c["high_speed_total_damping_rate_Nms_per_rad"]),
            _fmt(c["high_speed_total_friction_Nm"]),
            _fmt(case["damping_rate_Nms_per_rad"]),
            _fmt(case["friction_Nm"]),
            _fmt(case["system_friction_Nm"]),
        )
    console.print(ecd)

    table = Table(title="Deployment", title_justify="left")
    table.add_column(escape("T [degC]"), justify="right")
    methods = document["methods"]
    for name in methods:
        table.add_column(escape(f"{name}\nt [s]"), justify="right")
    table.add_column(escape("start speed\n[rad/s]"), justify="right")
    table.add_column(escape("end speed\n[rad/s]"), justify="right")
    if "difference" in cases[0]:
        table.add_column(escape("paper - exact\n[s]"), justify="right")
        table.add_column(escape("rel.\n[%]"), justify="right")
    table.add_column("stall", justify="left")
    reference = "exact" if "exact" in methods else methods[0]
    for case in cases:
        row = [_fmt(case["temperature_C"])]
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
            row.append("-" if rel is None else f"{100.0 * rel:+.1f}")
        stall = case[reference]
        row.append(f"at {stall['stall_angle_rad']:.3g} rad" if stall["stalled"] else "no")
        table.add_row(*row)
    console.print(table)
    labels = ", ".join(f"{m} = {SOLVERS[m].label}" for m in methods)
    console.print(escape(f"methods: {labels}; speeds from the {reference} method"), style="dim")
