"""The report's qualification section: the config's torque budget and, with a Monte
Carlo study, the probability of missing each requirement (docs/qualification.md).

Its own module and template block (``templates/qualification.html.j2``): the numbers
come from :func:`ecdsim.sizing.budget.budget_from_config` (as ``ecdsim margin CONFIG``)
and from the study's summary (as ``ecdsim montecarlo``); nothing is computed here.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from ecdsim.formatting import format_number

if TYPE_CHECKING:
    from ecdsim.config import Config
    from ecdsim.units_display import Shown


def _budget(config: Config, shown: Shown) -> dict[str, Any] | None:
    """The ``[budget]`` of the config as ``ecdsim margin`` computes it, or None."""
    if getattr(config.spec, "budget", None) is None:
        return None
    from ecdsim.deployment import ModelDomainError
    from ecdsim.sizing.budget import BudgetError, budget_from_config

    temps = list(config.temperatures)
    try:
        budget = budget_from_config(config, temps)
    except (BudgetError, ModelDomainError) as exc:
        return {"error": str(exc), "phases": []}

    def cells(values: Any) -> list[str]:
        flat = np.broadcast_to(np.atleast_1d(values), (len(temps),))
        return [shown.num(float(v), "torque") for v in flat]

    phases = []
    for phase in budget.phases:
        margins = np.atleast_1d(phase.margin)
        ratios = np.atleast_1d(phase.torque_ratio)
        phases.append(
            {
                "name": phase.phase,
                "terms": [
                    {
                        "name": t.name,
                        "kind": t.kind,
                        "factor": f"{phase.factor(t):g}",
                        "cells": cells(t.value),
                    }
                    for t in phase.terms
                ],
                "total": cells(phase.total),
                "factored": cells(phase.factored),
                "available": cells(phase.available),
                "margins": [{"text": f"{m:+.4g}", "ok": bool(m >= 0.0)} for m in margins],
                "ratios": [format_number(float(r), 4) for r in ratios],
                "verdicts": phase.verdicts(),
            }
        )
    return {
        "error": None,
        "temperatures": [shown.num(t, "temperature") for t in temps],
        "torque_unit": shown.unit("torque"),
        "phases": phases,
        "factors_applied": budget.factors_applied,
        "notes": list(budget.notes),
    }


def _misses(montecarlo: dict[str, Any] | None, shown: Shown) -> dict[str, Any] | None:
    """The study's probability of missing each requirement, or None."""
    summary = None if montecarlo is None else montecarlo.get("summary")
    if not summary or not all("requirements" in case for case in summary["cases"]):
        return None
    cases = summary["cases"]
    names = list(cases[0]["requirements"])
    return {
        "samples": summary["samples"],
        "temperatures": [shown.num(case["temperature_C"], "temperature") for case in cases],
        "rows": [
            {
                "name": name,
                "label": cases[0]["requirements"][name]["label"],
                "cells": [
                    f"{100 * case['requirements'][name]['probability']:.3g} "
                    f"({100 * case['requirements'][name]['upper95']:.2g})"
                    for case in cases
                ],
            }
            for name in names
        ],
    }


def qualification_section(
    config: Config, montecarlo: dict[str, Any] | None, shown: Shown
) -> dict[str, Any] | None:
    """The section's data, or None when the config has neither a budget nor a Monte
    Carlo study with requirements."""
    budget = _budget(config, shown)
    misses = _misses(montecarlo, shown)
    if budget is None and misses is None:
        return None
    return {"budget": budget, "misses": misses}
