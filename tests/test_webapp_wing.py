"""The explorer's wing endpoint (POST /api/wing) and the geometry its animation draws.

The animation's frames are checked against the example wing's geometry derived by hand
(its panel lengths and hinge angles, below), its result against ``ecdsim deploy
WING.toml --json`` run on the same file, and the outlines against the function the CLI's
shape strip draws (one source).
"""

from __future__ import annotations

import json
import math
import tomllib
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from fastapi.testclient import TestClient
from typer.testing import CliRunner

from ecdsim.cli.app import app as cli
from ecdsim.config.wing_schema import load_wing_config, parse_wing_config
from ecdsim.sizing.catalogue import load_catalogue
from ecdsim.webapp.server import create_app
from ecdsim.webapp.wingapi import MAX_FRAMES, WING_REFUSAL, frame_indices
from tests.conftest import PAPER_CONFIG, ROOT

WING_FILE = ROOT / "examples" / "wing_cc16_three_panel.toml"
runner = CliRunner()

# The example wing by hand (examples/wing_cc16_three_panel.toml): three panels of 0.5 m
# hinge to hinge, 20 mm thick. The pictures draw every panel max(2.5 % of the wing's
# 1.5 m, 20 mm) = 37.5 mm thick, so each outline runs 18.75 mm either side of its hinge
# line. Stowed, the relative angles are 90, -180 and 180 deg, so the panels' absolute
# angles are 90, -90 and 90 deg: panel 1 runs from the root (0, 0) up to (0, 0.5),
# panel 2 back down to (0, 0), panel 3 up again to (0, 0.5). Deployed, every relative
# angle is 0: the panels lie end to end along +x.
LENGTH = 0.5
HALF = 0.5 * max(0.025 * 1.5, 0.020)
STOWED_ABSOLUTE_DEG = (90.0, -90.0, 90.0)
STOWED_HINGES = ((0.0, 0.0), (0.0, 0.5), (0.0, 0.0))
DEPLOYED_HINGES = ((0.0, 0.0), (0.5, 0.0), (1.0, 0.0))
# Geometry from cos and sin of whole multiples of 90 deg: exact to a few ulp of 1 m.
GEOMETRY_ABS = 1e-12


def _rectangle(start: tuple[float, float], absolute_deg: float) -> list[list[float]]:
    """A panel's outline by hand: from its inboard hinge along e = (cos, sin) of its
    absolute angle for LENGTH, HALF either side along n = e turned +90 deg; corners
    start - h n, end - h n, end + h n, start + h n (docs/wing.md's convention)."""
    a = math.radians(absolute_deg)
    e = (round(math.cos(a)), round(math.sin(a)))  # a multiple of 90 deg: exactly 0 or 1
    n = (-e[1], e[0])
    x0, y0 = start
    x1, y1 = x0 + LENGTH * e[0], y0 + LENGTH * e[1]
    return [
        [x0 - HALF * n[0], y0 - HALF * n[1]],
        [x1 - HALF * n[0], y1 - HALF * n[1]],
        [x1 + HALF * n[0], y1 + HALF * n[1]],
        [x0 + HALF * n[0], y0 + HALF * n[1]],
    ]


STOWED = [_rectangle(p, a) for p, a in zip(STOWED_HINGES, STOWED_ABSOLUTE_DEG, strict=True)]
DEPLOYED = [_rectangle(p, 0.0) for p in DEPLOYED_HINGES]


def warm_wing_kernel() -> None:
    """Compile (or load from numba's cache) the wing's kernel in this process first: on a
    clean clone the first wing run compiles it, which on a loaded 2-core machine takes
    longer than the explorer's 60 s limit on a request (the worker would answer 503)."""
    from ecdsim.api import deploy_wing

    deploy_wing(WING_FILE, temperatures=25)


@pytest.fixture(scope="module")
def client() -> TestClient:
    warm_wing_kernel()
    return TestClient(create_app(host="testserver"), base_url="http://localhost")


@pytest.fixture(scope="module")
def wing_raw() -> dict[str, Any]:
    return tomllib.loads(WING_FILE.read_text(encoding="utf-8"))


@pytest.fixture(scope="module")
def answer(client: TestClient, wing_raw: dict[str, Any]) -> dict[str, Any]:
    response = client.post("/api/wing", json={"config": wing_raw})
    assert response.status_code == 200, response.text
    body: dict[str, Any] = response.json()
    return body


def test_stowed_and_deployed_outlines_are_the_hand_geometry(answer: dict[str, Any]) -> None:
    np.testing.assert_allclose(answer["stowed_outlines_m"], STOWED, rtol=0, atol=GEOMETRY_ABS)
    np.testing.assert_allclose(answer["deployed_outlines_m"], DEPLOYED, rtol=0, atol=GEOMETRY_ABS)
    assert answer["panels"] == ["inboard panel", "middle panel", "outer panel"]
    assert answer["hinges"] == ["root", "middle", "outer"]
    assert answer["extent_m"] == pytest.approx(1.5, rel=1e-15)
    np.testing.assert_allclose(answer["travel_rad"], [math.pi / 2, math.pi, math.pi], rtol=1e-15)


