"""Draft the JSON Schemas of the ``--json`` documents (src/ecdsim/schemas/).

    .venv/bin/python scripts/json_schemas.py

runs every command of tests/json_documents.py (the examples and the variants that reach
each optional part), and writes one schema per document kind: every key seen, its JSON
type(s) (``null`` where it was null in some document, and for every number: a number
that does not exist is null, docs/json.md), ``required`` for the keys present
in every document, its SI unit (from the key's suffix, ecdsim.tidy) in the description,
and the closed vocabularies below as enums. Rerun it after a change to a document, look at
the diff, and commit it: tests/test_json_schemas.py checks every document against the
committed schemas, with unknown keys refused, so that a key added to the output without
its schema fails there.
"""

from __future__ import annotations

import json
import sys
import tempfile
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from ecdsim.dynamics.result import STATUSES  # noqa: E402
from ecdsim.jsonrows import SCHEMA_DIR, SCHEMAS  # noqa: E402
from ecdsim.tidy import unit_of  # noqa: E402
from ecdsim.wing.result import EVENT_KINDS  # noqa: E402
from tests.json_documents import CASES, document  # noqa: E402

# Keys whose values are a closed vocabulary, by key name.
ENUMS: dict[str, list[str]] = {
    "display_units": ["si", "us"],
    "method": ["paper", "exact", "dynamic"],
    "noise_model": ["torque", "timing"],
    "sampling": ["random", "lhs", "sobol"],
    "status": list(STATUSES),  # a wing's statuses are a subset (ecdsim.wing.result)
    "event": list(EVENT_KINDS),  # a wing's events; the single hinge's are under "kind"
    # fit drop-test's noise check names the two noise models.
    "alternative": ["torque", "timing"],
    "fitted_model": ["torque", "timing"],
}
# A kind's vocabularies where they differ from ENUMS: a wing file's documents name the
# wing's solver as their method ("wing"), and a sweep may be a wing's.
KIND_ENUMS: dict[str, dict[str, list[str]]] = {
    "sweep": {"method": [*ENUMS["method"], "wing"]},
    "compare_fluid": {"method": ["dynamic", "quasi-static"]},
    "wing_montecarlo": {"method": ["wing"]},
}
# Top-level keys that may be null though no document of tests/json_documents.py shows it:
# fit drop-test's noise_check where no check can be made (ecdsim.characterize.droptest).
NULLABLE: dict[str, list[str]] = {"fit_drop_test": ["noise_check"]}
# Objects keyed by the user's hinge names, by document kind: each is a map (any name, every
# value of one schema), not an object with fixed properties.
MAPS: dict[str, frozenset[str]] = {
    "wing_deploy": frozenset(
        {
            "final_angle_rad",
            "max_speed_rad_s",
            "peak_damper_temperature_C",
            "spring_work",
            "damper_dissipation",
            "friction_dissipation",
            "latch_dissipation",
            "impact_loss",
            "gear_loss",
            "engagement_loss",
        }
    ),
}
# Top-level keys a document of the kind may lack: summary.json is montecarlo --json without
# display_units.
OPTIONAL = {"montecarlo": ["display_units"]}
TITLES = {
    "deploy": "ecdsim deploy --json",
    "fit_drop_test": "ecdsim fit drop-test --json",
    "fit_trace": "ecdsim fit trace --json",
    "size": "ecdsim size --json",
    "compare_fluid": "ecdsim compare-fluid --json",
    "montecarlo": "ecdsim montecarlo --json (and OUT/summary.json)",
    "repeat": "ecdsim repeat --json",
    "sweep": "ecdsim sweep --json",
    "margin": "ecdsim margin --json",
    "reliability_demonstrated": "ecdsim reliability demonstrated --json",
    "reliability_runs_needed": "ecdsim reliability runs-needed --json",
    "reliability_weibull": "ecdsim reliability weibull --json",
    "fit_drive_test": "ecdsim fit drive-test --json",
    "fit_fluid_damper": "ecdsim fit fluid-damper --json",
    "wing_deploy": "ecdsim deploy WING.toml --json",
    "wing_montecarlo": "ecdsim montecarlo WING.toml --json (and OUT/summary.json)",
}


