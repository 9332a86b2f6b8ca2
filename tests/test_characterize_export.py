"""The round trip: a fit writes a configuration that ``ecdsim deploy`` reproduces."""

from __future__ import annotations

import json
import tomllib
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from typer.testing import CliRunner

from ecdsim.characterize.export import (
    ExportError,
    fitted_ecd,
    fitted_parameter_text,
    spring_config_text,
    toml_string,
    write_parameter_file,
)
from ecdsim.characterize.stats import Estimate
from ecdsim.cli.app import app
from ecdsim.config import parse_config
from tests import hand
from tests.conftest import PAPER_CONFIG
from tests.test_characterize_synthetic import Truth, drop_csv, drop_points, paper_trace

runner = CliRunner()
TRUTH = Truth()
TEMPERATURES = [-40.0, 25.0, 100.0]
MASSES = [2.0, 3.5, 5.0, 6.5, 8.0, 9.5]


def invoke(*args: str) -> dict[str, Any]:
    result = runner.invoke(app, list(args))
    assert result.exit_code == 0, result.output
    document: dict[str, Any] = json.loads(result.stdout)
    return document


def deploy(path: Path) -> dict[float, dict[str, Any]]:
    document = invoke("deploy", str(path), "--json")
    return {case["temperature_C"]: case for case in document["cases"]}


def test_drop_test_round_trip_reproduces_the_true_parameters(tmp_path: Path) -> None:
    data = tmp_path / "drops.csv"
    data.write_text(drop_csv(drop_points(TRUTH, TEMPERATURES, MASSES), inertia_column=False))
    out = tmp_path / "fitted.toml"
    invoke("fit", "drop-test", str(data), "-o", str(out), "--config", str(PAPER_CONFIG), "--json")
    cases = deploy(out)
    assert sorted(cases) == TEMPERATURES  # the test temperatures become the analysis ones
    for t, case in cases.items():
        # Exact data on the linear law: the file must give the truth back (round-off only).
        assert case["damping_rate_Nms_per_rad"] == pytest.approx(TRUTH.damping(t), rel=1e-9)
        assert case["friction_Nm"] == pytest.approx(TRUTH.friction(t), rel=1e-9)
        assert case["components"]["gear_ratio"] == 1.0
        # The load is the --config's: the paper's spring and FS_T.
        assert case["start_torque_Nm"] == pytest.approx(hand.TS, rel=1e-15)
        assert case["end_torque_Nm"] == pytest.approx(hand.TE, rel=1e-15)
        assert case["system_friction_Nm"] == pytest.approx(hand.fs(t), rel=1e-12)


def test_noisy_round_trip_reproduces_the_fitted_laws(tmp_path: Path) -> None:
    rng = np.random.default_rng(12)
    points = drop_points(TRUTH, TEMPERATURES, MASSES, torque_noise=0.01, rng=rng)
    data = tmp_path / "drops.csv"
    data.write_text(drop_csv(points, inertia_column=False))
    out = tmp_path / "fitted.toml"
    fit = invoke("fit", "drop-test", str(data), "-o", str(out), "--json")
    assert fit["parameter_file"] == str(out)
    linear = fit["temperature_laws"]["damping_rate"]["linear"]
    line = fit["temperature_laws"]["friction"]
    cases = deploy(out)
    for t, case in cases.items():
        law_b = linear["damping_rate_ref_Nms_per_rad"] * (
            1.0 + linear["temperature_coefficient_per_K"] * (t - 25.0)
        )
        law_f = line["slope_Nm_per_K"] * t + line["at_0C_Nm"]
        # The file writes each fitted number to 6 significant digits at least (more where
        # its interval is narrow): each rounded by <= 5e-6 relative, so BECD and FECD,
        # sums of two such terms, lie within 2e-5 of the law (they are far from 0 here).
        assert case["damping_rate_Nms_per_rad"] == pytest.approx(law_b, rel=2e-5)
        assert case["friction_Nm"] == pytest.approx(law_f, rel=2e-5)
    written = tomllib.loads(out.read_text())["damper"]
    # No float noise: 6 significant digits where the interval is wider than 1e-4 relative.
    b_ref = linear["damping_rate_ref_Nms_per_rad"]
    assert written["damping_rate"] == f"{b_ref:.6g} N*m*s/rad"
    text = out.read_text()
    assert "PLACEHOLDER LOAD" in text  # no --config: a marked placeholder
    largest = max(p.true_torque for p in points)
    # The stand-in torque is written to 6 significant digits (issue 26: no float noise).
    assert cases[25.0]["start_torque_Nm"] == pytest.approx(largest, rel=5e-6)
    assert cases[25.0]["end_torque_Nm"] == cases[25.0]["start_torque_Nm"]
    assert not any(w["code"] == "stall" for w in invoke("deploy", str(out), "--json")["warnings"])


