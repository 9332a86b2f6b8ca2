"""A method plugs in through the registry and the protocol's hooks alone.

A probe method, unknown to every caller, is added to ``ecdsim.methods.SOLVERS``: its
extra JSON fields, its findings, its kept trajectory and its need for the dynamic
parameters reach the JSON, the warnings, ``Prediction.trajectory``, ``predict`` and the
config exactly as the dynamic method's do, so no caller needs to know a method by type
or by name.
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from typing import Any

import numpy as np
import pytest
from typer.testing import CliRunner

from ecdsim._types import ArrayLike
from ecdsim.cli.app import app
from ecdsim.config import ConfigError, parse_config
from ecdsim.deployment import ModelDomainError, predict
from ecdsim.methods import SOLVERS
from ecdsim.solvers import EXACT, DeploymentSolution, QuasiStaticProblem, Trajectory
from tests.conftest import PAPER_CONFIG, paper_system


@dataclass(frozen=True, kw_only=True)
class ProbeSolution(DeploymentSolution):
    """The exact method's answer, plus what only the probe knows."""

    kept: Trajectory

    def case_fields(self, index: int) -> dict[str, Any]:
        return {"probe_index": index}

    def findings(self) -> list[tuple[str, str, int]]:
        return [("probe_note", "the probe looked at this case", 1)]

    def trajectory(self, times: ArrayLike) -> Trajectory:
        return self.kept

    def time_series_csv(self) -> str:
        return "probe_time_s\n0\n"


@dataclass(frozen=True)
class ProbeMethod:
    name: str = "probe"
    label: str = "probe (test)"
    needs_dynamics: bool = False

    def solve(self, problem: QuasiStaticProblem) -> ProbeSolution:
        exact = EXACT.solve(problem)
        common = {f.name: getattr(exact, f.name) for f in fields(exact)}
        kept = Trajectory("probe", np.zeros(1), np.zeros((1, 2)), np.zeros((1, 2)))
        return ProbeSolution(**{**common, "method": self.name}, kept=kept)

    def trajectory(self, problem: QuasiStaticProblem, times: ArrayLike) -> Trajectory:
        raise AssertionError("the kept trajectory must be used")


@pytest.fixture
def probe(monkeypatch: pytest.MonkeyPatch) -> ProbeMethod:
    method = ProbeMethod()
    monkeypatch.setitem(SOLVERS, method.name, method)
    return method


def test_hooks_reach_json_warnings_and_trajectory(probe: ProbeMethod) -> None:
    prediction = predict(paper_system(), [25.0, 100.0], ("exact", "probe"))
    cases = prediction.to_dict()["cases"]
    assert [case["probe"]["probe_index"] for case in cases] == [0, 1]
    assert "probe_index" not in cases[0]["exact"]  # the base hook adds nothing
    assert cases[1]["probe"]["deployment_time_s"] == cases[1]["exact"]["deployment_time_s"]
    notes = [w for w in prediction.warnings if w.code == "probe_note"]
    assert [(w.method, w.temperature_C) for w in notes] == [("probe", 100.0)]
    assert prediction.trajectory("probe", [0.0, 1.0]).method == "probe"
    # The exact method keeps no trajectory: its solver computes one.
    assert prediction.trajectory("exact", [0.0, 1.0]).angle.shape == (2, 2)


def test_time_series_come_from_the_first_method_that_records_one(
    probe: ProbeMethod, tmp_path: Any
) -> None:
    path = tmp_path / "series.csv"
    args = ["deploy", str(PAPER_CONFIG), "-m", "exact", "-m", "probe", "--timeseries", str(path)]
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 0, result.output
    assert path.read_text() == "probe_time_s\n0\n"
    plain = CliRunner().invoke(app, [*args[:2], "-m", "exact", "--timeseries", str(path)])
    assert plain.exit_code == 2
    assert "--timeseries needs the dynamic method" in plain.stderr


def test_a_method_needing_dynamics_is_refused_without_them(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setitem(SOLVERS, "probe", ProbeMethod(needs_dynamics=True))
    with pytest.raises(ModelDomainError, match="missing; the probe method needs the load's"):
        predict(paper_system(), [25.0], ("exact", "probe"))
    text = PAPER_CONFIG.read_text(encoding="utf-8")
    text = text.replace("[analysis]\n", '[analysis]\nmethods = ["probe"]\n', 1)
    with pytest.raises(ConfigError, match=r"the probe method needs \[load\] inertia"):
        parse_config(text)


# The computing layers: what a method needs reaches them through the protocol's hooks.
# Presentation (the CLI's tables, the plots, the report, the notebook API's figures) may
# name the dynamic method for its own tables; docs/architecture.md lists where.
HOOKS_ONLY = [
    "ecdsim/deployment.py",
    "ecdsim/sweeps.py",
    "ecdsim/cli/app.py",
    "ecdsim/config",
    "ecdsim/montecarlo",
    "ecdsim/sizing",
    "ecdsim/characterize",
    "ecdsim/webapp",
]
SPECIAL_CASES = ("DynamicSolution", '== "dynamic"', '"dynamic" in', '["dynamic"]')


def test_computing_layers_do_not_special_case_the_dynamic_method() -> None:
    from tests.conftest import ROOT

    source = ROOT / "src"
    found = [
        f"{path.relative_to(source)}:{number}: {line.strip()}"
        for where in HOOKS_ONLY
        for path in (
            [source / where] if where.endswith(".py") else sorted((source / where).rglob("*.py"))
        )
        for number, line in enumerate(path.read_text().splitlines(), 1)
        if any(needle in line for needle in SPECIAL_CASES)
    ]
    assert found == []
