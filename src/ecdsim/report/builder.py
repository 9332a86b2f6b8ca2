"""Collect a report's data from library calls and render it as one self-contained HTML file.

Every number comes from the calls the CLI makes: :func:`ecdsim.deployment.predict` (as
``ecdsim deploy`` calls it), :meth:`~ecdsim.deployment.Prediction.to_dict` (the JSON of
``ecdsim deploy --json``, embedded verbatim in the report), :mod:`ecdsim.plotting` for the
figures and :func:`ecdsim.sizing.search.evaluate` for the torque margins. Nothing here
computes physics; the tables only format and subtract numbers already in that JSON.
"""

from __future__ import annotations

import base64
import datetime as dt
import io
import json
from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from pydantic import BaseModel

from ecdsim._version import __version__
from ecdsim.atomic import write_text
from ecdsim.config.errors import ConfigError
from ecdsim.config.placeholder import is_placeholder
from ecdsim.config.units import Kind
from ecdsim.deployment import Prediction, predict, with_flight
from ecdsim.formatting import describe_method, format_number
from ecdsim.methods import SOLVERS
from ecdsim.model import TabulatedTemperatureLaw
from ecdsim.units_display import KIND_BY_SI_UNIT, Shown, UnitSystem, convert_text, kind_of_key

if TYPE_CHECKING:
    import jinja2
    from matplotlib.figure import Figure

    from ecdsim.config import Config

DATA_ELEMENT_ID = "ecdsim-data"

# (JSON key in "components"/case, column header, unit); the paper's symbols.
COMPONENT_COLUMNS: tuple[tuple[str, str, str], ...] = (
    ("components.damper_damping_rate_Nms_per_rad", "BD_T", "N*m*s/rad"),
    ("components.gearbox_damping_rate_Nms_per_rad", "BG", "N*m*s/rad"),
    ("components.damper_friction_Nm", "FD", "N*m"),
    ("components.lubrication_friction_Nm", "FL_T", "N*m"),
    ("components.gearbox_friction_Nm", "FG", "N*m"),
    ("damping_rate_Nms_per_rad", "BECD", "N*m*s/rad"),
    ("friction_Nm", "FECD", "N*m"),
    ("system_friction_Nm", "FS", "N*m"),
)

METHOD_COLUMNS: tuple[tuple[str, str, str], ...] = (
    ("deployment_time_s", "deployment time", "s"),
    ("start_speed_rad_s", "start speed", "rad/s"),
    ("end_speed_rad_s", "end speed", "rad/s"),
    ("max_speed_rad_s", "max speed", "rad/s"),
)


def predict_config(config: Config) -> Prediction:
    """Predict a loaded configuration exactly as ``ecdsim deploy`` does.

    Raises :class:`~ecdsim.deployment.ModelDomainError` where the model has no meaning.
    With ``[load.gravity]`` the flight (0 g) twin comes too (:func:`with_flight`), for the
    side-by-side table.
    """
    dynamics = config.spec.dynamics()
    return with_flight(
        predict(config.system, config.temperatures, config.methods, dynamics=dynamics), dynamics
    )


def lookup(case: dict[str, Any], key: str) -> Any:
    """The value at a dotted key path of a case dictionary (``"exact.deployment_time_s"``)."""
    value: Any = case
    for part in key.split("."):
        value = value[part]
    return value


def fmt(value: float | None, digits: int = 6) -> str:
    """A number for a table cell: ``digits`` significant digits, "-" for None."""
    return format_number(value, digits)


