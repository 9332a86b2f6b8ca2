"""[load] resistive_table (issue 16 item 1): harness and blanket torque against angle.

Checked against hand calculations (a constant resistance is a spring lowered by it;
the torque margin typed out), a tight scipy integration of the quasi-static equation
with the table written here, and the config's refusals.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from ecdsim.cli.app import app
from ecdsim.config import ConfigError, parse_config
from ecdsim.deployment import predict
from ecdsim.montecarlo.apply import NotTolerable, Parameters, nominal
from ecdsim.sizing.margin import MarginSettings, margin_over_travel
from tests import hand, reference

EXAMPLE = Path(__file__).resolve().parent.parent / "examples" / "paper_cc16.toml"
TEXT = EXAMPLE.read_text()
TEMPERATURES = (-40.0, 25.0, 100.0)


def _with_load_lines(*lines: str) -> str:
    anchor = 'travel = "1.57 rad"'
    assert anchor in TEXT
    return TEXT.replace(anchor, "\n".join([anchor, *lines]))


def test_a_constant_resistance_is_the_spring_lowered_by_it() -> None:
    # R = 0.1 N*m everywhere: the net drive is the linear spring from Ts - R to Te - R,
    # whose exact and paper times are the closed forms of tests/hand.py.
    config = parse_config(
        _with_load_lines('resistive_table = [["0 rad", "0.1 N*m"], ["2 rad", "0.1 N*m"]]')
    )
    prediction = predict(config.system, np.array(TEMPERATURES), ("exact", "paper"))
    for i, t in enumerate(TEMPERATURES):
        exact = hand.exact_time(t, ts=hand.TS - 0.1, te=hand.TE - 0.1)
        paper = hand.paper_time(t, ts=hand.TS - 0.1, te=hand.TE - 0.1)
        # 1e-12: the same closed forms in another order of operations
        assert prediction.solutions["exact"].deployment_time[i] == pytest.approx(exact, rel=1e-12)
        assert prediction.solutions["paper"].deployment_time[i] == pytest.approx(paper, rel=1e-12)


def test_a_varying_table_matches_a_tight_integration_of_the_quasi_static_equation() -> None:
    # Rows inside the travel and one beyond it (clipped there), a negative (assisting) row.
    rows = [(0.0, 0.2), (0.5, 0.6), (0.9, -0.1), (1.3, 0.3), (2.0, 0.0)]
    table = ", ".join(f'["{a} rad", "{r} N*m"]' for a, r in rows)
    config = parse_config(_with_load_lines(f"resistive_table = [{table}]"))
    angles = [a for a, _ in rows]
    torques = [r for _, r in rows]
    for t in TEMPERATURES:
        found = predict(config.system, np.array([t]), ("exact",)).solutions["exact"]

        def drive(phi: float) -> float:
            spring = hand.TS + (hand.TE - hand.TS) * phi / hand.TRAVEL
            return spring - float(np.interp(phi, angles, torques))

        expected, _ = reference.deploy(drive, hand.fecd(t) + hand.fs(t), hand.becd(t), 1.57)
        assert expected is not None
        # 1e-8: the reference integrates at rtol 1e-10 over five pieces
        assert float(found.deployment_time[0]) == pytest.approx(expected, rel=1e-8)


def test_the_dynamic_method_sees_the_resistance_too() -> None:
    # Same constant-resistance equivalence through the dynamic method (inertia, end stop):
    # the two configs are one physical system and must give the same deployment time.
    inertia = 'inertia = "2 kg*m^2"'
    resisted = parse_config(
        _with_load_lines(
            inertia, 'resistive_table = [["0 rad", "0.1 N*m"], ["1.57 rad", "0.1 N*m"]]'
        )
    )
    lowered = parse_config(
        _with_load_lines(inertia)
        .replace('start_torque = "3.73 N*m"', 'start_torque = "3.63 N*m"')
        .replace('end_torque = "1.58 N*m"', 'end_torque = "1.48 N*m"')
    )
    temps = np.array(TEMPERATURES)
    a = predict(resisted.system, temps, ("dynamic",), dynamics=resisted.spec.dynamics())
    b = predict(lowered.system, temps, ("dynamic",), dynamics=lowered.spec.dynamics())
    times_a = a.solutions["dynamic"].deployment_time
    times_b = b.solutions["dynamic"].deployment_time
    # 1e-9: one problem stated two ways; the breakpoints differ only by a zero-length piece
    np.testing.assert_allclose(times_a, times_b, rtol=1e-9)


def test_the_resistive_table_has_its_own_energy_term() -> None:
    # Issue 23 item 8: spring_work had included the table's work. A constant R = 0.1 N*m
    # over the whole travel L = 1.57 rad takes R L = 0.157 J (by hand), and the spring
    # gives its own integral, (Ts + Te) L / 2 = (3.73 + 1.58) 1.57 / 2 = 4.16835 J.
    config = parse_config(
        _with_load_lines(
            'inertia = "2 kg*m^2"',
            'resistive_table = [["0 rad", "0.1 N*m"], ["1.57 rad", "0.1 N*m"]]',
        )
    )
    found = predict(config.system, np.array([25.0]), ("dynamic",), dynamics=config.spec.dynamics())
    result = found.solutions["dynamic"].result  # type: ignore[attr-defined]
    assert result.arrived.all()
    energy = result.energy
    assert energy.resistive_work is not None
    # 1e-12: the travel is reached exactly (the end-stop event), the table is constant
    assert float(np.ravel(energy.resistive_work)[0]) == pytest.approx(0.1 * 1.57, rel=1e-12)
    spring = (3.73 + 1.58) * 1.57 / 2.0
    assert float(np.ravel(energy.spring_work)[0]) == pytest.approx(spring, rel=1e-12)


def test_the_torque_margin_counts_the_table_as_its_own_kind() -> None:
    # Two breakpoints, net drive = spring - R; friction F = 1 N*m, no damping speed.
    # By hand, with factor 2 on the table: TM = spring / (F + 2 R) - 1 at each point.
    spring = np.array([3.0, 2.0])
    resist = np.array([0.25, 0.5])
    settings = MarginSettings(factors={"resistive_table": 2.0})
    terms = margin_over_travel(
        np.array([0.0, 1.0]),
        spring - resist,
        ecd_friction=0.6,
        system_friction=0.4,
        damping_rate=10.0,
        stalled=False,
        stall_angle=math.nan,
        settings=settings,
        resistance=resist,
    )
    assert terms.margin[:2].tolist() == pytest.approx([3.0 / 1.5 - 1.0, 2.0 / 2.0 - 1.0])
    assert terms.drive[:2].tolist() == pytest.approx(spring.tolist())
    assert terms.resistive["resistive_table"][:2].tolist() == pytest.approx(resist.tolist())


def test_the_margin_at_a_stall_takes_the_table_at_the_stall_angle() -> None:
    # Stall at 0.5 rad, midway between rows of R = 0.2 and 0.6: R there is 0.4 by hand,
    # and the spring torque there is F + R = 1.4 (net drive equal to the friction).
    terms = margin_over_travel(
        np.array([0.0, 1.0]),
        np.array([2.0, 0.0]),
        ecd_friction=0.5,
        system_friction=0.5,
        damping_rate=10.0,
        stalled=True,
        stall_angle=0.5,
        settings=MarginSettings(),
        resistance=np.array([0.2, 0.6]),
    )
    assert float(terms.drive[-1]) == pytest.approx(1.4)
    assert float(terms.resistive["resistive_table"][-1]) == pytest.approx(0.4)
    assert float(terms.margin[-1]) == pytest.approx(0.0, abs=1e-12)  # 1.4 / 1.4 - 1


def test_monte_carlo_takes_a_tolerance_on_the_table() -> None:
    config = parse_config(
        _with_load_lines('resistive_table = [["0 rad", "0.3 N*m"], ["2 rad", "0.1 N*m"]]')
    )
    assert nominal(Parameters(config.system), "load.resistive_table") == 1.0
    plain = parse_config(TEXT)
    with pytest.raises(NotTolerable, match="resistive_table, which this config does not give"):
        nominal(Parameters(plain.system), "load.resistive_table")


@pytest.mark.parametrize(
    ("table", "message"),
    [
        ('[["0.1 rad", "0.3 N*m"], ["2 rad", "0.1 N*m"]]', "must start at angle 0"),
        ('[["0 rad", "0.3 N*m"], ["0 rad", "0.1 N*m"]]', "strictly increasing"),
        ('[["0 rad", "0.3 N*m"], ["1 rad", "0.1 N*m"]]', "before the travel"),
        ('[["0 rad", "0.3 N*m"]]', "at least two"),
        ('[["0 rad", "0.3 m"], ["2 rad", "0.1 N*m"]]', "N*m"),
    ],
)
def test_bad_tables_are_refused_by_name(table: str, message: str, tmp_path: Path) -> None:
    text = _with_load_lines(f"resistive_table = {table}")
    with pytest.raises(ConfigError, match="resistive_table") as caught:
        parse_config(text)
    assert message in str(caught.value)
    path = tmp_path / "bad.toml"
    path.write_text(text)
    result = CliRunner().invoke(app, ["deploy", str(path)])
    assert result.exit_code == 2
    assert "Traceback" not in result.output


@pytest.mark.parametrize(
    "name", ["paper_cc16.toml", "paper_cc16_dynamic.toml", "paper_cc16_tolerances.toml"]
)
def test_a_zero_table_changes_nothing_in_the_shipped_examples(name: str) -> None:
    # Omitting the key and giving an all-zero table are the same physics: every method's
    # times and speeds agree, so adding the key cannot have moved today's results.
    text = (EXAMPLE.parent / name).read_text()
    travel_line = next(line for line in text.splitlines() if line.startswith("travel ="))
    zero = 'resistive_table = [["0 rad", "0 N*m"], ["1 rad", "0 N*m"], ["10 rad", "0 N*m"]]'
    plain = parse_config(text)
    zeroed = parse_config(text.replace(travel_line, f"{travel_line}\n{zero}", 1))
    dynamics = plain.spec.dynamics()
    methods = ("paper", "exact", "dynamic") if dynamics is not None else ("paper", "exact")
    temps = np.array(plain.temperatures)
    a = predict(plain.system, temps, methods, dynamics=dynamics)
    b = predict(zeroed.system, temps, methods, dynamics=zeroed.spec.dynamics())
    for method in methods:
        for field in ("deployment_time", "end_speed"):
            # 1e-12: the zero table only adds breakpoints (pieces of the same line)
            np.testing.assert_allclose(
                getattr(b.solutions[method], field),
                getattr(a.solutions[method], field),
                rtol=1e-12,
                err_msg=f"{name} {method} {field}",
            )
