"""The notebook API (ecdsim.deploy, fit, size, montecarlo.open; issue 17 item 2).

Numbers are checked against the paper's section 6 (BECD25 = 24 N*m*s/rad, FECD25 =
0.52 N*m, as printed to two figures), the hand calculations of tests/hand.py, or the
CLI's JSON document for the same input.
"""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path
from typing import Any

import pint
import pytest
from typer.testing import CliRunner

import ecdsim
from ecdsim.api import MissingDependencyError
from ecdsim.cli.app import app
from ecdsim.config import ConfigError
from tests import hand

ROOT = Path(__file__).resolve().parent.parent
PAPER = ROOT / "examples" / "paper_cc16.toml"
U: Any = pint.UnitRegistry()
LBF_IN = 0.45359237 * 9.80665 * 0.0254  # N*m per lbf*in, from the exact definitions


def test_import_is_light_and_exports_are_lazy() -> None:
    code = (
        "import sys, ecdsim; "
        "heavy = [m for m in ('pandas', 'matplotlib', 'scipy', 'ecdsim.api') if m in sys.modules]; "
        "print(heavy); ecdsim.deploy; print('ecdsim.api' in sys.modules)"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    ).stdout.split("\n")
    assert out[0] == "[]"
    assert out[1] == "True"
    with pytest.raises(AttributeError, match="no attribute 'nothing'"):
        _ = ecdsim.nothing


def test_deploy_matches_the_paper_and_the_hand_calculation() -> None:
    result = ecdsim.deploy(PAPER)
    frame = result.to_dataframe()
    # Long format: one row per (temperature, method), units in the column names.
    assert list(frame["temperature_C"]) == [-40.0, -40.0, 25.0, 25.0, 100.0, 100.0]
    assert list(frame["method"]) == ["paper", "exact"] * 3
    for column in ("deployment_time_s", "damping_rate_Nms_per_rad", "friction_Nm"):
        assert column in frame.columns
    at25 = frame[frame["temperature_C"] == 25.0].set_index("method")
    # The paper prints BECD25 = 24 and FECD25 = 0.52: agreement to their 2 figures.
    assert at25.loc["exact", "damping_rate_Nms_per_rad"] == pytest.approx(24.0, rel=0.02)
    assert at25.loc["exact", "friction_Nm"] == pytest.approx(0.52, rel=0.03)
    for t in (-40.0, 25.0, 100.0):
        rows = frame[frame["temperature_C"] == t].set_index("method")
        # Same equations as tests/hand.py, different arithmetic order: 1e-12.
        assert rows.loc["paper", "deployment_time_s"] == pytest.approx(
            hand.paper_time(t), rel=1e-12
        )
        assert rows.loc["exact", "deployment_time_s"] == pytest.approx(
            hand.exact_time(t), rel=1e-12
        )
        assert rows.loc["exact", "damping_rate_Nms_per_rad"] == pytest.approx(
            hand.becd(t), rel=1e-12
        )
    assert result.deployment_time("paper")[25.0] == pytest.approx(hand.paper_time(25.0), 1e-12)


def test_quantities_and_plain_si_give_the_same_answer() -> None:
    # 77 degF = 25 degC and 212 degF = 100 degC by (F - 32) * 5 / 9.
    by_pint = ecdsim.deploy(PAPER, temperatures=U.Quantity([77.0, 212.0], "degF"), methods="exact")
    by_string = ecdsim.deploy(PAPER, temperatures=["77 degF", "100 degC"], methods=["exact"])
    plain = ecdsim.deploy(PAPER, temperatures=[25, 100], methods="exact")
    times = [list(r.to_dataframe()["deployment_time_s"]) for r in (by_pint, by_string, plain)]
    # pint's degF conversion rounds in the last digits: 1e-12.
    assert times[0] == pytest.approx(times[2], rel=1e-12)
    assert times[1] == pytest.approx(times[2], rel=1e-12)
    assert times[2][0] == pytest.approx(hand.exact_time(25.0), rel=1e-12)

    # Overrides: 33 lbf*in as a pint quantity, the same in plain SI, and in a string.
    ts = 33.0 * LBF_IN
    expected = hand.paper_time(25.0, ts=ts)
    for value in (U.Quantity(33.0, "lbf*inch"), ts, "33 lbf*in"):
        r = ecdsim.deploy(PAPER, 25, "paper", overrides={"load.start_torque": value})
        assert r.deployment_time("paper")[25.0] == pytest.approx(expected, rel=1e-12)


def test_bad_input_raises_config_error_naming_the_field() -> None:
    cases = [
        ({"temperatures": "hot"}, "temperatures"),
        ({"temperatures": U.Quantity(3.0, "kg")}, "temperatures"),
        ({"temperatures": [-300.0]}, "temperatures"),
        ({"methods": "magic"}, "methods: 'magic'"),
        ({"overrides": {"load.start_torque": U.Quantity(3.0, "kg")}}, "load.start_torque"),
        ({"overrides": {"load.start_torque": -1.0}}, "load.start_torque"),
        ({"overrides": {"gearbox.nope": 1.0}}, "gearbox.nope: unknown key"),
        ({"overrides": {"title.x": 1.0}}, "title.x: title is a value"),
    ]
    for kwargs, needle in cases:
        with pytest.raises(ConfigError) as caught:
            ecdsim.deploy(PAPER, **kwargs)
        assert needle in str(caught.value), (kwargs, str(caught.value))
        assert all(line.strip() for line in str(caught.value).splitlines())
    with pytest.raises(ConfigError, match="config file not found"):
        ecdsim.deploy(ROOT / "no-such.toml")
    with pytest.raises(ConfigError, match="cannot take overrides"):
        ecdsim.deploy(ecdsim.load(PAPER), overrides={"gearbox.ratio": 1.0})