def input_rows(
    spec: BaseModel, prefix: str = "", shown: Shown | None = None
) -> Iterator[tuple[str, str, str]]:
    """(key, value, unit) for every field of the validated config, in ``shown``'s units.

    Units come from each field's :class:`~ecdsim.config.units.Kind` (SI by default);
    sections without a scalar quantity (tables, lists) are shown as they were validated,
    in SI.
    """
    for name, info in type(spec).model_fields.items():
        value = getattr(spec, name)
        key = f"{prefix}{name}"
        if value is None:
            continue
        if isinstance(value, BaseModel):
            yield from input_rows(value, f"{key}.", shown)
            continue
        kinds = [m for m in info.metadata if isinstance(m, Kind)]
        unit = (kinds[0].unit or "-") if kinds else _units_of(info.annotation)
        kind = KIND_BY_SI_UNIT.get(unit)
        if isinstance(value, float | int) and not isinstance(value, bool):
            if shown is not None and kind is not None:
                yield key, shown.num(float(value), kind), shown.unit(kind)
                continue
            # An integer field (a seed, a count) exactly: 6 digits made seed 20240611 2.02406e+07.
            yield key, str(value) if isinstance(value, int) else fmt(value), unit
        elif shown is not None and isinstance(value, list | tuple):
            yield _shown_list(key, value, info.annotation, shown)
        else:
            yield key, _plain(value), _units_of(info.annotation)


def _shown_list(key: str, value: Any, annotation: Any, shown: Shown) -> tuple[str, str, str]:
    """A list field (temperatures, friction or spring table rows) in ``shown``'s units."""
    units = _units_of(annotation).strip("()").split(", ")
    kinds = [KIND_BY_SI_UNIT.get(unit) for unit in units]

    def one(item: Any, kind: str | None) -> str:
        if isinstance(item, float | int) and not isinstance(item, bool) and kind is not None:
            return shown.num(float(item), kind)
        return _plain(item)

    if len(kinds) == 1 and not any(isinstance(item, list | tuple) for item in value):
        text = "[" + ", ".join(one(item, kinds[0]) for item in value) + "]"
        return key, text, shown.unit(kinds[0]) if kinds[0] else units[0]
    if len(value) == len(kinds) and not any(isinstance(item, list | tuple) for item in value):
        # A fixed pair such as a temperature range: each item in its own unit.
        text = "[" + ", ".join(one(x, k) for x, k in zip(value, kinds, strict=True)) + "]"
        labels = [shown.unit(k) if k else u for k, u in zip(kinds, units, strict=True)]
        return key, text, "(" + ", ".join(labels) + ")"
    if not all(isinstance(row, list | tuple) and len(row) == len(kinds) for row in value):
        return key, _plain(value), _units_of(annotation)  # another shape: as validated, SI
    rows = [
        "[" + ", ".join(one(x, k) for x, k in zip(row, kinds, strict=False)) + "]" for row in value
    ]
    labels = [shown.unit(k) if k else u for k, u in zip(kinds, units, strict=True)]
    return key, "[" + ", ".join(rows) + "]", "(" + ", ".join(labels) + ")"


def _plain(value: Any) -> str:
    if isinstance(value, list | tuple):
        return "[" + ", ".join(_plain(v) for v in value) + "]"
    if isinstance(value, float):
        return fmt(value)
    return str(value)


def _units_of(annotation: Any) -> str:
    """Units of the items of a list or tuple field, e.g. "(degC, N*m)"; "-" if none."""
    found: list[str] = []

    def walk(node: Any) -> None:
        for meta in getattr(node, "__metadata__", ()):
            if isinstance(meta, Kind):
                found.append(meta.unit or "-")
                return
        for arg in getattr(node, "__args__", ()):
            walk(arg)

    walk(annotation)
    if not found:
        return "-"
    return found[0] if len(found) == 1 else "(" + ", ".join(found) + ")"


def figure_data_uri(fig: Figure) -> str:
    """A matplotlib figure as an inline ``data:image/png;base64,...`` URI."""
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=110)
    return "data:image/png;base64," + base64.b64encode(buffer.getvalue()).decode("ascii")


def _figures(prediction: Prediction, units: UnitSystem = "si") -> list[dict[str, str]]:
    from ecdsim.plotting import plot_deployment, plot_speed, plot_torque_speed

    made = [
        (
            "angle",
            "Deployed angle against time (paper Fig. 4-6)",
            plot_deployment(prediction, units=units),
        ),
        ("speed", "Input shaft speed against time", plot_speed(prediction, units=units)),
        (
            "torque_speed",
            "ECD torque against speed at each temperature (paper Fig. 8)",
            plot_torque_speed(prediction, units=units),
        ),
    ]
    # With [load.gravity] the curves are the ground test's (the flight twin is the table
    # above them): say so, since a figure is often read without the section it is in.
    scope = " (ground test, 1 g)" if prediction.flight is not None else ""
    return [
        {"id": key, "caption": caption + scope, "src": figure_data_uri(fig)}
        for key, caption, fig in made
    ]


