"""The report of a wing file: ``ecdsim report WING.toml`` (docs/wing.md, report).

One self-contained HTML file, in the single hinge's report's style (the same stylesheet,
``_style.html.j2``, provenance, warnings, tables whose cells carry ``data-case`` and
``data-key``, figures inline, the SI JSON embedded): per temperature the deployment time,
the latch sequence, the hinges left stuck and the energy balance; per hinge its latch
time, speed, the wing's kinetic energy on arrival, the compliant latch's peak torque, the
impact loss, its final angle and its damper's peak temperature where the heating is
modelled; the energy account; the hinge angles against time and a shape strip per
temperature (the figures ``ecdsim deploy --plot`` writes). Numbers are shown in the
report's units (``--units`` or the file's ``[output] units``), as the single hinge's.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ecdsim.atomic import write_text
from ecdsim.report.builder import (
    DATA_ELEMENT_ID,
    figure_data_uri,
    provenance_of,
    template_environment,
)
from ecdsim.units_display import Shown

if TYPE_CHECKING:
    from ecdsim.config.wing_schema import WingConfig
    from ecdsim.units_display import UnitSystem
    from ecdsim.wing.model import Hinge, Wing
    from ecdsim.wing.result import LatchEvent, WingCase, WingResult

# The energy account's columns: (key, header), each summed over the hinges [J].
ENERGY_COLUMNS = (
    ("spring_work", "spring work"),
    ("gravity_work", "gravity work"),
    ("damper_dissipation", "damper"),
    ("friction_dissipation", "friction"),
    ("latch_dissipation", "latch damping"),
    ("impact_loss", "impact loss"),
    ("gear_loss", "gear loss"),
    ("engagement_loss", "lost-motion catch"),
    ("final_kinetic", "kinetic at the end"),
    ("elastic", "elastic at the end"),
)


# Columns shown only where some hinge's ECD has the effect: a lossy gear, lost motion.
def _has_key(hinge: Hinge, key: str) -> bool:
    ecd = hinge.ecd
    if ecd is None:
        return False
    if key == "gear_loss":
        return ecd.ecd.gearbox.efficiency is not None
    return ecd.lost_motion > 0.0


def _energy_columns(wing: Wing) -> list[tuple[str, str]]:
    """The account's columns for this wing: the optional losses only where present."""
    optional = ("gear_loss", "engagement_loss")
    return [
        (key, label)
        for key, label in ENERGY_COLUMNS
        if key not in optional or any(_has_key(h, key) for h in wing.hinges)
    ]


def _energy_cells(case: WingCase, u: Shown, columns: list[tuple[str, str]]) -> list[dict[str, str]]:
    energy = case.energy
    values = {
        "spring_work": float(energy.spring_work.sum()),
        "gravity_work": energy.gravity_work,
        "damper_dissipation": float(energy.damper_dissipation.sum()),
        "friction_dissipation": float(energy.friction_dissipation.sum()),
        "latch_dissipation": float(energy.latch_dissipation.sum()),
        "impact_loss": float(energy.impact_loss.sum()),
        "gear_loss": float(energy.mesh_loss.sum()),
        "engagement_loss": float(energy.engagement_losses.sum()),
        "final_kinetic": energy.final_kinetic,
        "elastic": energy.cable_elastic + energy.latch_elastic,
    }
    return [{"key": key, "text": u.num(values[key], "energy")} for key, _ in columns]


def _hinge_rows(result: WingResult, u: Shown) -> list[dict[str, Any]]:
    rows = []
    for i, case in enumerate(result.cases):
        first: dict[int, LatchEvent] = {}
        for record in case.latches:
            first.setdefault(record.hinge, record)
        peaks = case.peak_damper_temperature
        for j, name in enumerate(result.hinges):
            latch = first.get(j)
            stuck = j in case.stuck_hinges
            missing = "stuck" if stuck else "-"
            peak = peaks[j] if j < len(peaks) else None
            cells = [
                ("latch_time_s", u.num(latch.time, "time") if latch else missing),
                ("latch_speed_rad_s", u.num(latch.speed, "angular_speed") if latch else "-"),
                ("kinetic_energy_J", u.num(latch.kinetic_energy, "energy") if latch else "-"),
                ("peak_torque_Nm", u.num(latch.peak_torque, "torque") if latch else "-"),
                ("impact_loss_J", u.num(latch.impact_loss, "energy") if latch else "-"),
                ("final_angle_rad", u.num(float(case.angle[-1, j]), "angle")),
                ("peak_damper_temperature_C", u.num(peak, "temperature")),
            ]
            rows.append(
                {
                    "case": i,
                    "hinge_index": j,
                    "temperature": u.num(case.temperature, "temperature"),
                    "hinge": name,
                    "cells": [{"key": key, "text": text} for key, text in cells],
                }
            )
    return rows