def test_to_dataframe_without_pandas_names_the_extra(monkeypatch: pytest.MonkeyPatch) -> None:
    result = ecdsim.deploy(PAPER, 25, "exact")
    monkeypatch.setitem(sys.modules, "pandas", None)
    with pytest.raises(MissingDependencyError) as caught:
        result.to_dataframe()
    message = str(caught.value)
    assert "pip install 'ecdsim[montecarlo]'" in message
    assert "\n" not in message


def test_html_and_plots(tmp_path: Path) -> None:
    result = ecdsim.deploy(PAPER)
    page = result._repr_html_()
    assert page.startswith("<table>")
    assert "<th>deployment_time_s</th>" in page
    assert "CDA Cc-16" in page
    figures = result.plot()
    assert len(figures) == 3
    for fig in figures:
        ax = fig.axes[0]
        assert ax.get_title()
        assert "[" in ax.get_xlabel()
        assert "[" in ax.get_ylabel()
        assert ax.get_legend() is not None
    figures[0].savefig(tmp_path / "angle.png")
    assert (tmp_path / "angle.png").stat().st_size > 0


def _cli_json(*args: str) -> dict[str, object]:
    run = CliRunner().invoke(app, list(args))
    assert run.exit_code == 0, run.output
    start = run.stdout.index("{")
    document: dict[str, object] = json.loads(run.stdout[start:])
    return document


def test_fit_matches_the_cli() -> None:
    csv = ROOT / "examples" / "drop_test.csv"
    result = ecdsim.fit(csv)
    frame = result.to_dataframe()
    cli = _cli_json("fit", "drop-test", str(csv), "--json")
    temps = cli["temperatures"]
    assert isinstance(temps, list)
    assert list(frame["temperature_C"]) == [t["temperature_C"] for t in temps]
    # The same fit by the same code path: equal to 1e-12 (JSON round trip of floats).
    for row, t in zip(frame.to_dict("records"), temps, strict=True):
        assert row["damping_rate_Nms_per_rad"] == pytest.approx(
            t["damping_rate_Nms_per_rad"], 1e-12
        )
        assert row["friction_Nm"] == pytest.approx(t["friction_Nm"], 1e-12)
        assert [
            row["damping_rate_ci95_low_Nms_per_rad"],
            row["damping_rate_ci95_high_Nms_per_rad"],
        ] == pytest.approx(t["damping_rate_ci95"], 1e-12)
    assert len(result.plot()) == 3
    with pytest.raises(ConfigError, match="noise: unknown noise model 'loud'"):
        ecdsim.fit(csv, noise="loud")
    with pytest.raises(ConfigError, match="reference_temperature: expected one"):
        ecdsim.fit(csv, reference_temperature=[20, 30])
    with pytest.raises(ConfigError, match="not found"):
        ecdsim.fit(ROOT / "no-such.csv")


def test_size_matches_the_cli() -> None:
    config = ROOT / "examples" / "sizing.toml"
    catalogue = ROOT / "examples" / "catalogue.toml"
    result = ecdsim.size(config, catalogue)
    frame = result.to_dataframe()
    cli = _cli_json("size", str(config), "--catalog", str(catalogue), "--json")
    candidates = cli["candidates"]
    assert isinstance(candidates, list)
    best = frame[frame["rank"] == 1]
    times = [c["deployment_time_s"] for c in candidates[0]["cases"]]
    assert list(best["deployment_time_s"]) == pytest.approx(times, rel=1e-12)
    assert len(frame) == sum(len(c["cases"]) for c in candidates)
    figures = result.plot()
    assert figures
    assert figures[0].axes[0].get_xlabel() == "temperature [degC]"
    with pytest.raises(ConfigError, match="requirements"):
        ecdsim.size(PAPER, catalogue)


@pytest.mark.slow
def test_montecarlo_open(tmp_path: Path) -> None:
    out = tmp_path / "study"
    config = ROOT / "examples" / "paper_cc16_tolerances.toml"
    run = CliRunner().invoke(
        app, ["montecarlo", str(config), "--samples", "300", "--out", str(out), "--seed", "1"]
    )
    assert run.exit_code == 0, run.output
    frame = ecdsim.montecarlo.open(out)
    assert len(frame) == 300
    assert sorted(frame["sample"]) == list(range(300))
    assert "deployment_time_s@25.0C" in frame.columns
    summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    assert summary  # the study finished
    dataset = ecdsim.montecarlo.open(out, as_="arrow")
    assert dataset.count_rows() == 300
    assert math.isfinite(float(frame["deployment_time_s@25.0C"].median()))

    from ecdsim.montecarlo import NotAStudy

    with pytest.raises(NotAStudy, match="no manifest"):
        ecdsim.montecarlo.open(tmp_path)
    (out / "summary.json").unlink()
    with pytest.raises(NotAStudy, match="not finished"):
        ecdsim.montecarlo.open(out)
