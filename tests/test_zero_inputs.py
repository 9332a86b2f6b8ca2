"""Zero is a valid torque and a valid damping rate (issue 11, item 2).

One rule for every quantity: reject what is not physical (negative, NaN, infinite),
accept zeros, and where a *method* cannot solve an accepted case, say so per method in
the result, never as a config error. The references are closed-form solutions of the
same equations, derived by hand below.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from ecdsim.cli.app import app
from ecdsim.config import ConfigError, parse_config
from ecdsim.deployment import predict
from tests import hand
from tests.conftest import ROOT

runner = CliRunner()
DYNAMIC_EXAMPLE = (ROOT / "examples" / "paper_cc16_dynamic.toml").read_text()

# The dynamic example's inertia at the input shaft: the 5 kg*m^2 load plus the rotor's
# 2e-7 kg*m^2 reflected through 380:1 (J * N^2).
J_TOTAL = 5.0 + 2e-7 * 380.0**2


def _edit(text: str, **replacements: str) -> str:
    for old, new in replacements.items():
        assert old in text, old
        text = text.replace(old, new)
    return text


def spin_down_config() -> str:
    """No spring, an initial speed: the classic brake (spin-down) test."""
    text = _edit(
        DYNAMIC_EXAMPLE,
        **{
            'start_torque = "3.73 N*m"': 'start_torque = "0 N*m"',
            'end_torque = "1.58 N*m"': 'end_torque = "0 N*m"',
        },
    )
    return text + '\n[initial]\nspeed = "0.5 rad/s"\n'


def undamped_config() -> str:
    """The dynamic example with no eddy-current damping (so BG = 0.26 * BD = 0 too)."""
    return _edit(
        DYNAMIC_EXAMPLE,
        **{'damping_rate = "1.3e-4 N*m*s/rad"': 'damping_rate = "0 N*m*s/rad"'},
    )


def test_zero_torque_and_zero_damping_are_accepted() -> None:
    # Accepted and kept as zero (not replaced by a default or a floor).
    load = parse_config(spin_down_config()).system.load
    _, torques = load.spring.breakpoints(load.travel, 25.0)
    assert np.all(np.asarray(torques) == 0.0)
    undamped = parse_config(undamped_config()).system
    assert float(undamped.ecd.at(25.0).ecd_damping_rate) == 0.0


@pytest.mark.parametrize(
    ("line", "value", "key"),
    [
        ('start_torque = "3.73 N*m"', 'start_torque = "-1 N*m"', "load.start_torque"),
        ('start_torque = "3.73 N*m"', 'start_torque = "nan N*m"', "load.start_torque"),
        ('start_torque = "3.73 N*m"', 'start_torque = "inf N*m"', "load.start_torque"),
        (
            'damping_rate = "1.3e-4 N*m*s/rad"',
            'damping_rate = "-1e-4 N*m*s/rad"',
            "damper.damping_rate",
        ),
        (
            'damping_rate = "1.3e-4 N*m*s/rad"',
            'damping_rate = "nan N*m*s/rad"',
            "damper.damping_rate",
        ),
    ],
)
def test_non_physical_values_are_still_rejected(line: str, value: str, key: str) -> None:
    with pytest.raises(ConfigError) as info:
        parse_config(_edit(DYNAMIC_EXAMPLE, **{line: value}))
    assert any(key in message for message in info.value.problems)


def test_spin_down_dynamic_matches_the_closed_form() -> None:
    # J dw/dt = -B w - F from w0 (no spring): the speed decays to zero at
    #   t_stop = (J/B) ln(1 + B w0 / F)
    # having turned
    #   theta_stop = (J/B) (w0 - (F/B) ln(1 + B w0 / F)).
    config = parse_config(spin_down_config())
    prediction = predict(
        config.system, [25.0], ["paper", "exact", "dynamic"], config.spec.dynamics()
    )
    b = hand.becd(25.0)
    f = hand.fecd(25.0) + hand.fs(25.0)
    w0 = 0.5
    log_term = math.log1p(b * w0 / f)
    theta_stop = (J_TOTAL / b) * (w0 - (f / b) * log_term)
    t_stop = (J_TOTAL / b) * log_term
    document = prediction.to_dict()
    dynamic = document["cases"][0]["dynamic"]
    # Linear segments are solved in closed form by ecdsim too: agreement to rounding, with
    # margin for the event location (root finding to ~1e-12 relative).
    assert dynamic["stuck_angle_rad"] == pytest.approx(theta_stop, rel=1e-9)
    assert dynamic["stuck_time_s"] == pytest.approx(t_stop, rel=1e-9)
    # The quasi-static methods solve it too: with no drive torque the mechanism cannot
    # start, a stall at 0 rad, and the warning says so in those words.
    for method in ("paper", "exact"):
        block = document["cases"][0][method]
        assert block["solved"] is True
        assert block["stalled"] is True
        assert block["stall_angle_rad"] == 0.0
    messages = [w.message for w in prediction.warnings if w.method == "exact"]
    # "cannot start: drive torque X < friction Y at T" (issue 14 item 4): drive 0 here.
    assert any(m.startswith("cannot start: drive torque 0 N*m < ") for m in messages), messages
    assert any(f"< friction {f:.4g} N*m at 25 degC" in m for m in messages), messages


def test_undamped_coast_dynamic_matches_the_closed_form_and_quasi_static_says_why() -> None:
    # J x'' = (Ts - F) - k x with k = (Ts - Te) / travel and x the deployed angle, from
    # rest: x(t) = (a/k)(1 - cos(w t)), a = Ts - F, w = sqrt(k/J). It reaches the travel
    # L at t = arccos(1 - k L / a) / w.
    config = parse_config(undamped_config())
    temps = [25.0, 100.0]
    prediction = predict(
        config.system, temps, ["paper", "exact", "dynamic"], config.spec.dynamics()
    )
    document = prediction.to_dict()
    for case, t in zip(document["cases"], temps, strict=True):
        f = hand.fecd(t) + hand.fs(t)  # the friction does not depend on the damping
        a = hand.TS - f
        k = (hand.TS - hand.TE) / hand.TRAVEL
        expected = math.acos(1.0 - k * hand.TRAVEL / a) / math.sqrt(k / J_TOTAL)
        # Closed-form linear segments in ecdsim as well: agreement to rounding.
        assert case["dynamic"]["deployment_time_s"] == pytest.approx(expected, rel=1e-9)
        assert case["damping_rate_Nms_per_rad"] == 0.0
        for method in ("paper", "exact"):
            block = case[method]
            assert block["solved"] is False
            assert block["stalled"] is False
            assert block["deployment_time_s"] is None
            assert block["start_speed_rad_s"] is None
        assert case["difference"] == {"deployment_time_s": None, "relative": None}
    not_solved = [w for w in prediction.warnings if w.code == "not_solved"]
    assert {(w.method, w.temperature_C) for w in not_solved} == {
        (m, t) for m in ("paper", "exact") for t in temps
    }
    assert all("BECD_T is 0" in w.message for w in not_solved)
    # The internal arrays hold no NaN in times or speeds.
    for solution in prediction.solutions.values():
        assert not np.isnan(solution.deployment_time).any()
        assert not np.isnan(solution.start_speed).any()


def test_undamped_case_through_the_cli(tmp_path: Path) -> None:
    config = tmp_path / "undamped.toml"
    config.write_text(undamped_config())
    result = runner.invoke(app, ["deploy", str(config), "-T", "25", "--json"])
    assert result.exit_code == 0, result.output
    case = json.loads(result.stdout)["cases"][0]
    assert case["exact"]["solved"] is False
    plots = tmp_path / "plots"
    table = runner.invoke(app, ["deploy", str(config), "-T", "25", "--plot", str(plots)])
    assert table.exit_code == 0, table.output
    assert "cannot solve the case at 25 degC" in table.output
    assert (plots / "angle_vs_time.png").is_file()


def test_quasi_static_solvers_flag_zero_damping_in_a_batch() -> None:
    # A batch mixing damped and undamped cases: only the undamped ones are unsolved and
    # the damped one keeps its hand-computed exact time.
    from ecdsim.methods import SOLVERS
    from ecdsim.solvers import QuasiStaticProblem

    problem = QuasiStaticProblem(
        angles=np.array([0.0, hand.TRAVEL]),
        torques=np.array([hand.TS, hand.TE]),
        friction=np.array([hand.fecd(25.0) + hand.fs(25.0)] * 2),
        damping_rate=np.array([hand.becd(25.0), 0.0]),
    )
    for name in ("paper", "exact"):
        solution = SOLVERS[name].solve(problem)
        assert solution.solved_mask.tolist() == [True, False]
        assert solution.deployment_time[1] == np.inf
        assert not solution.stalled[1]
    exact = SOLVERS["exact"].solve(problem)
    assert exact.deployment_time[0] == pytest.approx(hand.exact_time(25.0), rel=1e-12)
    path = SOLVERS["exact"].trajectory(problem, [0.0, 1.0, 100.0])
    assert np.all(np.isfinite(path.angle))
    assert path.angle[:, 1].tolist() == [0.0, 0.0, 0.0]


def test_long_plot_titles_are_wrapped_not_cut_off() -> None:
    # The dynamic example's system name plus "ECD torque against speed" is 79 characters,
    # wider than a 7.5 in figure at the default font: it must wrap onto a second line.
    from ecdsim.plotting import plot_title

    system = "CDA Cc-16 test deployment (paper section 6), full dynamics"
    title = plot_title(system, "ECD torque against speed")
    lines = title.split("\n")
    assert len(lines) == 2
    assert all(len(line) <= 70 for line in lines)
    assert " ".join(lines) == f"{system}: ECD torque against speed"


def test_fit_trace_against_a_zero_spring_says_why(tmp_path: Path) -> None:
    # A zero start torque is a valid config, but a trace cannot be fitted against a load
    # that drives nothing: one line per temperature and exit 2, not scipy's traceback.
    config = tmp_path / "no_spring.toml"
    text = (ROOT / "examples" / "paper_cc16.toml").read_text()
    config.write_text(_edit(text, **{'start_torque = "3.73 N*m"': 'start_torque = "0 N*m"'}))
    trace = ROOT / "examples" / "deployment_trace.csv"
    result = runner.invoke(app, ["fit", "trace", str(trace), "--config", str(config)])
    assert result.exit_code == 2
    assert result.exception is None or isinstance(result.exception, SystemExit)
    lines = result.stderr.strip().splitlines()
    # The example trace's rows by temperature (header = row 1): 2-112, 113-174, 175-210.
    assert lines[:3] == [
        f"error: not fitted: {t} degC (rows {rows}): the configuration's load gives no drive "
        "torque, so there is nothing to fit the trace against (is [load] start_torque 0?)"
        for t, rows in (("-40", "2-112"), ("25", "113-174"), ("100", "175-210"))
    ]