def _deployment_rows(document: dict[str, Any], shown: Shown | None = None) -> list[dict[str, Any]]:
    """One row per (temperature, method): the method's numbers and its difference to exact."""
    u = shown or Shown(digits=6)
    methods: list[str] = document["methods"]
    reference = "exact" if "exact" in methods else methods[0]
    rows = []
    for i, case in enumerate(document["cases"]):
        ref_time = case[reference]["deployment_time_s"]
        for method in methods:
            result = case[method]
            time = result["deployment_time_s"]
            if method == reference or time is None or ref_time is None:
                diff = rel = None
            else:
                diff = time - ref_time
                rel = diff / ref_time
            cells = [
                {"key": f"{method}.{key}", "text": fmt(result[key]), "unit": unit}
                for key, _, unit in METHOD_COLUMNS
            ]
            rows.append(
                {
                    "case": i,
                    "temperature": u.num(case["temperature_C"], "temperature"),
                    "method": method,
                    "label": SOLVERS[method].label,
                    "cells": cells,
                    "difference": fmt(diff),
                    "relative": "-" if rel is None else f"{100.0 * rel:+.3f}",
                    "stall": _stall_cell(method, result),
                }
            )
    return rows


def _stall_cell(method: str, result: dict[str, Any]) -> str:
    """The stall cell as ``ecdsim deploy``'s table says it: "no", "cannot start" or
    "at X deg"; for the dynamic method also a stop for good after a rebound (stuck)."""
    if method == "dynamic" and result.get("stuck"):
        angle = result["stuck_angle_rad"]
    elif result["stalled"]:
        angle = result["stall_angle_rad"]
    else:
        return "no"
    return "cannot start" if angle == 0.0 else f"at {np.degrees(angle):.4g} deg"


# What each requirement check measures, in words, for the report's requirements table.
REQUIREMENT_QUANTITIES = {
    "min_deployment_time": "deployment time",
    "max_deployment_time": "deployment time",
    "max_end_speed": "end (latch) speed",
    "max_input_torque": "ECD input torque",
    "no_stall": "no stall: least spring torque - friction",
    "min_torque_margin": "torque margin",
}


def _limit_text(name: str, requirements: Any, shown: Shown) -> str:
    """The limit of check ``name`` as "<= 60 s", in ``shown``'s units."""
    r = requirements
    limits: dict[str, tuple[str, float | None, str]] = {
        "min_deployment_time": (">=", r.min_deployment_time, "time"),
        "max_deployment_time": ("<=", r.max_deployment_time, "time"),
        "max_end_speed": ("<=", r.max_end_speed, "angular_speed"),
        "max_input_torque": ("<=", r.max_input_torque, "torque"),
        "no_stall": (">", 0.0, "torque"),
        "min_torque_margin": (">=", r.min_torque_margin, ""),
    }
    if name not in limits:
        return "-"
    sign, value, kind = limits[name]
    return f"{sign} {shown.text(value, kind) if kind else fmt(value, 4)}"


def _value_text(value: float, unit: str, shown: Shown) -> str:
    kind = KIND_BY_SI_UNIT.get(unit)
    if kind is None:
        return fmt(value, 4)
    return shown.text(value, kind)