def test_single_temperature_round_trip(tmp_path: Path) -> None:
    data = tmp_path / "drops.csv"
    data.write_text(drop_csv(drop_points(TRUTH, [40.0], MASSES), inertia_column=False))
    out = tmp_path / "fitted.toml"
    fit = invoke("fit", "drop-test", str(data), "-o", str(out), "--json")
    assert "single_temperature_export" in [w["code"] for w in fit["warnings"]]
    spec = tomllib.loads(out.read_text())
    assert spec["damper"]["damping_temperature_coefficient"] == "0 / K"
    (case,) = deploy(out).values()
    assert case["temperature_C"] == 40.0
    assert case["damping_rate_Nms_per_rad"] == pytest.approx(TRUTH.damping(40.0), rel=1e-9)
    assert case["friction_Nm"] == pytest.approx(TRUTH.friction(40.0), rel=1e-9)


def test_trace_round_trips(tmp_path: Path) -> None:
    lines = ["time_s,angle_rad,temperature_C"]
    for t in TEMPERATURES:
        times = np.arange(0.0, 1.1 * hand.exact_time(t), 0.25)
        for time, angle in zip(times, paper_trace(t, times), strict=True):
            lines.append(f"{float(time)!r},{float(angle)!r},{t!r}")
    data = tmp_path / "trace.csv"
    data.write_text("\n".join(lines) + "\n")
    damper = tmp_path / "damper.toml"
    invoke("fit", "trace", str(data), "--config", str(PAPER_CONFIG), "-o", str(damper), "--json")
    for t, case in deploy(damper).items():
        # The paper's BECD and FECD are linear in T: the fitted laws are exact (1e-6 from the
        # trace fit's stopping rule), and the load with FS_T is the config's.
        assert case["damping_rate_Nms_per_rad"] == pytest.approx(hand.becd(t), rel=1e-6)
        assert case["friction_Nm"] == pytest.approx(hand.fecd(t), rel=1e-6)
        assert case["system_friction_Nm"] == pytest.approx(hand.fs(t), rel=1e-12)
        assert case["exact"]["deployment_time_s"] == pytest.approx(hand.exact_time(t), rel=1e-6)
    spring = tmp_path / "spring.toml"
    args = ["fit", "trace", str(data), "--config", str(PAPER_CONFIG), "--fit-spring"]
    invoke(*args, "-o", str(spring), "--json")
    for t, case in deploy(spring).items():
        assert case["start_torque_Nm"] == pytest.approx(hand.TS, rel=1e-6)
        assert case["end_torque_Nm"] == pytest.approx(hand.TE, rel=1e-6)
        assert case["damping_rate_Nms_per_rad"] == pytest.approx(hand.becd(t), rel=1e-12)


