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
from ecdsim.invocation import pip_install
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
    assert message.endswith(f"install it with: {pip_install('montecarlo')}")  # ecdsim.invocation
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
        ] == pytest.approx(t["damping_rate_ci95_Nms_per_rad"], 1e-12)
    assert len(result.plot()) == 3
    with pytest.raises(ConfigError, match=r"noise: 'loud' is not one of \['torque', 'timing'\]"):
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
    import hashlib

    import numpy as np
    import pyarrow.parquet as pq

    out = tmp_path / "study"
    config = ROOT / "examples" / "paper_cc16_tolerances.toml"
    run = CliRunner().invoke(
        app, ["montecarlo", str(config), "--samples", "300", "--out", str(out), "--seed", "1"]
    )
    assert run.exit_code == 0, run.output
    temps = [-40.0, 25.0, 100.0]
    # Long (tidy): one row per (sample, temperature), temperature a column, units in names.
    frame = ecdsim.montecarlo.open(out)
    assert len(frame) == 300 * 3
    assert list(frame["sample"][:6]) == [0, 0, 0, 1, 1, 1]
    assert list(frame["temperature_C"][:3]) == temps
    for column in (
        "damper.damping_rate_Nms_per_rad",
        "load.start_torque_Nm",
        "gearbox.damping_fraction",
        "deployment_time_s",
        "end_speed_rad_s",
    ):
        assert column in frame.columns
    assert not any("@" in c for c in frame.columns)
    assert frame["stalled"].dtype == bool
    # The same numbers as the stored (wide) chunk columns.
    stored = ecdsim.montecarlo.open(out, as_="arrow").to_table().to_pandas()
    assert stored.shape[0] == 300
    for t in temps:
        mine = frame[frame["temperature_C"] == t].set_index("sample")
        assert np.array_equal(
            mine["deployment_time_s"].to_numpy(), stored[f"deployment_time_s@{t!r}C"].to_numpy()
        )
        assert np.array_equal(
            mine["damper.damping_rate_Nms_per_rad"].to_numpy(),
            stored["damper.damping_rate"].to_numpy(),
        )
    # The summary's P50 is the ceil(0.5 N)-th smallest time (docs/montecarlo.md).
    summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    for case in summary["cases"]:
        times = np.sort(
            frame.loc[
                frame["temperature_C"] == case["temperature_C"], "deployment_time_s"
            ].to_numpy()
        )
        p50 = case["deployment_time_s"]["percentiles"]["P50"]["value"]
        assert p50 == times[math.ceil(0.5 * 300) - 1]
    assert frame.attrs["config_sha256"] == hashlib.sha256(config.read_bytes()).hexdigest()

    # xarray: sample x temperature, units as attributes.
    data = ecdsim.montecarlo.open(out, as_="xarray")
    assert dict(data.sizes) == {"sample": 300, "temperature_C": 3}
    assert list(data["temperature_C"].values) == temps
    assert data["deployment_time_s"].dims == ("sample", "temperature_C")
    assert data["deployment_time_s"].attrs["units"] == "s"
    assert data["end_speed_rad_s"].attrs["units"] == "rad/s"
    assert data["damper.damping_rate_Nms_per_rad"].attrs["units"] == "N*m*s/rad"
    assert data["gearbox.damping_fraction"].attrs["units"] == "1"
    assert data["temperature_C"].attrs["units"] == "degC"
    assert np.array_equal(
        data["deployment_time_s"].sel(temperature_C=25.0).values,
        stored["deployment_time_s@25.0C"].to_numpy(),
    )
    assert data.attrs["method"] == "exact"
    assert data.attrs["seed"] == 1

    # The chunk files carry each column's unit, the config's hash and the version.
    chunk = pq.read_schema(out / "chunks" / "chunk-000000.parquet")
    assert chunk.field("load.start_torque").metadata == {b"unit": b"N*m"}
    assert chunk.field("deployment_time_s@-40.0C").metadata == {b"unit": b"s"}
    tag = json.loads(chunk.metadata[b"ecdsim.montecarlo"])
    assert tag["ecdsim_version"] == ecdsim.__version__
    assert tag["config_sha256"] == hashlib.sha256(config.read_bytes()).hexdigest()
    assert tag["units"]["gearbox.damping_fraction"] == "1"

    from ecdsim.montecarlo import NotAStudy

    with pytest.raises(ValueError, match=r"as_ = 'polars': expected one of \['pandas'"):
        ecdsim.montecarlo.open(out, as_="polars")
    with pytest.raises(NotAStudy, match="no manifest"):
        ecdsim.montecarlo.open(tmp_path)
    manifest = (out / "manifest.json").read_text(encoding="utf-8")
    for bad in ("[]", "[" * 100_000, '{"format": "ecdsim-montecarlo/1"}'):
        (out / "manifest.json").write_text(bad, encoding="utf-8")
        with pytest.raises(NotAStudy):
            ecdsim.montecarlo.open(out)
    (out / "manifest.json").write_text(manifest, encoding="utf-8")
    (out / "summary.json").unlink()
    with pytest.raises(NotAStudy, match="not finished"):
        ecdsim.montecarlo.open(out)