def margin_section(config: Config, shown: Shown | None = None) -> dict[str, Any] | None:
    """Torque margins and requirement checks (``[requirements]``), or None without it.

    The same :func:`ecdsim.sizing.search.evaluate` call as ``ecdsim size`` makes, for the
    configured damper and gearbox as a single candidate. Each check has one row per
    temperature: the value, the limit, pass or fail and the margin (its definition is
    :data:`ecdsim.sizing.report.MARGIN_DEFINITIONS`), values and limits in ``shown``'s
    units.
    """
    spec = config.spec.requirements
    if spec is None:
        return None
    from ecdsim.sizing.report import MARGIN_DEFINITIONS, percent
    from ecdsim.sizing.requirements import Requirements
    from ecdsim.sizing.search import evaluate, stack_ecd

    u = shown or Shown(digits=6)
    requirements = Requirements.from_spec(spec)
    ecd = stack_ecd([config.system.ecd.damper], [config.system.ecd.gearbox])
    evaluation = evaluate(ecd, config.system.load, requirements)
    temps = [float(t) for t in evaluation.temperatures]
    checks = []
    for check in evaluation.checks:
        values = [float(v) for v in np.ravel(check.values[0])]
        margins = [float(m) for m in np.ravel(check.margins[0])]
        held = (
            [bool(h) for h in np.ravel(check.cannot_start[0])]
            if check.cannot_start is not None
            else [False] * len(values)
        )
        limit = _limit_text(check.name, requirements, u)
        checks.append(
            {
                "name": check.name,
                "label": check.label,
                "quantity": REQUIREMENT_QUANTITIES.get(check.name, check.label),
                "unit": check.unit,
                "limit": limit,
                "definition": MARGIN_DEFINITIONS.get(check.name, "-"),
                "values": values,
                "margins": margins,
                "cells": [
                    {"value": fmt(v), "margin": fmt(m, 4), "ok": m >= 0.0}
                    for v, m in zip(values, margins, strict=True)
                ],
                "rows": [
                    {
                        "temperature": u.num(t, "temperature"),
                        "value": "cannot start" if h else _value_text(v, check.unit, u),
                        "limit": limit,
                        "ok": m >= 0.0,
                        "margin": percent(m),
                    }
                    for t, v, m, h in zip(temps, values, margins, held, strict=True)
                ],
                "passed": all(m >= 0.0 for m in margins),
            }
        )
    return {
        "temperatures_C": temps,
        "torque_margin": [float(v) for v in np.ravel(evaluation.torque_margin[0])],
        "torque_margin_angle_rad": [float(v) for v in np.ravel(evaluation.torque_margin_angle[0])],
        "factors_applied": requirements.margin.factors_applied,
        "requirements": requirements.describe(),
        "checks": checks,
        "passed": bool(evaluation.passed()[0]),
    }


def _tolerance_text(spec: dict[str, Any]) -> str:
    """One tolerance as an engineer writes it: "normal, 3 sigma = 10 %"."""
    widths = (("sigma", "sigma = "), ("three_sigma", "3 sigma = "), ("plus_minus", "+-"))
    parts = [f"{label}{spec[key]['text']}" for key, label in widths if spec.get(key) is not None]
    return ", ".join([str(spec.get("distribution", "?")), *parts])


# A report's study is a quick look (the P1/P99 of 4096 samples are good to a few %),
# not a replacement for a full `ecdsim montecarlo` run; the report says so.
REPORT_MC_SAMPLES = 4096
REPORT_MC_SEED = 0  # used when [tolerances] gives no seed, so that a report is repeatable
PERCENTILE_KEYS = ("P1", "P5", "P50", "P95", "P99")


