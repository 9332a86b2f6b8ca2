"""Explorer latency: one ``POST /api/deploy`` request against the same prediction called directly.

Cases (``cases(quick)``, run by ``benchmarks/run.py``; needs the app extra, fastapi):
for the paper example with the exact method, with the paper and exact methods, and the
dynamic example with paper, exact and dynamic methods, the whole in-process request
through FastAPI's test client (JSON body, validation, TOML round trip, prediction, the
curves and the JSON answer) is timed against the baseline: the same config parsed and
predicted by calling the library directly (``parse_config`` -> ``predict_config`` ->
``to_dict``, what ``ecdsim deploy --json`` computes), so the ratio is the share of the
request that is the prediction itself. Agreement: the largest relative difference
between the numbers of the two prediction documents. Goal (issue 7): a request under
100 ms median per slider change.
"""

from __future__ import annotations

import tomllib
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

import harness
from harness import ROOT, Case, max_relative_difference

GOAL_S = 0.1


def numbers(document: Any) -> Iterator[float]:
    """Every number in a JSON-like document, in a fixed order (None as NaN)."""
    if isinstance(document, dict):
        for key in sorted(document):
            if key != "display_units":
                yield from numbers(document[key])
    elif isinstance(document, list):
        for item in document:
            yield from numbers(item)
    elif isinstance(document, bool | str):
        return
    elif document is None:
        yield float("nan")
    elif isinstance(document, int | float):
        yield float(document)


def documents_agree(a: dict[str, Any], b: dict[str, Any]) -> float:
    """Max relative difference of the numbers of two prediction documents."""
    x, y = list(numbers(a)), list(numbers(b))
    return max_relative_difference(x, y) if len(x) == len(y) else float("inf")


def case(name: str, config_path: Path, methods: list[str]) -> Case[dict[str, Any]]:
    """One request case: the HTTP request against the direct call, same config."""
    from fastapi.testclient import TestClient

    from ecdsim.config import parse_config
    from ecdsim.report.builder import predict_config
    from ecdsim.webapp.server import create_app
    from ecdsim.webapp.tomlwriter import to_toml

    client = TestClient(create_app())
    config: dict[str, Any] = tomllib.loads(config_path.read_text(encoding="utf-8"))
    config.setdefault("analysis", {})["methods"] = methods

    def request() -> dict[str, Any]:
        response = client.post("/api/deploy", json={"config": config})
        response.raise_for_status()
        document: dict[str, Any] = response.json()["prediction"]
        return document

    def direct() -> dict[str, Any]:
        document: dict[str, Any] = predict_config(parse_config(to_toml(config), "c")).to_dict()
        return document

    return Case(
        name=name,
        ecdsim=request,
        baseline=direct,
        baseline_name="the same config parsed and predicted by a direct library call "
        "(what ecdsim deploy --json computes), no HTTP, no curves",
        agree=documents_agree,
        tolerance=0.0,
        repeats=15,
        goal_s=GOAL_S,
        description=f"POST /api/deploy, {config_path.name}, methods {'+'.join(methods)}",
    )


def cases(quick: bool) -> list[Case[Any]]:
    """The explorer cases (``quick`` keeps only the first)."""
    examples = ROOT / "examples"
    out = [case("explorer deploy exact", examples / "paper_cc16.toml", ["exact"])]
    if not quick:
        out += [
            case("explorer paper+exact", examples / "paper_cc16.toml", ["paper", "exact"]),
            case(
                "explorer +dynamic",
                examples / "paper_cc16_dynamic.toml",
                ["paper", "exact", "dynamic"],
            ),
        ]
    return out


def main(argv: Sequence[str] | None = None) -> int:
    """Run this file's cases alone and print their table (exit 1 if an agreement fails)."""
    return harness.run_alone(cases, __doc__, argv, quick_help="smaller sizes")


if __name__ == "__main__":
    raise SystemExit(main())