# ----------------------------------------------------------------------- issue 27 item 5


DYNAMIC = ROOT / "examples" / "paper_cc16_dynamic.toml"


def test_results_have_a_short_repr() -> None:
    result = ecdsim.deploy(DYNAMIC)
    text = repr(result)
    # One line that says what it holds (it was the dataclass repr: 12 kB of arrays).
    assert len(text) < 400
    assert "\n" not in text
    assert "CDA Cc-16" in text
    assert "[-40, 25, 100] degC" in text
    assert f"exact [{hand.exact_time(-40.0):.4g} s" in text
    assert "0 warnings" in text
    fitted = ecdsim.fit(ROOT / "examples" / "drop_test.csv")
    assert len(repr(fitted)) < 400
    assert "3 temperatures" in repr(fitted)
    sized = ecdsim.size(ROOT / "examples" / "sizing.toml", ROOT / "examples" / "catalogue.toml")
    assert len(repr(sized)) < 400
    assert repr(sized).startswith("<SizeResults ")
    swept = ecdsim.sweep(PAPER, {"gearbox.ratio": [300, 400]}, temperatures=25)
    assert repr(swept).endswith("2 points of [gearbox.ratio], 4 rows, 0 point errors>")


def test_plot_on_given_axes() -> None:
    from matplotlib.figure import Figure

    result = ecdsim.deploy(PAPER, temperatures=[-40, 25])
    figure = Figure()
    left, right = figure.subplots(1, 2)
    assert result.plot(ax=left) is left
    assert result.plot(ax=right, kind="torque_speed", units="us") is right
    # One line per (method, temperature) of the angle; the axes keep their labels.
    assert len(left.get_lines()) == 2 * 2
    assert left.get_xlabel() == "time since release [s]"
    assert "lbf*in" in right.get_ylabel()
    with pytest.raises(ecdsim.api.UnknownNameError, match=r"kind: 'torque' is not one of"):
        result.plot(ax=left, kind="torque")


def test_numpy_numbers_are_accepted() -> None:
    import numpy as np

    plain = ecdsim.deploy(PAPER, temperatures=[-40, 25], overrides={"gearbox.ratio": 400})
    for ratio in (np.int64(400), np.int32(400), np.float64(400.0), np.array(400)):
        numpy = ecdsim.deploy(
            PAPER, temperatures=np.array([-40, 25]), overrides={"gearbox.ratio": ratio}
        )
        assert numpy.deployment_time() == plain.deployment_time()
    assert list(ecdsim.deploy(PAPER, temperatures=np.int64(25)).deployment_time()) == [25.0]