def montecarlo_section(config: Config, samples: int = REPORT_MC_SAMPLES) -> dict[str, Any] | None:
    """A Monte Carlo summary for ``[tolerances]`` (exact method), or None without it.

    The study runs in process through the same functions as ``ecdsim montecarlo``
    (:func:`ecdsim.montecarlo.build_plan`, :func:`ecdsim.montecarlo.run`,
    :func:`ecdsim.montecarlo.stats.summarize`), into a temporary folder.
    """
    import tempfile

    if config.spec.tolerances is None:
        return None
    raw = config.spec.tolerances.model_dump(mode="json")
    quantities = raw.get("quantities") or {}
    section: dict[str, Any] = {
        "command": f"ecdsim montecarlo {config.source} --samples 100000",
        "quantities": [{"name": k, "spec": _tolerance_text(v)} for k, v in quantities.items()],
        "samples": samples,
        "rows": [],
        "error": None,
        "summary": None,
    }
    from ecdsim.montecarlo import InProcess, MissingDependency, RunError, build_plan, run
    from ecdsim.montecarlo.stats import summarize

    seed = None if config.spec.tolerances.seed is not None else REPORT_MC_SEED
    try:
        with tempfile.TemporaryDirectory(prefix="ecdsim-report-mc-") as folder:
            out = Path(folder) / "study"
            plan = build_plan(config, samples, "exact", seed=seed, out=out)
            run(plan, out, InProcess())
            summary = summarize(plan, out)
    except (MissingDependency, RunError, ConfigError) as exc:
        # ConfigError: tolerances that only fail against the configured values (a "10 %"
        # spread of a value of 0); the report of the deployment itself still stands.
        section["error"] = str(exc)
        return section
    section["summary"] = summary
    section["seed"] = summary.get("seed")
    for case in summary["cases"]:
        time = case["deployment_time_s"]
        inputs = sorted(case["sensitivity"]["inputs"], key=lambda item: -abs(item["src"] or 0.0))
        section["rows"].append(
            {
                "temperature_C": case["temperature_C"],
                "percentiles": [time["percentiles"][k]["value"] for k in PERCENTILE_KEYS],
                "mean": time["mean"],
                "std": time["std"],
                "stall_probability": case["stall"]["probability"],
                # src is None where it cannot be computed (every sample stalls): "-".
                "drivers": ", ".join(
                    f"{i['key']} ({'-' if i['src'] is None else format(i['src'], '+.2f')})"
                    for i in inputs[:3]
                ),
            }
        )
    return section


def findings_checked(config: Config) -> str:
    """What "no warning" means for this config: only the checks that were made.

    A stall is always checked; the damper's linear range only where the config gives
    ``max_linear_speed`` or ``max_linear_torque``; extrapolation only of a friction table.
    """
    damper = config.system.ecd.damper
    checked = ["stall"]
    limited = damper.max_linear_speed is not None or damper.max_linear_torque is not None
    if limited:
        checked.append("the damper's linear range")
    laws = (damper.lubrication_friction, config.system.load.system_friction)
    if any(isinstance(law, TabulatedTemperatureLaw) for law in laws):
        checked.append("friction-table extrapolation")
    text = "No warning: checked for " + (
        " and ".join(checked)
        if len(checked) < 3
        else f"{checked[0]}, {checked[1]} and {checked[2]}"
    )
    text += ", at every temperature and by every method."
    if not limited:
        text += (
            " The damper's linear range is not checked: the config gives no max_linear_speed "
            "or max_linear_torque ([damper], docs/config.md)."
        )
    return text


# Solver settings: shown in the appendix, not among the physical inputs.
SOLVER_KEYS = ("analysis.rtol", "analysis.integrator")


def solver_appendix(config: Config, prediction: Prediction, document: dict[str, Any]) -> Any:
    """Solver internals for the appendix: methods, settings, and the dynamic run's counts.

    For the dynamic method, per case: its end status, the relative energy-balance error,
    the number of closed-form and integrated segments and the integrator's accepted steps
    (:meth:`ecdsim.dynamics.result.TrajectoryData.segment_counts`); "-" without a
    recorded trajectory.
    """
    analysis = config.spec.analysis
    settings = [("methods", "; ".join(f"{m}: {_described(m)}" for m in document["methods"]))]
    if "dynamic" in document["methods"]:
        settings += [("integrator", analysis.integrator), ("rtol", f"{analysis.rtol:g}")]
    rows = []
    if "dynamic" in prediction.solutions:
        counts = _dynamic_counts(prediction.solutions["dynamic"], len(document["cases"]))
        for i, case in enumerate(document["cases"]):
            result = case.get("dynamic", {})
            error = result.get("energy_balance_error")
            rows.append(
                {
                    "temperature": case["temperature_C"],
                    "status": result.get("status", "-"),
                    "energy_balance_error": "-" if error is None else f"{error:.2g}",
                    **counts[i],
                }
            )
    return {"settings": settings, "dynamic": rows}


