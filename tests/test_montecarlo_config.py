"""The [tolerances] section: parsing, resolution against the config, and clear errors."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from ecdsim.cli.app import app
from ecdsim.config import ConfigError, parse_config
from ecdsim.config.tolerance_schema import TOLERABLE
from ecdsim.dynamics.params import DynamicParameters
from ecdsim.montecarlo import apply
from ecdsim.montecarlo.tolerances import resolve
from tests.conftest import PAPER_CONFIG, ROOT, paper_system

PAPER_TEXT = PAPER_CONFIG.read_text(encoding="utf-8")
EXAMPLE = ROOT / "examples" / "paper_cc16_tolerances.toml"


def config_text(
    quantities: str, settings: str = "", extra: str = "", base: str = PAPER_TEXT
) -> str:
    """The paper example plus a [tolerances] section (settings, quantities, extra tables)."""
    return f"{base}\n[tolerances]\n{settings}\n[tolerances.quantities]\n{quantities}\n{extra}\n"


def write_config(
    folder: Path, quantities: str, settings: str = "", extra: str = "", base: str = PAPER_TEXT
) -> Path:
    path = folder / "study.toml"
    path.write_text(config_text(quantities, settings, extra, base), encoding="utf-8")
    return path


def problems_of(text: str) -> list[str]:
    with pytest.raises(ConfigError) as info:
        resolve(parse_config(text))
    return info.value.problems


def test_the_shipped_example_resolves_to_the_papers_nominal_values() -> None:
    config = parse_config(EXAMPLE.read_text(encoding="utf-8"))
    tolerances = resolve(config)
    by_key = {t.key: t for t in tolerances.tolerances}
    # Nominal values are the paper's section 6 constants, in SI.
    assert by_key["damper.damping_rate"].nominal == pytest.approx(1.3e-4, rel=1e-12)
    assert by_key["load.system_friction.at_0C"].nominal == pytest.approx(0.58, rel=1e-12)
    # "three_sigma = 10 %" of 1.3e-4 is sigma = 1.3e-5 / 3; "plus_minus = 0.04" is absolute.
    assert by_key["damper.damping_rate"].scale == pytest.approx(0.1 * 1.3e-4 / 3.0, rel=1e-12)
    assert by_key["gearbox.damping_fraction"].scale == pytest.approx(0.04, rel=1e-12)
    assert by_key["load.start_torque"].distribution == "normal"
    matrix = np.asarray(tolerances.correlation)
    i, j = tolerances.keys.index("load.start_torque"), tolerances.keys.index("load.end_torque")
    assert matrix[i, j] == matrix[j, i] == 0.8


def test_units_and_percentages_are_converted() -> None:
    text = config_text(
        '"load.travel" = { distribution = "uniform", plus_minus = "1 deg" }\n'
        '"damper.damping_rate" = { distribution = "normal", sigma = "5 percent" }\n'
        '"load.start_torque" = { distribution = "triangular", plus_minus = "100 mN*m" }\n'
        'load.end_torque = { distribution = "normal", sigma = "0.01 N*m" }\n'  # unquoted key
    )
    t = {x.key: x for x in resolve(parse_config(text)).tolerances}
    assert t["load.travel"].scale == pytest.approx(np.pi / 180.0, rel=1e-12)
    assert t["damper.damping_rate"].scale == pytest.approx(0.05 * 1.3e-4, rel=1e-12)
    assert t["load.start_torque"].scale == pytest.approx(0.1, rel=1e-12)
    assert t["load.end_torque"].scale == pytest.approx(0.01, rel=1e-12)


@pytest.mark.parametrize(
    ("quantities", "extra", "expected"),
    [
        (  # unknown key
            '"damper.damping_rat" = { distribution = "normal", sigma = "3 %" }',
            "",
            "tolerances.quantities: 'damper.damping_rat' cannot take a tolerance; expected one of "
            "damper.damping_rate,",
        ),
        (  # wrong dimension: key, value and expected unit
            '"damper.damping_rate" = { distribution = "normal", sigma = "3 N*m" }',
            "",
            "tolerances.quantities.damper.damping_rate.sigma: '3 N*m' has the wrong dimension; "
            "expected a damping rate in N*m*s/rad",
        ),
        (  # no unit on a dimensional quantity
            '"load.start_torque" = { distribution = "uniform", plus_minus = 0.1 }',
            "",
            "tolerances.quantities.load.start_torque.plus_minus: 0.1 has no unit; expected a "
            "torque in N*m",
        ),
        (  # spread not allowed for the distribution
            '"load.start_torque" = { distribution = "uniform", sigma = "0.1 N*m" }',
            "",
            "tolerances.quantities.load.start_torque: a uniform tolerance takes exactly one of "
            "plus_minus (got sigma)",
        ),
        (  # unknown distribution
            '"gearbox.ratio" = { distribution = "lognormal", sigma = 2 }',
            "",
            "tolerances.quantities.gearbox.ratio.distribution = 'lognormal': Input should be "
            "'normal', 'uniform' or 'triangular'",
        ),
        (  # zero spread
            '"load.travel" = { distribution = "normal", sigma = "0 rad" }',
            "",
            "tolerances.quantities.load.travel.sigma: '0 rad' must be > 0",
        ),
        (  # negative percentage
            '"load.travel" = { distribution = "normal", sigma = "-2 %" }',
            "",
            "tolerances.quantities.load.travel.sigma: '-2 %' must be > 0",
        ),
        (  # correlation with a quantity that has no tolerance
            '"load.start_torque" = { distribution = "normal", sigma = "1 %" }',
            '[[tolerances.correlations]]\nquantities = ["load.start_torque", "load.end_torque"]\n'
            "coefficient = 0.5",
            "tolerances: correlations[0]: 'load.end_torque' has no tolerance",
        ),
        (  # correlation coefficient out of range
            '"load.start_torque" = { distribution = "normal", sigma = "1 %" }\n'
            '"load.end_torque" = { distribution = "normal", sigma = "1 %" }',
            '[[tolerances.correlations]]\nquantities = ["load.start_torque", "load.end_torque"]\n'
            "coefficient = 1.5",
            "tolerances.correlations[0].coefficient = 1.5: Input should be less than 1",
        ),
    ],
)
def test_a_bad_tolerance_spec_gets_one_clear_line(
    quantities: str, extra: str, expected: str
) -> None:
    with pytest.raises(ConfigError) as info:
        parse_config(config_text(quantities, extra=extra))
    assert len(info.value.problems) == 1, info.value.problems
    assert info.value.problems[0].startswith(expected), info.value.problems[0]


def test_inconsistent_correlations_are_rejected() -> None:
    # Pairwise 0.9, 0.9 and -0.9 among three quantities is impossible: the matrix has a
    # negative eigenvalue (1 - 0.9 - 0.9 ... by hand: det = 1 - 3*0.81 - 2*0.729 < 0).
    quantities = "\n".join(
        f'"{k}" = {{ distribution = "normal", sigma = "1 %" }}'
        for k in ("load.start_torque", "load.end_torque", "load.travel")
    )
    pairs = [("load.start_torque", "load.end_torque", 0.9), ("load.end_torque", "load.travel", 0.9)]
    pairs.append(("load.start_torque", "load.travel", -0.9))
    extra = "".join(
        f'[[tolerances.correlations]]\nquantities = ["{a}", "{b}"]\ncoefficient = {c}\n'
        for a, b, c in pairs
    )
    with pytest.raises(ConfigError, match="not positive definite"):
        parse_config(config_text(quantities, extra=extra))


def test_sobol_needs_a_power_of_two_chunk() -> None:
    with pytest.raises(ConfigError, match="chunk_size = 1000: sobol sampling needs a power of two"):
        parse_config(
            config_text(
                '"load.travel" = { distribution = "normal", sigma = "1 %" }',
                'sampling = "sobol"\nchunk_size = 1000',
            )
        )


@pytest.mark.parametrize(
    ("quantities", "base_edit", "expected"),
    [
        (  # a normal whose 6-sigma reach crosses zero for a positive quantity
            '"damper.damping_rate" = { distribution = "normal", sigma = "20 %" }',
            None,
            "tolerances.quantities.damper.damping_rate.sigma = '20 %': the normal spread reaches "
            "-2.6e-05 N*m*s/rad (nominal - 6 sigma, nominal 0.00013 N*m*s/rad), but the quantity "
            "must stay > 0",
        ),
        (  # a uniform reaching below zero for a non-negative friction
            '"gearbox.coulomb_friction" = { distribution = "uniform", plus_minus = "1e-3 N*m" }',
            None,
            "tolerances.quantities.gearbox.coulomb_friction.plus_minus = '1e-3 N*m': the uniform "
            "spread reaches -0.00055 N*m",
        ),
        (  # the config gives the gearbox damping as a fraction
            '"gearbox.damping_rate" = { distribution = "normal", sigma = "1e-6 N*m*s/rad" }',
            None,
            "tolerances.quantities.gearbox.damping_rate: not set in this config's [gearbox] "
            "section; this config gives gearbox.damping_fraction instead",
        ),
        (  # a percentage of a configured zero
            '"load.spring_temperature_coefficient" = { distribution = "normal", sigma = "5 %" }',
            None,
            "tolerances.quantities.load.spring_temperature_coefficient.sigma = '5 %': a "
            "percentage of a configured value of 0 is 0; give the spread in 1/K instead",
        ),
        (  # the spring is a table: no start_torque to scatter
            '"load.start_torque" = { distribution = "normal", sigma = "1 %" }',
            (
                'start_torque = "3.73 N*m"\nend_torque = "1.58 N*m"',
                'spring_table = [["0 rad", "3.73 N*m"], ["1.57 rad", "1.58 N*m"]]',
            ),
            "tolerances.quantities.load.start_torque: not set in this config: the tolerance "
            "applies to the linear spring's start_torque and end_torque",
        ),
    ],
)
def test_resolution_problems_name_key_value_and_reason(
    quantities: str, base_edit: tuple[str, str] | None, expected: str
) -> None:
    base = PAPER_TEXT if base_edit is None else PAPER_TEXT.replace(*base_edit)
    assert base_edit is None or base != PAPER_TEXT
    problems = problems_of(config_text(quantities, base=base))
    assert len(problems) == 1, problems
    assert problems[0].startswith(expected), problems[0]


def test_a_config_without_tolerances_is_a_clear_error() -> None:
    assert problems_of(PAPER_TEXT)[0].startswith("tolerances: missing; a Monte Carlo study")


def test_cli_bad_tolerance_exits_2_with_key_value_and_unit(tmp_path: Path) -> None:
    config = write_config(
        tmp_path, '"load.end_torque" = { distribution = "normal", three_sigma = "5 N*m*s" }'
    )
    result = CliRunner().invoke(
        app, ["montecarlo", str(config), "--samples", "10", "--out", str(tmp_path / "out")]
    )
    assert result.exit_code == 2, result.output
    assert result.stderr.splitlines() == [
        f"error: {config}: tolerances.quantities.load.end_torque.three_sigma: '5 N*m*s' has the "
        "wrong dimension; expected a torque in N*m or compatible units, e.g. '3.73 N*m' (or a "
        "percentage of the configured value, e.g. '5 %')"
    ]
    assert "Traceback" not in result.output
    assert not (tmp_path / "out").exists()


def test_every_tolerable_key_maps_onto_the_model() -> None:
    """Each key's model path reaches a field of the paper system (or is a documented 'not set')."""
    dynamics = DynamicParameters(load_inertia=5.0, rotor_inertia=2e-7, static_friction_factor=1.2)
    parameters = apply.Parameters(paper_system(), dynamics)
    reachable: dict[str, float | str] = {}
    for key in TOLERABLE:
        try:
            reachable[key] = apply.nominal(parameters, key)
        except apply.NotTolerable as exc:
            reachable[key] = str(exc)
    # The paper example sets everything except BG as a rate (it gives the fraction).
    assert reachable["gearbox.damping_rate"] == (
        "not set in this config's [gearbox] section; this config gives "
        "gearbox.damping_fraction instead"
    )
    numeric = {k: v for k, v in reachable.items() if not isinstance(v, str)}
    assert numeric == {
        "damper.damping_rate": 1.3e-4,
        "damper.coulomb_friction": 7.9e-4,
        "damper.damping_temperature_coefficient": -0.004,
        "damper.lubrication_friction.slope": -2.12e-6,
        "damper.lubrication_friction.at_0C": 2.2e-4,
        "gearbox.ratio": 380.0,
        "gearbox.damping_fraction": 0.26,
        "gearbox.coulomb_friction": 4.5e-4,
        "load.start_torque": 3.73,
        "load.end_torque": 1.58,
        "load.travel": 1.57,
        "load.spring_temperature_coefficient": 0.0,
        "load.system_friction.slope": -0.0044,
        "load.system_friction.at_0C": 0.58,
        "load.inertia": 5.0,
        "damper.rotor_inertia": 2e-7,
        "gearbox.inertia": 0.0,
        "damper.static_friction_factor": 1.2,
    }
    # Without [load] inertia there are no dynamic parameters to scatter.
    with pytest.raises(apply.NotTolerable, match="the dynamic parameters need \\[load\\] inertia"):
        apply.nominal(apply.Parameters(paper_system()), "load.inertia")


def test_apply_replaces_only_the_named_fields() -> None:
    system = paper_system()
    values = {
        "load.system_friction.at_0C": np.array([0.5, 0.6]),
        "damper.damping_rate": np.array([1.0e-4, 2.0e-4]),
        "load.inertia": np.array([4.0, 6.0]),
    }
    dynamics = DynamicParameters(load_inertia=5.0)
    result = apply.apply(apply.Parameters(system, dynamics), values)
    varied = result.system
    assert result.dynamics is not None
    assert np.asarray(result.dynamics.load_inertia).tolist() == [4.0, 6.0]
    assert result.dynamics.rotor_inertia == 0.0
    assert varied.load.system_friction.at_0c.tolist() == [0.5, 0.6]  # type: ignore[attr-defined]
    assert varied.load.system_friction.slope == -0.0044  # type: ignore[attr-defined]
    assert varied.ecd.damper.damping_rate.tolist() == [1.0e-4, 2.0e-4]  # type: ignore[union-attr]
    assert varied.ecd.damper.coulomb_friction == 7.9e-4
    assert varied.ecd.gearbox == system.ecd.gearbox
    assert system.ecd.damper.damping_rate == 1.3e-4  # the original is untouched