def test_temperatures_are_converted_exactly() -> None:
    # degC = (degF - 32) * 5/9 and degC = K - 273.15, by hand: -40 degF = -40 degC,
    # 77 degF = 25 degC, 298.15 K = 25 degC, 491.67 degR = 0 degC. pint's path through
    # kelvin gave -39.99999999999997 and 25.000000000000057.
    cases = {"-40 degF": -40.0, "77 degF": 25.0, "298.15 K": 25.0, "491.67 degR": 0.0}
    for text, celsius in cases.items():
        assert list(ecdsim.deploy(PAPER, temperatures=text).deployment_time()) == [celsius]
    quantities = U.Quantity([-40.0, 77.0], "degF")
    assert list(ecdsim.deploy(PAPER, temperatures=quantities).deployment_time()) == [-40.0, 25.0]
    # The same conversion at every edge: the command line and the config file.
    run = CliRunner().invoke(app, ["deploy", str(PAPER), "-T", "77 degF", "--json"])
    assert json.loads(run.stdout)["cases"][0]["temperature_C"] == 25.0
    config = ecdsim.load(PAPER, overrides={"analysis.temperatures": ["-40 degF", "212 degF"]})
    assert config.temperatures == (-40.0, 100.0)
    # 300 K: the double nearest to 26.85, not 26.850000000000023.
    assert list(ecdsim.deploy(PAPER, temperatures="300 K").deployment_time()) == [26.85]


def test_unknown_names_raise_value_errors_naming_the_choices() -> None:
    result = ecdsim.deploy(PAPER, temperatures=25)
    with pytest.raises(ValueError, match=r"method: 'rk4' is not one of \['paper', 'exact'\]"):
        result.deployment_time("rk4")
    with pytest.raises(ValueError, match=r"method: 'dynamic' is not one of"):
        result.flight_deployment_time("dynamic")
    with pytest.raises(ValueError, match=r"units: 'imperial' is not a unit system; expected 'si'"):
        result.plot(units="imperial")  # type: ignore[call-overload]
    with pytest.raises(ConfigError, match=r"methods: \['exact'\] is not a method; expected"):
        ecdsim.deploy(PAPER, methods=[["exact"]])  # type: ignore[list-item]
    with pytest.raises(ConfigError, match=r"methods: 3 is not a method"):
        ecdsim.deploy(PAPER, methods=3)  # type: ignore[arg-type]
    swept = ecdsim.sweep(PAPER, {"gearbox.ratio": [300, 400]}, temperatures=25)
    with pytest.raises(ValueError, match=r"output: 'time' is not one of \['point'"):
        swept.plot("time")


def test_nested_overrides_merge_into_their_table() -> None:
    dotted = ecdsim.deploy(
        PAPER,
        temperatures=25,
        overrides={"gearbox.ratio": 400, "load.system_friction.at_0C": "0.5 N*m"},
    )
    nested = ecdsim.deploy(
        PAPER,
        temperatures=25,
        overrides={"gearbox": {"ratio": 400}, "load": {"system_friction": {"at_0C": "0.5 N*m"}}},
    )
    assert nested.deployment_time() == dotted.deployment_time()
    # None removes a key: a required one is then missing, by name.
    with pytest.raises(ConfigError, match="gearbox.coulomb_friction: missing"):
        ecdsim.load(PAPER, overrides={"gearbox": {"coulomb_friction": None}})
    # The table's other keys are kept (the gearbox's friction, the law's slope).
    assert nested.config.spec.gearbox.coulomb_friction == pytest.approx(4.5e-4, rel=1e-15)
    assert nested.prediction.problem.friction.ravel()[0] == pytest.approx(
        hand.fecd(25.0) * 400 / 380 + (-0.0044 * 25 + 0.5), rel=1e-12
    )


@pytest.mark.parametrize(
    ("overrides", "needle"),
    [
        ({1: 2}, r"overrides: key 1 is not a config key; expected a dotted name"),
        ({"gearbox": {2: 3}}, r"overrides: key 2 in gearbox is not a config key"),
        ("gearbox.ratio=3", r"overrides = 'gearbox.ratio=3': expected a mapping"),
        ({"gearbox.ratio": "abc"}, r"gearbox.ratio: 'abc' does not start with a finite number"),
    ],
)
def test_bad_overrides_are_config_errors(overrides: Any, needle: str) -> None:
    with pytest.raises(ConfigError, match=needle):
        ecdsim.deploy(PAPER, temperatures=25, overrides=overrides)