def test_a_load_with_tables_is_copied_exactly() -> None:
    source = parse_config(
        """
[damper]
damping_rate = "1.3e-4 N*m*s/rad"
coulomb_friction = "7.9e-4 N*m"
[gearbox]
ratio = 380
damping_fraction = 0.26
coulomb_friction = "4.5e-4 N*m"
[load]
spring_table = [["0 deg", "3.7 N*m"], ["45 deg", "2.9 N*m"], ["95 deg", "1.5 N*m"]]
travel = "90 deg"
system_friction = { table = [["-40 degC", "0.75 N*m"], ["100 degC", "0.15 N*m"]] }
spring_temperature_coefficient = "-2e-4 / K"
reference_temperature = "20 degC"
"""
    )
    ecd = fitted_ecd([25.0], [Estimate(24.0, 0.1, (23.8, 24.2))], [Estimate(0.5, None, None)], None)
    text = fitted_parameter_text(ecd, source.spec.load, 0.0, "tables", ["test"])
    assert parse_config(text).spec.load == source.spec.load


def test_toml_strings_survive_tomllib() -> None:
    nasty = 'quote " backslash \\ tab \t newline \n bell \x07 del \x7f unicode \u00b0C \U0001f600'
    assert tomllib.loads(f"key = {toml_string(nasty)}")["key"] == nasty


def test_write_refuses_an_invalid_file_and_leaves_nothing(tmp_path: Path) -> None:
    target = tmp_path / "bad.toml"
    with pytest.raises(ExportError, match="would not be valid"):
        write_parameter_file(target, "[damper]\n")
    assert list(tmp_path.iterdir()) == []


def test_exports_that_cannot_be_written() -> None:
    b = [Estimate(24.0, None, None), Estimate(20.0, None, None)]
    f = [Estimate(0.5, None, None), Estimate(0.4, None, None)]
    with pytest.raises(ExportError, match="no law"):
        fitted_ecd([0.0, 50.0], b, f, None)
    with pytest.raises(ExportError, match="nothing to write"):
        fitted_ecd([], [], [], None)
    with pytest.raises(ExportError, match="not positive"):
        fitted_ecd([25.0], [Estimate(-1.0, None, None)], f[:1], None)


def test_a_spring_fit_writes_the_users_file_back() -> None:
    # A config in the user's own units and comments, with a title and [analysis].
    user = (
        PAPER_CONFIG.read_text().replace(
            'coulomb_friction = "4.5e-4 N*m"',
            'coulomb_friction = "4.5e-4 N*m"\nlost_motion = "0.25 deg"  # my gearbox',
        )
        + '\nmethods = ["exact"]   # only the exact method\n'
    )
    text = spring_config_text(
        user,
        Estimate(3.5123456789, 0.01, (3.48, 3.52)),
        Estimate(1.5, 0.01, (1.48, 1.52)),
        ["test"],
        "paper_cc16.toml",
    )
    # Everything else as the user wrote it, line for line (after the header).
    body = text[text.index(user.splitlines()[0]) :]
    changed = [(a, b) for a, b in zip(user.splitlines(), body.splitlines(), strict=True) if a != b]
    # The interval's half-width 0.02 N*m: 1 % of it is 2e-4, so 6 digits (3.51235).
    assert changed == [
        ('start_torque = "3.73 N*m"', 'start_torque = "3.51235 N*m"'),
        ('end_torque = "1.58 N*m"', 'end_torque = "1.5 N*m"'),
    ]
    written = parse_config(text).spec
    source = parse_config(user).spec
    expected = source.model_dump()
    expected["load"].update(start_torque=3.51235, end_torque=1.5)
    assert written.model_dump() == expected