def _dynamic_counts(solution: Any, n: int) -> list[dict[str, str]]:
    """Per case: closed-form segments, integrated segments, integrator steps ("-": unknown)."""
    trajectory = getattr(getattr(solution, "result", None), "trajectory", None)
    if trajectory is None:
        return [{"closed": "-", "integrated": "-", "steps": "-"}] * n
    closed, integrated, steps = trajectory.segment_counts()
    return [
        {"closed": str(closed[i]), "integrated": str(integrated[i]), "steps": str(steps[i])}
        for i in range(n)
    ]


def _described(method: str) -> str:
    """A method in words ("the exact solution of the same quasi-static equations")."""
    return describe_method(method, SOLVERS[method].label)


def _dynamic_section(prediction: Prediction, document: dict[str, Any], u: Shown) -> Any:
    """The dynamic method's results as ``ecdsim deploy`` prints them (latch speed and
    kinetic energy, impacts, sticking, engagement, the damper's peak temperature) and its
    figures (events marked; the damper's temperature rise when it heats); None without
    the dynamic method."""
    if "dynamic" not in document["methods"]:
        return None
    from ecdsim.plotting_dynamic import (
        dynamic_result,
        dynamic_tables,
        heated,
        plot_damper_temperature,
        plot_dynamic,
    )

    result = dynamic_result(prediction)
    tables = dynamic_tables(document["cases"], Shown(u.system))
    figures = []
    if result is not None:
        made = [
            ("dynamic_angle", "Dynamic method: angle against time, events marked", "angle"),
            ("dynamic_speed", "Dynamic method: load speed against time, events marked", "speed"),
        ]
        for key, caption, quantity in made:
            fig = plot_dynamic(prediction, quantity, u.system, result=result)  # type: ignore[arg-type]
            figures.append({"id": key, "caption": caption, "src": figure_data_uri(fig)})
        if heated(result):
            fig = plot_damper_temperature(prediction, u.system, result=result)
            caption = "Dynamic method: the damper's temperature rise above ambient (self-heating)"
            figures.append(
                {"id": "dynamic_heating", "caption": caption, "src": figure_data_uri(fig)}
            )
    one_line = [
        [header.replace("\n", " ") for header in h]
        for h in (tables.end_headers, tables.damper_headers)
    ]
    return {
        "end_title": tables.end_title,
        "end_headers": one_line[0],
        "end_rows": tables.end_rows,
        "damper_title": tables.damper_title,
        "damper_headers": one_line[1],
        "damper_rows": tables.damper_rows,
        "notes": "; ".join(tables.notes),
        "figures": figures,
    }


def _kind(key: str) -> str:
    return kind_of_key(key.rsplit(".", 1)[-1]) or "number"


def provenance_of(source: str, sha256: str) -> dict[str, str]:
    """What a report says it was made from: ecdsim's version, the file, its hash, when."""
    return {
        "ecdsim_version": __version__,
        "config_source": source,
        "config_sha256": sha256,
        "date": dt.datetime.now(dt.UTC).strftime("%Y-%m-%d %H:%M:%S UTC"),
    }


