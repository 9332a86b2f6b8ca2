"""Torque budgets (issue 28, item 1), each margin against a hand calculation.

The budget of the issue, by hand: 44 / (1.5 * 6.5 + 3.0 * 5.41) - 1 = 44 / 25.98 - 1, and
its torque ratio 44 / (6.5 + 5.41) = 44 / 11.91. A config's budget, by hand from the
paper's Eq. 1-4 and FS_T (tests/hand.py) at the end of travel, where the spring torque
Te = 1.58 N*m is lowest and every resistive torque is the same at every angle.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from typer.testing import CliRunner

from ecdsim.cli.app import app
from ecdsim.config import load_config
from ecdsim.sizing.budget import WAIVER, budget_from_config
from ecdsim.sizing.margin import MarginSettings, torque_margin
from tests import hand
from tests.conftest import ROOT

runner = CliRunner()
BUDGET = ROOT / "examples" / "torque_budget.toml"
CONFIG_BUDGET = ROOT / "examples" / "paper_cc16_budget.toml"
SIZING = ROOT / "examples" / "sizing.toml"
LBF_IN = 0.45359237 * 9.80665 * 0.0254  # N*m per lbf*in, by definition of lbf and inch
# A few float operations on O(1) numbers: the code and the hand formulas agree to rounding.
TIGHT = 1e-12

ISSUE_BUDGET = """
[budget]
available = "44 in*lbf"
factors = { known = 1.5, unknown = 3.0 }
[[budget.torque]]
name = "ECD magnetic Coulomb friction"
value = "6.5 in*lbf"
kind = "known"
[[budget.torque]]
name = "hinge friction and harness"
value = "5.41 in*lbf"
kind = "unknown"
"""


def write(tmp_path: Path, text: str, name: str = "budget.toml") -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def margin_json(path: Path, *extra: str) -> dict[str, Any]:
    result = runner.invoke(app, ["margin", str(path), "--json", *extra])
    assert result.exit_code == 0, result.output
    document: dict[str, Any] = json.loads(result.stdout)
    return document


def test_the_issues_budget_by_hand(tmp_path: Path) -> None:
    document = margin_json(write(tmp_path, ISSUE_BUDGET))
    assert document["margin"] == pytest.approx(44.0 / (1.5 * 6.5 + 3.0 * 5.41) - 1.0, rel=TIGHT)
    assert document["torque_ratio"] == pytest.approx(44.0 / (6.5 + 5.41), rel=TIGHT)
    (phase,) = document["phases"]
    (case,) = phase["cases"]
    # SI inside: the JSON's torques are the inch-pounds converted exactly.
    assert case["available_Nm"] == pytest.approx(44.0 * LBF_IN, rel=TIGHT)
    assert case["factored_sum_Nm"] == pytest.approx(25.98 * LBF_IN, rel=TIGHT)
    assert [t["factor"] for t in case["torques"]] == [1.5, 3.0]
    assert case["verdict"] == "positive margin"


def test_the_table_is_in_the_users_units(tmp_path: Path) -> None:
    result = runner.invoke(
        app, ["margin", str(write(tmp_path, ISSUE_BUDGET))], env={"COLUMNS": "80"}
    )
    assert result.exit_code == 0, result.output
    # Written in in*lbf, shown in in*lbf: 1.5 * 6.5 = 9.75, 3 * 5.41 = 16.23, sum 25.98.
    assert "[in*lbf]" in result.stdout
    for cell in ("9.75", "16.23", "11.91", "25.98"):
        assert cell in result.stdout
    assert "margin = 44 / 25.98 - 1 = +0.6936" in result.stdout
    assert "torque ratio = 44 / 11.91 = 3.694" in result.stdout
    assert max(len(line) for line in result.stdout.splitlines()) <= 80
    # --units si shows N*m instead: 44 lbf*in = 4.971 N*m.
    si = runner.invoke(app, ["margin", str(write(tmp_path, ISSUE_BUDGET)), "--units", "si"])
    assert "[N*m]" in si.stdout
    assert "4.971" in si.stdout


NEGATIVE = """
[budget]
available = "10 N*m"
factors = { known = 1.5, unknown = 3.0 }
[[budget.torque]]
name = "friction"
value = "4 N*m"
kind = "known"
[[budget.torque]]
name = "harness"
value = "2 N*m"
kind = "unknown"
"""


def test_a_negative_margin_with_a_torque_ratio_above_one_is_named(tmp_path: Path) -> None:
    # 10 / (6 + 6) - 1 = -1/6 < 0, while 10 / 6 > 1: the waiver case.
    path = write(tmp_path, NEGATIVE)
    document = margin_json(path)
    assert document["margin"] == pytest.approx(10.0 / 12.0 - 1.0, rel=TIGHT)
    assert document["torque_ratio"] == pytest.approx(10.0 / 6.0, rel=TIGHT)
    assert document["waiver_case"] is True
    assert document["phases"][0]["cases"][0]["verdict"] == WAIVER
    shown = runner.invoke(app, ["margin", str(path)])
    assert shown.exit_code == 0  # a negative margin is a result, not an error
    assert "negative margin, torque ratio above 1" in shown.stdout
    failed = runner.invoke(app, ["margin", str(path), "--fail-on", "margin"])
    assert failed.exit_code == 1
    assert "fail: margin: -0.1667" in failed.stderr
    assert "torque ratio above 1" in failed.stderr
    # Below 1 too: 5 / 6 < 1 is named differently.
    worse = margin_json(write(tmp_path, NEGATIVE.replace("10 N*m", "5 N*m"), "worse.toml"))
    assert worse["phases"][0]["cases"][0]["verdict"] == (
        "negative margin, torque ratio at or below 1"
    )


def test_a_positive_margin_passes_fail_on(tmp_path: Path) -> None:
    result = runner.invoke(
        app, ["margin", str(write(tmp_path, ISSUE_BUDGET)), "--fail-on", "margin"]
    )
    assert result.exit_code == 0


def test_phases_take_their_own_factors_and_fall_back_to_the_base(tmp_path: Path) -> None:
    document = margin_json(BUDGET)
    by_phase = {p["phase"]: p["cases"][0] for p in document["phases"]}
    hand_margins = {"PDR": (2.0, 4.0), "CDR": (1.5, 3.0), "qualification": (1.25, 2.0)}
    for name, (known, unknown) in hand_margins.items():
        assert by_phase[name]["margin"] == pytest.approx(
            44.0 / (known * 6.5 + unknown * 5.41) - 1.0, rel=TIGHT
        )
    # The smallest over the phases is the top-level margin (PDR's).
    assert document["margin"] == pytest.approx(44.0 / (2 * 6.5 + 4 * 5.41) - 1.0, rel=TIGHT)
    only = margin_json(BUDGET, "--phase", "CDR")
    assert [p["phase"] for p in only["phases"]] == ["CDR"]
    partial = """
