"""Explorer latency: server-side time per /api/deploy request, as a slider moves.

Run: ``python benchmarks/bench_webapp.py``. The goal (issue 7) is under 100 ms per change
for the exact method; the figure printed is the median and the maximum over the changes of
the server's own ``compute_ms`` and of the whole in-process request (validation, TOML
round trip, prediction, curves, JSON). Not part of ``make bench`` (needs the app extra).
"""

from __future__ import annotations

import statistics
import time
import tomllib
from pathlib import Path
from typing import Any

from fastapi.testclient import TestClient

from ecdsim.webapp.server import create_app

ROOT = Path(__file__).resolve().parent.parent
GOAL_MS = 100.0


def measure(config_path: Path, methods: list[str], changes: int = 60) -> dict[str, float]:
    client = TestClient(create_app())
    config: dict[str, Any] = tomllib.loads(config_path.read_text(encoding="utf-8"))
    config.setdefault("analysis", {})["methods"] = methods
    client.post("/api/deploy", json={"config": config})  # warm-up: pint's unit registry
    compute, total = [], []
    for k in range(changes):
        config["gearbox"]["ratio"] = 200 + 5 * k  # a slider sweep
        began = time.perf_counter()
        response = client.post("/api/deploy", json={"config": config})
        total.append(1000.0 * (time.perf_counter() - began))
        response.raise_for_status()
        compute.append(float(response.json()["compute_ms"]))
    return {
        "compute_median_ms": statistics.median(compute),
        "compute_max_ms": max(compute),
        "request_median_ms": statistics.median(total),
        "request_max_ms": max(total),
    }


def main() -> None:
    cases = [
        ("exact", ROOT / "examples" / "paper_cc16.toml", ["exact"]),
        ("paper+exact", ROOT / "examples" / "paper_cc16.toml", ["paper", "exact"]),
        ("paper+exact+dynamic", ROOT / "examples" / "paper_cc16_dynamic.toml",
         ["paper", "exact", "dynamic"]),
    ]  # fmt: skip
    for name, path, methods in cases:
        r = measure(path, methods)
        verdict = "MET" if r["request_max_ms"] < GOAL_MS else "NOT MET"
        print(
            f"{name:22s} compute median {r['compute_median_ms']:6.1f} ms max "
            f"{r['compute_max_ms']:6.1f} ms | request median {r['request_median_ms']:6.1f} ms "
            f"max {r['request_max_ms']:6.1f} ms | goal < {GOAL_MS:g} ms: {verdict}"
        )


if __name__ == "__main__":
    main()