def build_context(
    config: Config, prediction: Prediction, config_text: str, units: UnitSystem = "si"
) -> dict[str, Any]:
    """Everything the template shows, from the prediction and the config, in ``units``."""
    u = Shown(units, digits=6)
    document = prediction.to_dict()
    document["display_units"] = units
    provenance = provenance_of(config.source, config.sha256)
    margins = margin_section(config, u)
    montecarlo = montecarlo_section(config)
    # The qualification block (its own module and template, docs/qualification.md).
    from ecdsim.report.qualification import qualification_section

    qualification = qualification_section(config, montecarlo, u)
    data = {
        "prediction": document,
        "provenance": provenance,
        "margins": margins,
        "montecarlo": montecarlo["summary"] if montecarlo else None,
    }
    components = [
        {
            "case": i,
            "temperature": u.num(case["temperature_C"], "temperature"),
            "cells": [
                {"key": key, "text": u.num(lookup(case, key), _kind(key))}
                for key, _, _ in COMPONENT_COLUMNS
            ],
        }
        for i, case in enumerate(document["cases"])
    ]
    return {
        "title": config.system.name,
        "provenance": provenance,
        "inputs": [row for row in input_rows(config.spec, shown=u) if row[0] not in SOLVER_KEYS],
        "no_findings": findings_checked(config),
        "appendix": solver_appendix(config, prediction, document),
        "config_text": config_text,
        "component_columns": [
            (key, symbol, u.unit(_kind(key))) for key, symbol, _ in COMPONENT_COLUMNS
        ],
        "components": components,
        "method_columns": METHOD_COLUMNS,
        "deployment": _deployment_rows(document, u),
        "ground_test": _ground_test(document, u),
        "dynamic": _dynamic_section(prediction, document, u),
        "methods": [(m, _described(m)) for m in document["methods"]],
        "units_name": "SI" if units == "si" else "US customary",
        "placeholder": is_placeholder(config),
        "figures": _figures(prediction, units),
        "u": u,
        "t_unit": u.unit("temperature"),
        # The messages are SI sentences from the library; shown in the report's units.
        "warnings": [
            {**w, "message": convert_text(w["message"], units)} for w in document["warnings"]
        ],
        "margins": margins,
        "montecarlo": montecarlo,
        "qualification": qualification,
        "percentile_keys": PERCENTILE_KEYS,
        "data_id": DATA_ELEMENT_ID,
        # "</" must not appear inside <script>; JSON allows "<\/".
        "data_json": json.dumps(data, sort_keys=True, allow_nan=False).replace("</", "<\\/"),
    }


def _ground_test(document: dict[str, Any], u: Shown) -> dict[str, Any] | None:
    """Flight (0 g) against the ground test, per temperature and method; None without
    ``[load.gravity]`` (docs/model.md, gravity in ground tests)."""
    ground = document.get("ground_test")
    if ground is None:
        return None
    rows = []
    for case in ground["cases"]:
        for method in document["methods"]:
            block = case[method]
            rel = block["relative"]
            rows.append(
                {
                    "temperature": u.num(case["temperature_C"], "temperature"),
                    "method": method,
                    "flight": fmt(block["flight_deployment_time_s"])
                    if block["flight_deployment_time_s"] is not None
                    else "stalls",
                    "test": fmt(block["test_deployment_time_s"])
                    if block["test_deployment_time_s"] is not None
                    else "stalls",
                    "difference": fmt(block["test_minus_flight_s"]),
                    "relative": "-" if rel is None else f"{100.0 * rel:+.2f}",
                }
            )
    return {
        "offload": f"{100.0 * ground['offload']:.3g}",
        "mass": u.text(ground["mass_kg"], "mass"),
        "radius": u.text(ground["cg_radius_m"], "length"),
        "release_deg": f"{np.degrees(ground['release_angle_rad']):.4g}",
        "at_release": u.text(ground["torque_at_release_Nm"], "torque"),
        "at_latch": u.text(ground["torque_at_latch_Nm"], "torque"),
        "rows": rows,
    }


def template_environment() -> jinja2.Environment:
    """The reports' jinja2 environment (templates in ecdsim/report/templates, escaped,
    an undefined name an error): the single hinge's report and the wing's."""
    import jinja2

    return jinja2.Environment(
        loader=jinja2.PackageLoader("ecdsim.report", "templates"),
        autoescape=True,
        undefined=jinja2.StrictUndefined,
        trim_blocks=True,
        lstrip_blocks=True,
    )


def render_html(
    config: Config, prediction: Prediction, config_text: str, units: UnitSystem = "si"
) -> str:
    """The report as one self-contained HTML document (figures inline, no network)."""
    env = template_environment()
    env.globals["fmt"] = fmt
    template = env.get_template("report.html.j2")
    return template.render(**build_context(config, prediction, config_text, units))


def write_report(
    config: Config,
    prediction: Prediction,
    config_text: str,
    path: Path,
    units: UnitSystem = "si",
) -> Path:
    """Render the report in ``units`` and write it atomically to ``path``."""
    return write_text(path, render_html(config, prediction, config_text, units))
