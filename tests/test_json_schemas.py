"""Every --json document against its JSON Schema (issue 27 item 4).

The schemas ship with the package (src/ecdsim/schemas/, ``ecdsim.jsonrows.schema``) and
are published in docs/json.md. Each document of tests/json_documents.py (every command,
on the examples and on variants that reach the optional parts) is validated against its
schema with unknown keys refused, so that a key added to a document without its schema
(or renamed without the rename table of docs/json.md) fails here.
"""

from __future__ import annotations

import copy
import json
from pathlib import Path
from typing import Any

import jsonschema  # type: ignore[import-untyped]
import pytest

from ecdsim.jsonrows import SCHEMA_DIR, SCHEMAS, schema
from tests.json_documents import CASES, ROOT, Case, document


def _strict(node: Any) -> Any:
    """The schema with ``additionalProperties: false`` on every object that lists its
    properties: the shipped schemas let consumers ignore unknown keys, the tests do not."""
    if isinstance(node, dict):
        out = {k: _strict(v) for k, v in node.items()}
        if "properties" in out:
            out["additionalProperties"] = False
        return out
    if isinstance(node, list):
        return [_strict(v) for v in node]
    return node


def test_every_schema_is_a_valid_draft_2020_12_schema() -> None:
    assert sorted(p.name for p in SCHEMA_DIR.glob("*.json")) == sorted(
        f"{name}.schema.json" for name in SCHEMAS
    )
    for name in SCHEMAS:
        found = schema(name)
        jsonschema.Draft202012Validator.check_schema(found)
        assert found["$id"] == f"urn:ecdsim:schema:{name}"
    # Every kind of document has a case, and docs/json.md lists every schema file.
    assert {case.schema for case in CASES} == set(SCHEMAS)
    docs = (ROOT / "docs" / "json.md").read_text(encoding="utf-8")
    for name in SCHEMAS:
        assert f"src/ecdsim/schemas/{name}.schema.json" in docs
    with pytest.raises(ValueError, match=r"'deploi' is not a JSON document of ecdsim; expected"):
        schema("deploi")


@pytest.mark.parametrize("case", CASES, ids=[case.name for case in CASES])
def test_document_matches_its_schema(case: Case, tmp_path: Path) -> None:
    found = document(case, tmp_path)
    validator = jsonschema.Draft202012Validator(_strict(schema(case.schema)))
    errors = sorted(validator.iter_errors(found), key=lambda e: list(e.absolute_path))
    assert not errors, "\n".join(
        f"{'/'.join(map(str, e.absolute_path))}: {e.message}" for e in errors[:10]
    )
    if case.schema == "montecarlo":
        # summary.json is the same document without display_units.
        out = Path(case.argv(tmp_path)[case.argv(tmp_path).index("--out") + 1])
        summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
        assert summary == {k: v for k, v in found.items() if k != "display_units"}
        validator.validate(summary)


def test_a_document_that_breaks_the_schema_is_caught(tmp_path: Path) -> None:
    found = document(CASES[0], tmp_path)
    validator = jsonschema.Draft202012Validator(_strict(schema("deploy")))
    renamed = copy.deepcopy(found)
    case = renamed["cases"][0]
    case["friction_N_m"] = case.pop("friction_Nm")  # a renamed key: missing and unknown
    messages = [e.message for e in validator.iter_errors(renamed)]
    assert any("'friction_Nm' is a required property" in m for m in messages)
    assert any("'friction_N_m' was unexpected" in m for m in messages)
    wrong = copy.deepcopy(found)
    wrong["cases"][0]["exact"]["stalled"] = "no"
    assert not validator.is_valid(wrong)