def _warnings(result: WingResult, u: Shown) -> list[dict[str, str]]:
    """A stall, a stuck hinge, a run cut short: each said once per temperature."""
    out = []
    for case in result.cases:
        at = u.text(case.temperature, "temperature")
        if case.stuck_hinges:
            names = ", ".join(result.hinges[j] for j in case.stuck_hinges)
            out.append(
                {
                    "code": "stuck",
                    "message": f"at {at} the wing comes to rest with {names} short of its "
                    "latch: it does not deploy",
                }
            )
        elif case.status != "latched":
            out.append(
                {
                    "code": case.status,
                    "message": f"at {at} the run ended without every latch: {case.status}",
                }
            )
    return out


def _figures(result: WingResult, config: WingConfig, u: Shown) -> list[dict[str, str]]:
    from ecdsim.plotting_wing import plot_hinge_angles, plot_wing_shapes

    figures = [
        {
            "id": "wing_hinge_angles",
            "caption": "Each hinge's deployed angle against time (travels dotted, events "
            "marked), one panel per temperature.",
            "src": figure_data_uri(plot_hinge_angles(result, config.wing)),
        }
    ]
    for case in result.cases:
        label = f"{case.temperature:+g}".replace("+", "p").replace("-", "m")
        figures.append(
            {
                "id": f"wing_shapes_{label}C",
                "caption": "The wing's shape from release to the end at "
                f"{u.text(case.temperature, 'temperature')} (drawn in SI).",
                "src": figure_data_uri(plot_wing_shapes(config.wing, result, case.temperature)),
            }
        )
    return figures


def build_wing_context(
    config: WingConfig, result: WingResult, config_text: str, units: UnitSystem = "si"
) -> dict[str, Any]:
    """Everything the wing report shows, in ``units``."""
    u = Shown(units, digits=6)
    document = result.to_dict()
    document["display_units"] = units
    provenance = provenance_of(config.source, config.sha256)
    cases = []
    for i, case in enumerate(result.cases):
        order = " > ".join(result.hinges[j] for j in case.sequence) or "none"
        cases.append(
            {
                "case": i,
                "temperature": u.num(case.temperature, "temperature"),
                "status": case.status,
                "deployment_time": u.num(case.deployment_time, "time")
                if math.isfinite(case.deployment_time)
                else "does not deploy",
                "sequence": order,
                "stuck": ", ".join(result.hinges[j] for j in case.stuck_hinges) or "none",
                "energy_error": f"{case.energy.error:.1e}",
            }
        )
    n = len(result.hinges)
    columns = _energy_columns(config.wing)
    summary = (
        f"{n} hinges ({', '.join(result.hinges)}), solved by ecdsim's wing solver (the dynamic "
        f"core, validated against an independent Lagrangian; docs/wing.md) at rtol {config.rtol:g}."
    )
    return {
        "title": config.spec.title,
        "provenance": provenance,
        "method": f"wing: {result.source}",
        "units_name": "SI" if units == "si" else "US customary",
        "warnings": _warnings(result, u),
        "no_findings": "No findings: every hinge latched at every temperature.",
        "wing_summary": summary,
        "wing_cases": cases,
        "wing_hinges": _hinge_rows(result, u),
        "wing_energy": [
            {
                "case": i,
                "temperature": u.num(c.temperature, "temperature"),
                "cells": _energy_cells(c, u, columns),
            }
            for i, c in enumerate(result.cases)
        ],
        "energy_headers": [label for _, label in columns],
        "figures": _figures(result, config, u),
        "config_text": config_text,
        "t_unit": u.unit("temperature"),
        "speed_unit": u.unit("angular_speed"),
        "energy_unit": u.unit("energy"),
        "torque_unit": u.unit("torque"),
        "angle_unit": u.unit("angle"),
        "data_id": DATA_ELEMENT_ID,
        "data_json": json.dumps(
            {"wing": document, "provenance": provenance}, sort_keys=True, allow_nan=False
        ).replace("</", "<\\/"),
    }


def render_wing_html(
    config: WingConfig, result: WingResult, config_text: str, units: UnitSystem = "si"
) -> str:
    """The wing report as one self-contained HTML document."""
    template = template_environment().get_template("wing_report.html.j2")
    return template.render(**build_wing_context(config, result, config_text, units))


def write_wing_report(
    config: WingConfig,
    result: WingResult,
    config_text: str,
    path: Path,
    units: UnitSystem = "si",
) -> Path:
    """Render the wing report in ``units`` and write it atomically to ``path``."""
    return write_text(path, render_wing_html(config, result, config_text, units))