def test_frames_start_stowed_and_end_deployed(answer: dict[str, Any]) -> None:
    """Every temperature's first frame is the stowed wing (release, every angle 0) and its
    last the deployed one (every hinge latched at its travel: each case of the example
    latches)."""
    assert [c["temperature_C"] for c in answer["cases"]] == [-40.0, 25.0, 100.0]
    for case, result in zip(answer["cases"], answer["result"]["cases"], strict=True):
        assert result["status"] == "latched"
        frames = case["outlines_m"]
        assert len(frames) == len(case["time_s"]) == len(case["angle_rad"][0])
        assert case["time_s"][0] == 0.0
        np.testing.assert_allclose(frames[0], STOWED, rtol=0, atol=GEOMETRY_ABS)
        # A rigid latch holds its hinge exactly at the travel: the last angles are the
        # travels to rounding, and the outline to the same few ulp.
        np.testing.assert_allclose(frames[-1], DEPLOYED, rtol=0, atol=1e-9)
        # Somewhere between, the wing is neither: the frames move.
        middle = frames[len(frames) // 2]
        assert np.max(np.abs(np.subtract(middle, STOWED))) > 0.1
        assert np.max(np.abs(np.subtract(middle, DEPLOYED))) > 0.1


def test_frames_are_the_solutions_own_samples(answer: dict[str, Any]) -> None:
    """The frames' times and angles are the solver's samples (the notebook API's series),
    none interpolated: the example has fewer samples than MAX_FRAMES, so all of them."""
    from ecdsim.api import deploy_wing

    result = deploy_wing(WING_FILE).to_dict(series=True)
    for case, solved in zip(answer["cases"], result["cases"], strict=True):
        series = solved["series"]
        assert len(series["time_s"]) <= MAX_FRAMES
        assert case["time_s"] == series["time_s"]
        for j, name in enumerate(answer["hinges"]):
            assert case["angle_rad"][j] == series["angle_rad"][name]


def test_each_frame_is_the_shape_strips_outline(answer: dict[str, Any]) -> None:
    """One source: a frame's outlines are what the CLI's shape strip (--plot) draws at the
    same angles; the strip's first instant (t = 0) is drawn as the stowed frame."""
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.patches import Polygon

    from ecdsim.plotting_wing import drawn_outlines, plot_wing_shapes
    from ecdsim.wing.solver import deploy_wing

    config = load_wing_config(WING_FILE, read_catalogue=load_catalogue)
    case = answer["cases"][1]
    k = len(case["time_s"]) // 3
    angles = np.array([case["angle_rad"][j][k] for j in range(3)])
    np.testing.assert_allclose(
        drawn_outlines(config.wing, angles), case["outlines_m"][k], rtol=0, atol=1e-15
    )
    result = deploy_wing(config.wing, [25.0])
    figure = plot_wing_shapes(config.wing, result, 25.0, times=[0.0])
    drawn = sorted(
        (p for p in figure.axes[0].patches if isinstance(p, Polygon) and p.get_gid()),
        key=lambda p: str(p.get_gid()),
    )
    assert [p.get_gid() for p in drawn] == ["panel 1", "panel 2", "panel 3"]
    for patch, outline in zip(drawn, case["outlines_m"][0], strict=True):
        np.testing.assert_allclose(patch.get_xy()[:4], outline, rtol=0, atol=1e-15)


def test_the_result_is_the_clis_json(answer: dict[str, Any], wing_raw: dict[str, Any]) -> None:
    """``result`` is ``ecdsim deploy WING.toml --json`` on the same file (the same solver
    and inputs on this machine: equal)."""
    run = runner.invoke(cli, ["deploy", str(WING_FILE), "--json"])
    assert run.exit_code == 0, run.output
    assert answer["result"] == json.loads(run.stdout)
    # The TOML the page exports reads back to the same wing.
    assert (
        parse_wing_config(answer["toml"], "x").wing
        == parse_wing_config(WING_FILE.read_text(encoding="utf-8"), "y").wing
    )


def test_units_follow_the_display_system(client: TestClient, wing_raw: dict[str, Any]) -> None:
    response = client.post("/api/wing", json={"config": wing_raw, "units": "us"})
    assert response.status_code == 200, response.text
    body = response.json()
    assert body["display_units"] == "us"
    # 1 in = 0.0254 m exactly; a temperature in degF is 9/5 degC + 32.
    assert body["units"]["length"]["scale"] == pytest.approx(1 / 0.0254, rel=1e-15)
    assert body["units"]["temperature"] == {"unit": "degF", "scale": 1.8, "offset": 32.0}
    assert body["key_units"]["outlines_m"] == "in"
    assert body["key_units"]["kinetic_energy_J"] == "in*lbf"


def test_a_wing_is_refused_by_the_single_hinge_endpoints_with_one_line(
    client: TestClient, wing_raw: dict[str, Any]
) -> None:
    response = client.post("/api/deploy", json={"config": wing_raw})
    assert response.status_code == 422
    assert response.json() == {"errors": [WING_REFUSAL]}


def test_the_report_of_a_wing_is_the_wing_report(
    client: TestClient, wing_raw: dict[str, Any], answer: dict[str, Any]
) -> None:
    """``/api/report`` with a wing file: the wing's report (ecdsim report WING.toml), in
    the request's units, its embedded results those of ``/api/wing``."""
    import re

    response = client.post("/api/report", json={"config": wing_raw, "units": "us"})
    assert response.status_code == 200, response.text
    assert response.headers["content-type"].startswith("text/html")
    html = response.text
    found = re.search(r'<script type="application/json" id="ecdsim-data">(.*?)</script>', html)
    assert found is not None
    embedded = json.loads(found.group(1).replace("<\\/", "</"))["wing"]
    assert embedded.pop("display_units") == "us"
    assert embedded == answer["result"]
    assert "degF" in html


def test_wing_files_are_parsed_and_exported(client: TestClient, wing_raw: dict[str, Any]) -> None:
    text = WING_FILE.read_text(encoding="utf-8")
    parsed = client.post("/api/config/parse", json={"toml": text})
    assert parsed.status_code == 200, parsed.text
    assert parsed.json()["config"] == wing_raw
    exported = client.post("/api/config.toml", json={"config": wing_raw})
    assert exported.status_code == 200
    assert tomllib.loads(exported.text) == wing_raw


def test_bad_wing_input_names_the_field(client: TestClient, wing_raw: dict[str, Any]) -> None:
    bad = json.loads(json.dumps(wing_raw))
    bad["wing"]["panels"][1]["length"] = "-0.5 m"
    response = client.post("/api/wing", json={"config": bad})
    assert response.status_code == 422
    (line,) = response.json()["errors"]
    assert line.startswith("config: wing.panels[1].length: '-0.5 m'"), line
    exported = client.post("/api/config.toml", json={"config": bad})
    assert exported.status_code == 422
    single = tomllib.loads(PAPER_CONFIG.read_text(encoding="utf-8"))
    response = client.post("/api/wing", json={"config": single})
    assert response.status_code == 422
    assert "config: wing: missing" in response.json()["errors"]


def test_frame_indices_thin_evenly_and_keep_both_ends() -> None:
    chosen = frame_indices(5000, MAX_FRAMES)
    assert chosen[0] == 0
    assert chosen[-1] == 4999
    assert len(chosen) == MAX_FRAMES
    steps = np.diff(chosen)
    # 4999 / 599 = 8.35 samples apart, rounded to whole samples: 8 or 9.
    assert steps.min() >= 8
    assert steps.max() <= 9
    assert frame_indices(MAX_FRAMES) == list(range(MAX_FRAMES))


def test_many_temperatures_get_fewer_frames_each(
    client: TestClient, wing_raw: dict[str, Any]
) -> None:
    """3000 frames in all: ten temperatures get 300 frames each, every one a sample of the
    solution (the first and last kept); 51 temperatures are refused, as for a hinge."""
    config = json.loads(json.dumps(wing_raw))
    config["analysis"]["temperatures"] = [f"{t} degC" for t in range(-40, 60, 10)]
    response = client.post("/api/wing", json={"config": config})
    assert response.status_code == 200, response.text
    body = response.json()
    from ecdsim.api import deploy_wing

    solved = deploy_wing(WING_FILE, temperatures=[-40]).to_dict(series=True)["cases"][0]
    first = body["cases"][0]
    assert len(first["time_s"]) == 300
    assert set(first["time_s"]) <= set(solved["series"]["time_s"])
    assert first["time_s"][0] == 0.0
    assert first["time_s"][-1] == solved["series"]["time_s"][-1]
    config["analysis"]["temperatures"] = [f"{t} degC" for t in range(51)]
    response = client.post("/api/wing", json={"config": config})
    assert response.status_code == 422
    assert response.json() == {"errors": ["analysis.temperatures: 51 given; at most 50"]}


def test_app_refuses_a_bad_wing_file_in_one_line(tmp_path: Path) -> None:
    text = WING_FILE.read_text(encoding="utf-8").replace('mass = "1.0 kg"', 'mass = "1.0 m"', 1)
    bad = tmp_path / "wing.toml"
    bad.write_text(text, encoding="utf-8")
    run = runner.invoke(cli, ["app", str(bad), "--port", "1"])
    assert run.exit_code == 2, run.output
    assert "wing.panels[0].mass" in run.output
    assert "Traceback" not in run.output