[budget]
available = "10 N*m"
factors = { known = 1.5, unknown = 3.0 }
[budget.phases.early]
factors = { unknown = 4.0 }
[[budget.torque]]
name = "a"
value = "1 N*m"
kind = "known"
[[budget.torque]]
name = "b"
value = "1 N*m"
kind = "unknown"
"""
    # "early" gives unknown only: known takes the base factor 1.5.
    case = margin_json(write(tmp_path, partial))["phases"][0]["cases"][0]
    assert case["margin"] == pytest.approx(10.0 / (1.5 + 4.0) - 1.0, rel=TIGHT)


def test_without_factors_every_factor_is_one_and_the_output_says_so(tmp_path: Path) -> None:
    text = "\n".join(line for line in ISSUE_BUDGET.splitlines() if "factors" not in line)
    path = write(tmp_path, text)
    document = margin_json(path)
    assert document["factors_applied"] is False
    assert document["margin"] == pytest.approx(44.0 / 11.91 - 1.0, rel=TIGHT)
    assert "no uncertainty factors applied" in runner.invoke(app, ["margin", str(path)]).stdout


@pytest.mark.parametrize(
    ("text", "fragment"),
    [
        (
            ISSUE_BUDGET.replace('available = "44 in*lbf"\n', ""),
            "budget.available: missing; expected a torque",
        ),
        (
            ISSUE_BUDGET.replace('"6.5 in*lbf"', '"6.5 in"'),
            "budget.torque[0].value: '6.5 in' has the wrong dimension; expected a torque in N*m",
        ),
        (
            ISSUE_BUDGET.replace('"5.41 in*lbf"', '"-5.41 in*lbf"'),
            "budget.torque[1].value: '-5.41 in*lbf' must be >= 0",
        ),
        (
            ISSUE_BUDGET.replace('kind = "unknown"', 'kind = "unknwon"'),
            "budget: torque[1] ('hinge friction and harness'): kind 'unknwon' has no "
            "factor in budget.factors; known kinds: known, unknown",
        ),
        (
            ISSUE_BUDGET.replace("unknown = 3.0", "unknown = 0.5"),
            "budget.factors.unknown: 0.5 must be >= 1",
        ),
        (ISSUE_BUDGET.replace("[budget]", "[budget]\nmargin = 1"), "budget.margin: unknown key"),
        (
            ISSUE_BUDGET + "\n[extra]\n",
            "extra: unknown key (a budget file holds title and [budget]",
        ),
        (
            "title = 'x'\n",
            "neither a torque budget ([budget] with available and [[budget.torque]]) nor a "
            "deployment config",
        ),
        ("[budget\n", "not valid TOML"),
    ],
)
def test_bad_budgets_are_one_line_errors(tmp_path: Path, text: str, fragment: str) -> None:
    result = runner.invoke(app, ["margin", str(write(tmp_path, text))])
    assert result.exit_code == 2, result.output
    lines = result.stderr.strip().splitlines()
    assert all(line.startswith("error: ") for line in lines)
    assert any(fragment in line for line in lines), lines
    assert "Traceback" not in result.output


def test_bad_options_are_one_line_errors(tmp_path: Path) -> None:
    path = write(tmp_path, ISSUE_BUDGET)
    for args, fragment in (
        (["--fail-on", "stall"], "--fail-on: 'stall' is not a condition here; expected margin"),
        (["--phase", "CDR"], "--phase: 'CDR' is not a phase of the budget"),
        (["-T", "25"], "--temperature: a budget file has no temperatures"),
        (["--units", "imperial"], "--units"),
    ):
        result = runner.invoke(app, ["margin", str(path), *args])
        assert result.exit_code == 2, (args, result.output)
        assert fragment in result.stderr
    missing = runner.invoke(app, ["margin", str(tmp_path / "none.toml")])
    assert missing.exit_code == 2
    assert "not found" in missing.stderr


# A config's budget ---------------------------------------------------------------------


def test_a_configs_budget_equals_the_sizing_margin_by_hand() -> None:
    # examples/sizing.toml has no [budget]: its [requirements.torque_margin] (damping at
    # 0.005 rad/s, every factor 1) gives the kinds, and the budget's margin is the torque
    # margin of docs/sizing.md section 5 at each temperature, by hand at the end of travel.
    budget = budget_from_config(load_config(SIZING), [-40.0, 25.0, 100.0])
    (phase,) = budget.phases
    for i, t in enumerate((-40.0, 25.0, 100.0)):
        resistive = hand.fecd(t) + hand.fs(t) + hand.becd(t) * 0.005
        assert phase.margin[i] == pytest.approx(hand.TE / resistive - 1.0, rel=TIGHT)
        assert phase.available[i] == pytest.approx(hand.TE, rel=TIGHT)
        assert phase.angle is not None
        assert phase.angle[i] == pytest.approx(hand.TRAVEL)
    assert phase.margin[0] == pytest.approx(0.06348, abs=5e-6)  # docs/sizing.md's table


def test_one_arithmetic_for_the_ecss_margin_and_the_budget() -> None:
    # The same factors through the sizing margin (ECSS kinds) and through a budget whose
    # kinds map onto them: the same numbers, from the same functions.
    config = load_config(CONFIG_BUDGET)
    budget = budget_from_config(config, [-40.0])
    design = next(p for p in budget.phases if p.phase == "design")
    terms = {t.kind: 0.0 for t in design.terms}
    for t in design.terms:
        terms[t.kind] += float(t.value[0])
    fe, fs, damping = hand.fecd(-40.0), hand.fs(-40.0), hand.becd(-40.0) * 0.005
    hand_margin = hand.TE / (1.2 * (fe + damping) + 2.0 * (fs + 0.05)) - 1.0
    assert float(design.margin[0]) == pytest.approx(hand_margin, rel=TIGHT)
    ecss = torque_margin(
        hand.TE,
        {"ecd_friction": fe, "system_friction": fs, "damping": damping, "harness": 0.05},
        {"ecd_friction": 1.2, "damping": 1.2, "system_friction": 2.0, "harness": 2.0},
    )
    assert float(ecss) == pytest.approx(hand_margin, rel=TIGHT)
    assert float(design.torque_ratio[0]) == pytest.approx(
        hand.TE / (fe + fs + damping + 0.05), rel=TIGHT
    )


def test_a_ground_tests_budget_is_taken_where_the_margin_is_lowest() -> None:
    # With gravity the resistive torque changes along the travel: the budget is taken at
    # the point the sizing margin finds lowest, and equals it (unit factors).
    config = load_config(ROOT / "examples" / "paper_cc16_ground_test.toml")
    temps = [-40.0, 25.0]
    budget = budget_from_config(config, temps)
    from ecdsim.deployment import predict
    from ecdsim.sizing.budget import margin_points

    prediction = predict(config.system, np.array(temps), ("exact",))
    lowest, where = margin_points(prediction, MarginSettings()).minimum()
    (phase,) = budget.phases
    np.testing.assert_allclose(phase.margin, lowest, rtol=TIGHT)
    assert phase.angle is not None
    np.testing.assert_allclose(phase.angle, where, rtol=TIGHT)
    assert any("gravity" in t.name for t in phase.terms)


def test_a_model_torque_without_a_factor_names_its_key(tmp_path: Path) -> None:
    text = CONFIG_BUDGET.read_text(encoding="utf-8").replace(
        'model_kinds = { ecd_friction = "known", damping = "known", system_friction = "unknown" }',
        'model_kinds = { ecd_friction = "known", damping = "known" }',
    )
    path = write(tmp_path, text, "config.toml")
    result = runner.invoke(app, ["margin", str(path)])
    assert result.exit_code == 2, result.output
    (line,) = result.stderr.strip().splitlines()
    assert "budget.model_kinds.system_friction" in line
    assert "'system_friction'" in line
    assert "map it to one of known, unknown" in line


def test_the_config_budget_on_the_command_line() -> None:
    document = margin_json(CONFIG_BUDGET, "-T", "-40", "-T", "100")
    assert document["temperatures_C"] == [-40.0, 100.0]
    qualification = next(p for p in document["phases"] if p["phase"] == "qualification")
    cold = qualification["cases"][0]
    fe, fs, damping = hand.fecd(-40.0), hand.fs(-40.0), hand.becd(-40.0) * 0.005
    assert cold["margin"] == pytest.approx(
        hand.TE / (1.1 * (fe + damping) + 1.5 * (fs + 0.05)) - 1.0, rel=TIGHT
    )
    assert cold["verdict"] == WAIVER  # -0.21 with a torque ratio of 1.03
    shown = runner.invoke(app, ["margin", str(CONFIG_BUDGET)], env={"COLUMNS": "80"})
    assert shown.exit_code == 0
    assert max(len(line) for line in shown.stdout.splitlines()) <= 80


def test_the_help_lists_the_options_and_its_example_runs(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from tests.helptext import assert_options, read_help, run_example

    screen = read_help(runner, app, ["margin"])
    assert_options(
        screen,
        {
            "--json": None,
            "--phase": None,
            "--temperature": "-T",
            "--fail-on": None,
            "--units": None,
            "--wide": None,
            "--plain": None,
            "--help": None,
        },
    )
    shown = run_example(runner, app, screen, tmp_path, monkeypatch)
    # Only the phase asked for (a table title wraps with the table's width).
    assert "qualification" in shown.stdout
    assert "design" not in shown.stdout


def test_the_report_shows_the_configs_budget(tmp_path: Path) -> None:
    # The report's Qualification section holds the same numbers as `ecdsim margin`.
    out = tmp_path / "report.html"
    done = runner.invoke(app, ["report", str(CONFIG_BUDGET), "-o", str(out)])
    assert done.exit_code == 0, done.output
    html = out.read_text(encoding="utf-8")
    assert '<h2 id="qualification">Qualification</h2>' in html
    document = margin_json(CONFIG_BUDGET)
    for phase in document["phases"]:
        assert f'data-phase="{phase["phase"]}"' in html
        for case in phase["cases"]:
            assert f"{case['margin']:+.4g}" in html
            assert case["verdict"] in html
    # A config without [budget] or a study gets no section.
    plain = tmp_path / "plain.html"
    assert runner.invoke(app, ["report", str(ROOT / "examples" / "paper_cc16.toml"), "-o",
                               str(plain)]).exit_code == 0  # fmt: skip
    assert 'id="qualification"' not in plain.read_text(encoding="utf-8")