def _type(value: Any) -> str:
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "boolean"
    if isinstance(value, int):
        return "integer"
    if isinstance(value, float):
        return "number"
    if isinstance(value, str):
        return "string"
    if isinstance(value, list):
        return "array"
    return "object"


def infer(
    values: list[Any],
    key: str = "",
    maps: frozenset[str] = frozenset(),
    enums: dict[str, list[str]] = ENUMS,
) -> dict[str, Any]:
    """The schema of every value seen at one place of the documents; ``maps`` names the
    keys whose objects are keyed by hinge name (:data:`MAPS`), ``enums`` the vocabularies
    (:data:`ENUMS` with the kind's :data:`KIND_ENUMS`)."""
    types = {_type(v) for v in values}
    if {"integer", "number"} <= types:
        types.discard("integer")
    if "number" in types:
        # docs/json.md: a number that does not exist (a stalled case's time, an interval
        # too few samples give) is null, wherever it is; not every document shows one.
        types.add("null")
    schema: dict[str, Any] = {}
    unit = unit_of(key) if key else None
    if unit is not None:
        schema["description"] = f"unit: {unit}"
    objects = [v for v in values if isinstance(v, dict)]
    arrays = [v for v in values if isinstance(v, list)]
    if objects and key in maps:
        entries = [v for o in objects for v in o.values()]
        schema["description"] = "; ".join(
            [*filter(None, [schema.get("description")]), "keyed by hinge name"]
        )
        schema["additionalProperties"] = infer(entries, key) if entries else {"type": "number"}
        schema["additionalProperties"].pop("description", None)
    elif objects:
        keys = sorted({k for o in objects for k in o})
        schema["properties"] = {
            k: infer([o[k] for o in objects if k in o], k, maps, enums) for k in keys
        }
        required = [k for k in keys if all(k in o for o in objects)]
        if required:
            schema["required"] = required
    if arrays:
        items = [item for a in arrays for item in a]
        if items:
            schema["items"] = infer(items, key, maps, enums)
            schema["items"].pop("description", None)
    if key in enums and types <= {"string", "null"}:
        schema["enum"] = [*enums[key], *([None] if "null" in types else [])]
    ordered = sorted(types)
    schema["type"] = ordered[0] if len(ordered) == 1 else ordered
    return schema


def main() -> None:
    """Run the documents' commands and write one schema per kind."""
    documents: dict[str, list[Any]] = {}
    with tempfile.TemporaryDirectory() as folder:
        for i, case in enumerate(CASES):
            documents.setdefault(case.schema, []).append(document(case, Path(folder) / str(i)))
    SCHEMA_DIR.mkdir(exist_ok=True)
    for name in SCHEMAS:
        schema = {
            "$schema": "https://json-schema.org/draft/2020-12/schema",
            "$id": f"urn:ecdsim:schema:{name}",
            "title": TITLES[name],
            "description": (
                "Drafted by scripts/json_schemas.py from the documents of "
                "tests/json_documents.py; docs/json.md describes the keys. Numbers are SI "
                "(temperatures degC), the unit in the key's suffix; consumers ignore keys "
                "they do not know."
            ),
            **infer(
                documents[name],
                maps=MAPS.get(name, frozenset()),
                enums={**ENUMS, **KIND_ENUMS.get(name, {})},
            ),
        }
        schema["required"] = [k for k in schema["required"] if k not in OPTIONAL.get(name, [])]
        for key in NULLABLE.get(name, []):
            found = schema["properties"][key]
            kinds = found["type"] if isinstance(found["type"], list) else [found["type"]]
            found["type"] = sorted({*kinds, "null"})
        path = SCHEMA_DIR / f"{name}.schema.json"
        path.write_text(json.dumps(schema, indent=1, sort_keys=True) + "\n", encoding="utf-8")
        print(f"wrote {path.relative_to(ROOT)} ({len(documents[name])} documents)")


if __name__ == "__main__":
    main()