def test_a_damper_fit_keeps_the_users_file(tmp_path: Path) -> None:
    # The case: a config in degF with a title, [analysis] and comments. fit -o
    # used to drop the title and [analysis] and write -40 degF as -39.99999999999997 degC.
    user = tmp_path / "mine.toml"
    text = PAPER_CONFIG.read_text().replace(
        'temperatures = ["-40 degC", "25 degC", "100 degC"]',
        'temperatures = ["-40 degF", "77 degF", "212 degF"]   # our qualification range',
    )
    assert "degF" in text
    user.write_text(text)
    data = tmp_path / "drops.csv"
    data.write_text(drop_csv(drop_points(TRUTH, TEMPERATURES, MASSES), inertia_column=False))
    out = tmp_path / "fitted.toml"
    invoke("fit", "drop-test", str(data), "-o", str(out), "--config", str(user), "--json")
    written = out.read_text()
    assert 'title = "CDA Cc-16 test deployment (paper section 6)"' in written
    assert 'temperatures = ["-40 degF", "77 degF", "212 degF"]   # our qualification range' in (
        written
    )
    assert "-39.99" not in written  # the user's -40 degF, not its conversion
    assert 'travel = "1.57 rad"' in written  # the [load] as the user wrote it
    assert "ratio = 1 # BECD and FECD are already at the input shaft" in written
    # The paper's own comments on its [damper] go with the damper they described.
    assert "# FD" not in written
    assert written.startswith("# Written by ecdsim")
    # deploy reads it: the analysis temperatures are the user's (-40 degF = -40 degC).
    cases = deploy(out)
    assert sorted(cases) == pytest.approx([-40.0, 25.0, 100.0], abs=1e-12)
    for t, case in cases.items():
        assert case["damping_rate_Nms_per_rad"] == pytest.approx(TRUTH.damping(t), rel=1e-9)


def test_a_user_file_the_fit_cannot_keep_is_an_export_error() -> None:
    estimate = Estimate(3.5, 0.01, (3.48, 3.52))
    with pytest.raises(ExportError, match="no \\[load\\]"):
        spring_config_text('title = "x"\n', estimate, estimate, ["test"], "x.toml")
    with pytest.raises(ExportError, match="cannot keep the --config file's text"):
        spring_config_text("[load\n", estimate, estimate, ["test"], "x.toml")


def test_damper_and_gearbox_keys_the_fit_does_not_hold_are_named(tmp_path: Path) -> None:
    # The fitted file replaces [damper] and [gearbox] by one 1:1 ECD; keys of the damper's
    # own shaft or the gearbox (here a roll-off law, the rotor inertia and lost motion)
    # are not carried over. They used to vanish without a word: now the file's header and
    # a warning name each one.
    user = tmp_path / "mine.toml"
    text = PAPER_CONFIG.read_text().replace(
        'coulomb_friction = "7.9e-4 N*m"',
        'coulomb_friction = "7.9e-4 N*m"\nrotor_inertia = "2e-7 kg*m^2"\n'
        'rolloff = { peak_speed = "5000 rpm", resistivity_coefficient = "0.0039 / K" }',
        1,
    )
    text = text.replace("[gearbox]\n", '[gearbox]\nlost_motion = "0.2 deg"\n', 1)
    user.write_text(text)
    parse_config(text)  # the user's file is itself valid
    data = tmp_path / "drops.csv"
    data.write_text(drop_csv(drop_points(TRUTH, TEMPERATURES, MASSES), inertia_column=False))
    out = tmp_path / "fitted.toml"
    result = runner.invoke(
        app, ["fit", "drop-test", str(data), "-o", str(out), "--config", str(user), "--json"]
    )
    assert result.exit_code == 0, result.output
    names = "damper.rotor_inertia, damper.rolloff, gearbox.lost_motion"
    header = out.read_text().split("\n\n", 1)[0]
    assert names in header
    warnings = [w["message"] for w in json.loads(result.stdout)["warnings"]]
    assert any(names in w and "not carried over" in w for w in warnings), warnings
    written = tomllib.loads(out.read_text())
    assert "rolloff" not in written["damper"]
    assert "lost_motion" not in written["gearbox"]
    # A file with only the keys the fit writes names none (no header line, no warning).
    plain = tmp_path / "plain.toml"
    plain.write_text(PAPER_CONFIG.read_text())
    result = runner.invoke(
        app, ["fit", "drop-test", str(data), "-o", str(out), "--config", str(plain), "--json"]
    )
    assert result.exit_code == 0, result.output
    assert "not carried over" not in out.read_text()
    messages = [w["message"] for w in json.loads(result.stdout)["warnings"]]
    assert not any("not carried over" in m for m in messages)