def test_deeply_nested_overrides_are_refused_without_recursion() -> None:
    deep: dict[str, Any] = {}
    node = deep
    for _ in range(5000):
        node["a"] = {}
        node = node["a"]
    with pytest.raises(ConfigError, match=r"nested deeper than 32 levels"):
        ecdsim.deploy(PAPER, temperatures=25, overrides=deep)


def test_fit_takes_a_dataframe() -> None:
    import pandas

    csv = ROOT / "examples" / "drop_test.csv"
    from_file = ecdsim.fit(csv).to_dataframe()
    fitted = ecdsim.fit(pandas.read_csv(csv))
    # The same rows through the same reader: the same numbers, to the last bit.
    assert fitted.to_dataframe().equals(from_file)
    assert fitted.result.table.source == "<DataFrame>"
    broken = pandas.read_csv(csv).drop(columns=["mass [g]"])
    with pytest.raises(ConfigError, match="<DataFrame>: .*mass"):
        ecdsim.fit(broken)
    with pytest.raises(ConfigError, match="expected a CSV path or a pandas DataFrame"):
        ecdsim.fit(42)


# ----------------------------------------------------------------------- issue 27 item 4


def test_dataframe_types_hold_for_columns_only_some_methods_have() -> None:
    frame = ecdsim.deploy(DYNAMIC).to_dataframe()
    assert str(frame["stuck"].dtype) == "boolean"
    assert str(frame["impacts"].dtype) == "Int64"
    assert str(frame["stalled"].dtype) == "boolean"
    assert str(frame["method"].dtype) == "string"
    paper = frame[frame["method"] == "paper"]
    dynamic = frame[frame["method"] == "dynamic"]
    assert paper["stuck"].isna().all()
    assert paper["impacts"].isna().all()
    assert not dynamic["stuck"].isna().any()
    assert (dynamic["impacts"] >= 0).all()
    # The JSON's energy_J object flattened, the unit kept last.
    document = ecdsim.deploy(DYNAMIC).prediction.to_dict()
    energy = document["cases"][1]["dynamic"]["energy_J"]
    row = dynamic[dynamic["temperature_C"] == 25.0].iloc[0]
    assert row["energy_spring_work_J"] == energy["spring_work"]
    assert row["energy_damper_dissipation_J"] == energy["damper_dissipation"]


def test_timeseries_is_long_and_matches_the_exact_solution() -> None:
    import numpy as np

    result = ecdsim.deploy(PAPER, temperatures=[-40, 25])
    frame = result.timeseries(n_points=50)
    assert list(frame.columns) == ["temperature_C", "method", "time_s", "angle_rad", "speed_rad_s"]
    assert len(frame) == 2 * 2 * 50
    assert list(frame["method"][:51:50]) == ["paper", "exact"]
    for t in (-40.0, 25.0):
        exact = frame[(frame["temperature_C"] == t) & (frame["method"] == "exact")]
        # B dphi/dt = a - k phi  =>  phi(t) = (a/k)(1 - exp(-k t / B)) before the latch
        # (tests/hand.py's exact solution, written as the angle).
        a = hand.TS - hand.fecd(t) - hand.fs(t)
        k = (hand.TS - hand.TE) / hand.TRAVEL
        moving = exact[exact["time_s"] < hand.exact_time(t)]
        expected = a / k * (1.0 - np.exp(-k * moving["time_s"].to_numpy() / hand.becd(t)))
        # A closed form evaluated two ways: rounding only.
        assert moving["angle_rad"].to_numpy() == pytest.approx(expected, rel=1e-10, abs=1e-12)
        assert moving["speed_rad_s"].iloc[0] == pytest.approx(a / hand.becd(t), rel=1e-12)
        after = exact[exact["time_s"] > hand.exact_time(t)]
        assert after["angle_rad"].to_numpy() == pytest.approx(hand.TRAVEL, rel=1e-12)
    times = result.timeseries(times=[0.0, 1.0])
    assert list(times["time_s"]) == [0.0, 1.0] * 4
    with pytest.raises(ConfigError, match="times: expected one or more finite times"):
        result.timeseries(times=[-1.0])


def test_sweep_api_matches_deploy_and_the_command_line(tmp_path: Path) -> None:
    import csv
    import io

    swept = ecdsim.sweep(
        PAPER,
        {"gearbox.ratio": [300, 380], "load.start_torque": U.Quantity([3.2, 3.73], "N*m")},
        temperatures=[-40, 25],
        methods="exact",
    )
    frame = swept.to_dataframe()
    assert list(frame.columns[:5]) == [
        "point",
        "gearbox.ratio",
        "load.start_torque_Nm",
        "temperature_C",
        "method",
    ]
    assert len(frame) == 4 * 2
    row = frame[(frame["gearbox.ratio"] == 380.0) & (frame["load.start_torque_Nm"] == 3.73)]
    for t in (-40.0, 25.0):
        time = row.loc[row["temperature_C"] == t, "deployment_time_s"].item()
        assert time == pytest.approx(hand.exact_time(t), rel=1e-12)
    # The command line writes the same table.
    out = tmp_path / "s.csv"
    run = CliRunner().invoke(
        app,
        [
            "sweep",
            str(PAPER),
            "--vary",
            "gearbox.ratio=300,380",
            "--vary",
            "load.start_torque=3.2,3.73",
            "-T",
            "-40",
            "-T",
            "25",
            "-m",
            "exact",
            "-o",
            str(out),
        ],
    )
    assert run.exit_code == 0, run.output
    rows = list(csv.DictReader(io.StringIO(out.read_text(encoding="utf-8"))))
    assert [float(r["deployment_time_s"]) for r in rows] == list(frame["deployment_time_s"])
    # The command line's strings work too, and a Latin hypercube repeats with its seed.
    latin = ecdsim.sweep(PAPER, ["gearbox.ratio=300:400:2"], latin=5, seed=3, temperatures=25)
    again = ecdsim.sweep(PAPER, ["gearbox.ratio=300:400:2"], latin=5, seed=3, temperatures=25)
    assert latin.to_dataframe().equals(again.to_dataframe())
    with pytest.raises(ConfigError, match=r"seed = -1: expected an integer >= 0"):
        ecdsim.sweep(PAPER, ["gearbox.ratio=300:400:2"], latin=5, seed=-1)
    with pytest.raises(ConfigError, match=r"vary gearbox.ratio: the count 'x'"):
        ecdsim.sweep(PAPER, {"gearbox.ratio": "300:400:x"})


def test_sweep_parquet_carries_units_hash_and_version(tmp_path: Path) -> None:
    import hashlib

    import pyarrow.parquet as pq

    out = tmp_path / "s.parquet"
    run = CliRunner().invoke(
        app,
        [
            "sweep",
            str(DYNAMIC),
            "--vary",
            "gearbox.ratio=300,380",
            "--vary",
            "load.start_torque=3.2,3.73",
            "-T",
            "25",
            "-o",
            str(out),
        ],
    )
    assert run.exit_code == 0, run.output
    schema = pq.read_schema(out)
    meta = json.loads(schema.metadata[b"ecdsim"])
    assert meta["config_sha256"] == hashlib.sha256(DYNAMIC.read_bytes()).hexdigest()
    assert meta["ecdsim_version"] == ecdsim.__version__
    assert meta["units"]["load.start_torque_Nm"] == "N*m"
    assert meta["units"]["gearbox.ratio"] == "1"
    assert meta["units"]["damping_rate_Nms_per_rad"] == "N*m*s/rad"
    assert schema.field("deployment_time_s").metadata == {b"unit": b"s"}
    assert schema.field("temperature_C").metadata == {b"unit": b"degC"}
    frame = pq.read_table(out).to_pandas()
    # Nullable types survive the file: no object column of bools and NaN.
    assert str(frame["stuck"].dtype) == "boolean"
    assert str(frame["impacts"].dtype) == "Int64"
