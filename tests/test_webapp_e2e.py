"""The explorer end to end in headless Debian Chromium, driven by Playwright (no download).

The servers run in background threads on free loopback ports. The tests read the rendered
page as a user sees it: plot titles and axis labels (the SVG text plotly draws), the
number of traces, the table's cells, the error and stale marks; and check its numbers
against independent derivations (tests/hand.py, hand conversions, the CLI run on the
same config or CSV). Every state is screenshotted into ``$ECDSIM_SHOTS`` (default: a
folder in the system's temporary directory) and checked with axe-core, which
``scripts/ensure-axe.sh`` installs with npm (pinned). Without /usr/bin/chromium or
axe-core the tests fail naming what to install; they are never skipped.
"""

from __future__ import annotations

import base64
import json
import math
import os
import socket
import tempfile
import threading
import time
import tomllib
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import httpx
import pytest
import uvicorn
from typer.testing import CliRunner

from ecdsim.cli.app import app as cli
from ecdsim.webapp.server import create_app
from tests import hand
from tests.conftest import PAPER_CONFIG, ROOT

CHROMIUM = Path("/usr/bin/chromium")
AXE = Path(os.environ.get("ECDSIM_AXE", str(ROOT / ".venv/axe/node_modules/axe-core/axe.min.js")))
SHOTS = Path(os.environ.get("ECDSIM_SHOTS", str(Path(tempfile.gettempdir()) / "ecdsim-explorer")))
ARGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]
DYNAMIC_CONFIG = ROOT / "examples" / "paper_cc16_dynamic.toml"
DROP_TEST = ROOT / "examples" / "drop_test.csv"
# The table shows 6 significant digits (toPrecision(6)): half a unit in the 6th digit.
CELL_REL = 5.1e-6
# B - A cells show 4 significant digits.
DIFF_REL = 5.1e-4
# 1 lbf*in in N*m from the exact definitions (lbm, standard gravity, inch).
LBF_IN = 0.45359237 * 9.80665 * 0.0254
runner = CliRunner()


def _serve(text: str | None) -> Iterator[str]:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    config = uvicorn.Config(create_app(text), host="127.0.0.1", port=port, log_level="warning")
    srv = uvicorn.Server(config)
    thread = threading.Thread(target=srv.run, daemon=True)
    thread.start()
    deadline = time.monotonic() + 20.0
    while not srv.started:
        if time.monotonic() > deadline or not thread.is_alive():
            pytest.fail("the explorer server did not start")
        time.sleep(0.02)
    try:
        yield f"http://127.0.0.1:{port}"
    finally:
        srv.should_exit = True
        thread.join(timeout=10.0)


@pytest.fixture(scope="module")
def server() -> Iterator[str]:
    yield from _serve(None)


def _degf_text() -> str:
    """The paper example with its temperatures in degF and US display units."""
    text = PAPER_CONFIG.read_text(encoding="utf-8")
    old = 'temperatures = ["-40 degC", "25 degC", "100 degC"]'
    assert old in text
    text = text.replace(old, 'temperatures = ["-40 degF", "77 degF", "212 degF"]')
    return text + '\n[output]\nunits = "us"\n'


@pytest.fixture(scope="module")
def degf_server() -> Iterator[str]:
    yield from _serve(_degf_text())


@pytest.fixture(scope="module")
def browser() -> Iterator[Any]:
    if not CHROMIUM.is_file():
        pytest.fail(f"{CHROMIUM} is missing: apt-get install -y chromium (make test does it)")
    if not AXE.is_file():
        pytest.fail(f"{AXE} is missing: run bash scripts/ensure-axe.sh (npm; make test does it)")
    from playwright.sync_api import sync_playwright

    SHOTS.mkdir(parents=True, exist_ok=True)
    with sync_playwright() as p:
        chromium = p.chromium.launch(executable_path=str(CHROMIUM), args=ARGS, headless=True)
        try:
            yield chromium
        finally:
            chromium.close()


@pytest.fixture
def page(browser: Any) -> Iterator[Any]:
    context = browser.new_context(viewport={"width": 1400, "height": 1000}, accept_downloads=True)
    page = context.new_page()
    page.set_default_timeout(30_000)
    errors: list[str] = []
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.on("requestfailed", lambda r: errors.append(f"request failed: {r.url}"))
    # Nothing the page asks for is missing or breaks the server (422s are expected).
    page.on(
        "response",
        lambda r: (
            errors.append(f"HTTP {r.status}: {r.url}")
            if r.status == 404 or r.status >= 500
            else None
        ),
    )
    try:
        yield page
        assert not errors, errors
    finally:
        context.close()


def _wait_requests(page: Any, count: int) -> None:
    page.wait_for_function(f"() => Number(document.body.dataset.requests) >= {count}")
    page.wait_for_function("() => !window.ecdsim.inFlight && !window.ecdsim.pending")


def _requests(page: Any) -> int:
    return int(page.evaluate("Number(document.body.dataset.requests)"))


def _open(page: Any, url: str) -> None:
    page.goto(url)
    _wait_requests(page, 1)


def _cell_texts(page: Any, attribute: str = "key") -> dict[str, str]:
    """The results table's cells by 'case:key' (attribute: key, pinned-key or diff-key)."""
    texts: dict[str, str] = page.evaluate(
        f"""() => Object.fromEntries([...document.querySelectorAll('#results [data-{attribute}]')]
              .map(td => [td.dataset.case + ':' + td.getAttribute('data-{attribute}'),
                          td.textContent]))"""
    )
    return texts


def _cells(page: Any) -> dict[str, float | None]:
    return {
        k: None if v.startswith(("stalls", "stuck", "not deployed", "cannot start")) else float(v)
        for k, v in _cell_texts(page).items()
        if not k.endswith(":temperature")
    }


def _plot(page: Any, element: str) -> dict[str, Any]:
    """What the rendered plot shows: title, axis labels, trace names and count."""
    info: dict[str, Any] = page.evaluate(
        """(id) => {
            const el = document.getElementById(id);
            const text = (sel) => {
                const n = el.querySelector(sel);
                return n ? n.textContent : null;
            };
            return { title: text('.gtitle'), x: text('.xtitle'), y: text('.ytitle'),
                     traces: el.data.length, names: el.data.map(t => t.name),
                     legend: [...el.querySelectorAll('.legendtext')].map(n => n.textContent) };
        }""",
        element,
    )
    return info


def _shot(page: Any, name: str) -> Path:
    path = SHOTS / f"{name}.png"
    page.screenshot(path=str(path), full_page=True)
    return path


def _axe(page: Any) -> None:
    """No accessibility violation that axe-core finds (WCAG 2 A and AA rules and more)."""
    if not page.evaluate("typeof window.axe === 'object'"):
        page.add_script_tag(path=str(AXE))
    violations: list[dict[str, Any]] = page.evaluate(
        "async () => (await axe.run(document, {resultTypes: ['violations']})).violations"
    )
    report = [
        f"{v['id']} ({v['impact']}): {v['help']}: "
        + "; ".join(str(n["target"]) for n in v["nodes"][:5])
        for v in violations
    ]
    assert not report, "\n".join(report)


def _api_cases(server: str, config: dict[str, Any]) -> list[dict[str, Any]]:
    response = httpx.post(server + "/api/deploy", json={"config": config}, timeout=60.0)
    assert response.status_code == 200, response.text
    cases: list[dict[str, Any]] = response.json()["prediction"]["cases"]
    return cases


def _value(case: dict[str, Any], path: str) -> Any:
    value: Any = case
    for part in path.split("."):
        value = value[part]
    return value


def test_explorer_end_to_end(server: str, page: Any) -> None:
    _open(page, server + "/")
    assert page.evaluate("typeof Plotly") == "object"  # served locally, no CDN
    # The rendered plots have titles and axis labels with units (plotly's {text: ...}).
    angle = _plot(page, "angle-plot")
    assert angle["title"] == "Deployed angle against time"
    assert angle["x"] == "time since release [s]"
    assert angle["y"] == "angle [deg]"
    assert angle["traces"] == 3 * 2  # 3 temperatures x (paper, exact)
    assert "-40 degC, exact" in angle["legend"]
    sweep = _plot(page, "sweep-plot")
    assert sweep["title"] == "Deployment time against temperature"
    assert (sweep["x"], sweep["y"]) == ("temperature [degC]", "deployment time [s]")
    assert sweep["traces"] == 2
    header = page.inner_text("#results thead")
    assert "exact: t [s]" in header
    assert "FECD [N*m]" in header
    before = _cells(page)
    assert len(before) == 3 * 2 * 2 + 3 * 2  # 3 temperatures x (2 methods x 2 + 2)
    # A value from the table against the hand calculation (tests/hand.py, Eq. 1-4, 8-11).
    for i, t in enumerate((-40.0, 25.0, 100.0)):
        assert before[f"{i}:exact.deployment_time_s"] == pytest.approx(
            hand.exact_time(t), rel=CELL_REL
        )
        assert before[f"{i}:paper.deployment_time_s"] == pytest.approx(
            hand.paper_time(t), rel=CELL_REL
        )
    # The temperature column is free of float noise: -40, 25, 100 exactly as text.
    temps = [v for k, v in _cell_texts(page).items() if k.endswith(":temperature")]
    assert temps == ["-40", "25", "100"]
    notes = page.inner_text("#methods-note")
    assert "paper: the paper's Eq. 8-11" in notes
    assert "dynamic" not in notes  # only the configured methods are described
    _shot(page, "01-paper-example")
    _axe(page)

    angle_before = page.evaluate("document.getElementById('angle-plot').data[0].y")
    # Slider 0..1000 spans N from 0.05x to 3x the start 380: 400 -> N = 467.4, still
    # no stall at -40 degC (FECD + FS = 1.48 N*m < 1.58 N*m end torque).
    page.fill("#slider-gearbox\\.ratio", "400")  # a range input: dispatches input
    _wait_requests(page, 2)
    after = _cells(page)
    angle_after = page.evaluate("document.getElementById('angle-plot').data[0].y")
    config = page.evaluate("window.ecdsim.sentConfig")
    assert config["gearbox"]["ratio"] == pytest.approx(380 * (0.05 + 2.95 * 0.4))
    assert after != before
    assert angle_after != angle_before
    # The same inputs through the API: the page shows exactly these numbers.
    cases = _api_cases(server, config)
    for key, shown in after.items():
        index, path = key.split(":")
        assert shown is not None, key
        assert shown == pytest.approx(_value(cases[int(index)], path), rel=CELL_REL), key
    # A larger gear ratio damps more (BECD ~ N^2): slower at every temperature.
    for i in range(3):
        slower = after[f"{i}:exact.deployment_time_s"]
        faster = before[f"{i}:exact.deployment_time_s"]
        assert slower is not None
        assert faster is not None
        assert slower > faster


def test_error_marks_results_stale_and_stalls_are_shown(server: str, page: Any) -> None:
    _open(page, server + "/")
    assert page.get_attribute("#results-section", "data-stale") == "false"
    assert not page.is_visible("#stale-banner")
    # A negative gear ratio: the server refuses it (422), the page says so and marks
    # the plots and table, which still show N = 380, as stale.
    page.fill("#field-gearbox\\.ratio", "-5")
    page.dispatch_event("#field-gearbox\\.ratio", "change")
    _wait_requests(page, 2)
    assert "gearbox.ratio" in page.inner_text("#errors")
    assert page.get_attribute("#results-section", "data-stale") == "true"
    assert page.is_visible("#stale-banner")
    _shot(page, "02-error-stale")
    _axe(page)

    # System friction FS at 0 degC from 0.58 to 1.0 N*m: at -40 degC the total friction
    # is FECD + FS = 380 * (7.9e-4 + 4.5e-4 + (2.2e-4 + 2.12e-6 * 40)) + (1.0 + 0.0044 * 40)
    # = 0.587024 + 1.176 = 1.763024 N*m, above the 1.58 N*m end torque: the spring
    # (3.73 N*m falling linearly to 1.58 over 1.57 rad) stalls at
    # (3.73 - 1.763024) * 1.57 / (3.73 - 1.58) rad = 82.297 deg.
    page.fill("#field-gearbox\\.ratio", "380")
    page.dispatch_event("#field-gearbox\\.ratio", "change")
    _wait_requests(page, 3)
    assert page.get_attribute("#results-section", "data-stale") == "false"
    assert page.inner_text("#errors") == ""
    page.fill("#field-load\\.system_friction\\.at_0C", "1.0")
    page.dispatch_event("#field-load\\.system_friction\\.at_0C", "change")
    _wait_requests(page, 4)
    stall_deg = math.degrees((3.73 - 1.763024) * 1.57 / (3.73 - 1.58))
    texts = _cell_texts(page)
    assert texts["0:exact.deployment_time_s"] == f"stalls at {float(f'{stall_deg:.4g}'):g} deg"
    sweep = _plot(page, "sweep-plot")
    # The swept temperatures where it stalls are drawn, marked, not dropped.
    assert "exact: stalls (no deployment)" in sweep["names"]
    stall_x: list[float] = page.evaluate(
        """() => document.getElementById('sweep-plot').data
              .find(t => t.name === 'exact: stalls (no deployment)').x"""
    )
    # Where it stalls: FECD(T) + FS(T) = 380 * (1.46e-3 - 2.12e-6 T) + 1.0 - 0.0044 T
    # = 1.5548 - 0.0052056 T N*m exceeds the 1.58 N*m end torque below T = -4.841 degC.
    # The sweep's 25 temperatures from -40 to 100 degC: -40, -34.17, ..., -5 stall.
    limit = (1.5548 - 1.58) / 0.0052056
    swept = [-40.0 + 140.0 * k / 24 for k in range(25)]
    assert stall_x == pytest.approx([t for t in swept if t < limit], abs=1e-9)
    angle = _plot(page, "angle-plot")
    # Short legend entries (issue 26 item 3), the stall named in the line's entry.
    assert "-40 degC, exact: stalls 82.3 deg" in angle["legend"]
    assert not [name for name in angle["legend"] if name != name.lower()[: len(name)] and
                name.isupper()]  # fmt: skip
    # The cross at the stall's angle and where the curve reaches it (item 5): the exact
    # curve approaches 82.3 deg asymptotically, so the cross sits at the first sample
    # within 0.5 % of it (else at the axis' end), in the -40 degC line's colour.
    traces: list[dict[str, Any]] = page.evaluate(
        """() => document.getElementById('angle-plot').data.map(t => ({name: t.name,
              x: t.x, y: t.y, mode: t.mode, color: t.line ? t.line.color : null,
              marker: t.marker ? t.marker.color : null}))"""
    )
    line = next(t for t in traces if t["name"] == "-40 degC, exact: stalls 82.3 deg")
    cross = next(
        t for t in traces if t["mode"] == "markers" and t["name"].startswith("-40 degC, exact")
    )
    assert cross["y"] == [pytest.approx(stall_deg, rel=1e-9)]
    reached = [x for x, y in zip(line["x"], line["y"], strict=True) if y >= 0.995 * stall_deg]
    assert cross["x"] == [reached[0] if reached else line["x"][-1]]
    assert cross["marker"] == line["color"]
    others = {t["color"] for t in traces if t["mode"] == "lines" and "exact" in t["name"]}
    assert len(others) == 3  # one colour per temperature
    _shot(page, "03-stall")
    _axe(page)


def test_dynamic_config_describes_its_methods(server: str, page: Any) -> None:
    _open(page, server + "/")
    page.set_input_files("#upload", str(DYNAMIC_CONFIG))
    _wait_requests(page, 2)
    notes = page.inner_text("#methods-note")
    assert "dynamic: integrates the equation of motion" in notes
    assert "inertia" in notes
    angle = _plot(page, "angle-plot")
    assert angle["traces"] == 3 * 3  # 3 temperatures x (paper, exact, dynamic)
    # The dynamic column equals the CLI's own run of the file.
    result = runner.invoke(cli, ["deploy", str(DYNAMIC_CONFIG), "--json"])
    assert result.exit_code == 0, result.output
    cli_cases = json.loads(result.stdout)["cases"]
    cells = _cells(page)
    for i, case in enumerate(cli_cases):
        shown = cells[f"{i}:dynamic.deployment_time_s"]
        assert shown == pytest.approx(case["dynamic"]["deployment_time_s"], rel=CELL_REL)
    _shot(page, "08-dynamic-config")
    _axe(page)


def test_degf_config_keeps_its_units(degf_server: str, page: Any, tmp_path: Path) -> None:
    _open(page, degf_server + "/")
    # The temperatures field shows the config's own numbers under its own unit.
    assert page.inner_text("#temperatures-label") == "temperatures [degF], comma-separated"
    assert page.input_value("#temperatures") == "-40, 77, 212"
    # [output] units = "us": shown in degF and lbf*in, converted from the SI results.
    temps = [v for k, v in _cell_texts(page).items() if k.endswith(":temperature")]
    assert temps == ["-40", "77", "212"]  # no -39.99999999999997
    header = page.inner_text("#results thead")
    assert "T [degF]" in header
    assert "FECD [lbf*in]" in header
    assert _plot(page, "sweep-plot")["x"] == "temperature [degF]"
    assert "77 degF, exact" in _plot(page, "angle-plot")["legend"]
    config = page.evaluate("window.ecdsim.sentConfig")
    cases = _api_cases(degf_server, config)
    cells = _cells(page)
    for i, case in enumerate(cases):
        # FECD in lbf*in: N*m / (0.45359237 kg * 9.80665 m/s^2 * 0.0254 m), by hand.
        assert cells[f"{i}:friction_Nm"] == pytest.approx(
            case["friction_Nm"] / LBF_IN, rel=CELL_REL
        )
        assert cells[f"{i}:exact.deployment_time_s"] == pytest.approx(
            case["exact"]["deployment_time_s"], rel=CELL_REL
        )
    # 77 degF is 25 degC: (77 - 32) * 5 / 9; the paper's hand value at 25 degC.
    assert cells["1:exact.deployment_time_s"] == pytest.approx(hand.exact_time(25.0), rel=CELL_REL)
    # The inputs are in US units too: 3.73 N*m = 33.0133 lbf*in, 25 degC = 77 degF.
    assert page.input_value("#field-load\\.start_torque") == f"{3.73 / LBF_IN:.6g}"
    assert "[lbf*in]" in page.inner_text("label[for='slider-load.start_torque']")
    assert page.inner_text("#fit-reference-label") == "reference temperature [degF]"
    assert page.input_value("#fit-reference") == "77"
    _shot(page, "04-degF-us-units")
    _axe(page)
    # A torque typed with its unit is taken as it is (it was refused as "not a number").
    before = _requests(page)
    page.fill("#field-load\\.start_torque", "33 lbf*in")
    page.dispatch_event("#field-load\\.start_torque", "change")
    _wait_requests(page, before + 1)
    assert page.inner_text("#errors") == ""
    assert page.evaluate("window.ecdsim.sentConfig.load.start_torque") == "33 lbf*in"
    path = tmp_path / "typed.toml"
    path.write_text(page.evaluate("window.ecdsim.response.toml"), encoding="utf-8")
    result = runner.invoke(cli, ["deploy", str(path), "--json"])
    assert result.exit_code == 0, result.output
    cells = _cells(page)
    for i, case in enumerate(json.loads(result.stdout)["cases"]):
        assert case["start_torque_Nm"] == pytest.approx(33 * LBF_IN, rel=1e-12)
        assert cells[f"{i}:exact.deployment_time_s"] == pytest.approx(
            case["exact"]["deployment_time_s"], rel=CELL_REL
        )
    _wait_requests(page, _requests(page))

    # An edit keeps the unit: a bare 300 typed there is 300 degF, not 300 degC.
    page.fill("#temperatures", "-40, 77, 300")
    page.dispatch_event("#temperatures", "change")
    _wait_requests(page, 2)
    sent = page.evaluate("window.ecdsim.sentConfig.analysis.temperatures")
    assert sent == ["-40 degF", "77 degF", "300 degF"]
    temps = [v for k, v in _cell_texts(page).items() if k.endswith(":temperature")]
    assert temps == ["-40", "77", "300"]
    response = page.evaluate("window.ecdsim.response.prediction.cases.map(c => c.temperature_C)")
    assert response[2] == pytest.approx((300.0 - 32.0) * 5.0 / 9.0, rel=1e-12)

    # The display system chosen on the page: SI shows degC, converted, not relabelled.
    page.select_option("#units", "si")
    _wait_requests(page, 3)
    temps = [v for k, v in _cell_texts(page).items() if k.endswith(":temperature")]
    assert temps == ["-40", "25", f"{(300.0 - 32.0) * 5.0 / 9.0:.6g}"]
    assert "FECD [N*m]" in page.inner_text("#results thead")
    # One unit system per page (issue 26 item 4): the inputs follow the results into SI,
    # converted: 300 degF = 148.889 degC, the 33 lbf*in typed above = 3.72850 N*m.
    assert page.input_value("#temperatures") == f"-40, 25, {(300.0 - 32.0) * 5.0 / 9.0:.6g}"
    assert page.inner_text("#temperatures-label") == "temperatures [degC], comma-separated"
    assert page.input_value("#field-load\\.start_torque") == f"{33 * LBF_IN:.6g}"
    assert "[N*m]" in page.inner_text("label[for='slider-load.start_torque']")
    # Legends in degC, to 6 significant digits: (-40 - 32) * 5 / 9 is exactly -40.
    assert "-40 degC, exact" in _plot(page, "angle-plot")["legend"]


def test_compare_two_designs(server: str, page: Any) -> None:
    _open(page, server + "/")
    config_a = page.evaluate("window.ecdsim.sentConfig")
    page.click("#pin")
    page.fill("#slider-gearbox\\.ratio", "400")  # N = 467.4
    _wait_requests(page, 2)
    config_b = page.evaluate("window.ecdsim.sentConfig")
    angle = _plot(page, "angle-plot")
    assert angle["traces"] == 2 * 3 * 2  # B and A, 3 temperatures x 2 methods each
    assert sum(name.startswith("A: ") for name in angle["names"]) == 6
    assert sum(name.startswith("B: ") for name in angle["names"]) == 6
    assert "pinned A" in angle["title"]
    assert _plot(page, "sweep-plot")["traces"] == 4
    diffs = page.inner_text("#compare-diffs")
    assert "gearbox.ratio" in diffs
    # A, B and B - A against two independent API runs of the two configs.
    cases_a = _api_cases(server, config_a)
    cases_b = _api_cases(server, config_b)
    pinned = _cell_texts(page, "pinned-key")
    current = _cells(page)
    difference = _cell_texts(page, "diff-key")
    assert len(pinned) == len(difference) == len(current) == 18
    for key, shown in current.items():
        index, path = key.split(":")
        a = _value(cases_a[int(index)], path)
        b = _value(cases_b[int(index)], path)
        assert shown == pytest.approx(b, rel=CELL_REL), key
        assert float(pinned[key]) == pytest.approx(a, rel=CELL_REL), key
        assert float(difference[key]) == pytest.approx(b - a, rel=DIFF_REL), key
    _shot(page, "05-compare-A-B")
    _axe(page)
    page.click("#unpin")
    assert _plot(page, "angle-plot")["traces"] == 6
    assert not _cell_texts(page, "pinned-key")


def _drop_csv(page: Any, path: Path) -> None:
    """Drop a file on the fit section as a user's drag and drop does (a DataTransfer)."""
    page.evaluate(
        """([name, text]) => {
            const data = new DataTransfer();
            data.items.add(new File([text], name, { type: 'text/csv' }));
            document.getElementById('fit-section')
                .dispatchEvent(new DragEvent('drop', { dataTransfer: data, bubbles: true }));
        }""",
        [path.name, path.read_text(encoding="utf-8")],
    )


def test_fit_from_the_bench(server: str, page: Any, tmp_path: Path) -> None:
    _open(page, server + "/")
    _drop_csv(page, DROP_TEST)
    page.wait_for_function("() => Number(document.body.dataset.fits) >= 1")
    assert page.inner_text("#fit-errors") == ""
    torque = _plot(page, "fit-torque-plot")
    assert torque["title"] == "Drop test: drive torque against speed (Fig. 8)"
    assert (torque["x"], torque["y"]) == ("speed [rad/s]", "drive torque [N*m]")
    assert torque["traces"] == 3 * 2  # points and line per temperature (no outlier here)
    damping = _plot(page, "fit-damping-plot")
    assert damping["y"] == "BECD [N*m*s/rad]"
    assert "linear law 95 % band" in damping["names"]
    assert _plot(page, "fit-friction-plot")["y"] == "FECD [N*m]"
    # The table against the CLI's own fit of the same file.
    result = runner.invoke(cli, ["fit", "drop-test", str(DROP_TEST), "--json"])
    assert result.exit_code == 0, result.output
    cli_fit = json.loads(result.stdout)
    shown: dict[str, str] = page.evaluate(
        """() => Object.fromEntries([...document.querySelectorAll('#fit-table td[data-fit]')]
              .map(td => [td.dataset.fit + ':' + td.dataset.key, td.textContent]))"""
    )
    for i, fitted in enumerate(cli_fit["temperatures"]):
        for key in ("damping_rate_Nms_per_rad", "friction_Nm"):
            assert float(shown[f"{i}:{key}"]) == pytest.approx(fitted[key], rel=CELL_REL)
    # Each estimate's 95 % interval beside it, read from its key in the fit's JSON (the
    # cells after BECD and FECD; 4 significant digits: half a unit in the 4th).
    rows: list[list[str]] = page.evaluate(
        """() => [...document.querySelectorAll('#fit-table tbody tr')]
              .map(tr => [...tr.querySelectorAll('td')].map(td => td.textContent))"""
    )
    for row, fitted in zip(rows, cli_fit["temperatures"], strict=True):
        for cell, key in ((row[2], "damping_rate_ci95_Nms_per_rad"), (row[4], "friction_ci95_Nm")):
            bounds = [float(bound) for bound in cell.strip("[]").split(", ")]
            assert bounds == pytest.approx(fitted[key], rel=5.1e-4)
    b_ref = page.inner_text('#fit-laws td[data-law="b_ref"]')
    linear = cli_fit["temperature_laws"]["damping_rate"]["linear"]
    assert float(b_ref) == pytest.approx(linear["damping_rate_ref_Nms_per_rad"], rel=CELL_REL)
    _shot(page, "06-fit-drop-test")
    _axe(page)

    # In US units the fit is converted too: BECD in in*lbf*s/rad, T in degF, by hand.
    before = _requests(page)
    page.select_option("#units", "us")
    _wait_requests(page, before + 1)
    us: dict[str, str] = page.evaluate(
        """() => Object.fromEntries([...document.querySelectorAll('#fit-table td[data-fit]')]
              .map(td => [td.dataset.fit + ':' + td.dataset.key, td.textContent]))"""
    )
    for i, fitted in enumerate(cli_fit["temperatures"]):
        becd = fitted["damping_rate_Nms_per_rad"] / LBF_IN
        assert float(us[f"{i}:damping_rate_Nms_per_rad"]) == pytest.approx(becd, rel=CELL_REL)
    assert "[in*lbf*s/rad]" in page.inner_text("#fit-table thead")
    assert _plot(page, "fit-damping-plot")["x"] == "temperature [degF]"
    # c per degF is c per K times 5/9 (a degF is 5/9 K).
    c_shown = float(page.inner_text('#fit-laws td[data-law="c"]'))
    assert c_shown == pytest.approx(linear["temperature_coefficient_per_K"] * 5 / 9, rel=CELL_REL)
    _shot(page, "07-fit-us-units")
    page.select_option("#units", "si")
    _wait_requests(page, before + 2)

    # Use the fitted damper: the model then equals the CLI's -o file with this config.
    start = page.evaluate("window.ecdsim.sentConfig")
    (tmp_path / "start.toml").write_text(
        page.evaluate("window.ecdsim.response.toml"), encoding="utf-8"
    )
    before = _requests(page)
    page.click("#fit-use")
    _wait_requests(page, before + 1)
    used = page.evaluate("window.ecdsim.sentConfig")
    assert used["gearbox"]["ratio"] == 1
    assert used["load"] == start["load"]
    out = tmp_path / "fitted.toml"
    fitted_run = runner.invoke(
        cli,
        [
            "fit",
            "drop-test",
            str(DROP_TEST),
            "-o",
            str(out),
            "--config",
            str(tmp_path / "start.toml"),
        ],
    )
    assert fitted_run.exit_code == 0, fitted_run.output
    deployed = runner.invoke(cli, ["deploy", str(out), "--json"])
    assert deployed.exit_code == 0, deployed.output
    cli_cases = json.loads(deployed.stdout)["cases"]
    cells = _cells(page)
    for i, case in enumerate(cli_cases):
        for path in ("exact.deployment_time_s", "damping_rate_Nms_per_rad", "friction_Nm"):
            assert cells[f"{i}:{path}"] == pytest.approx(_value(case, path), rel=CELL_REL)
    assert "fitted" in page.inner_text("#source")


def test_bad_csv_is_reported_on_the_page(server: str, page: Any, tmp_path: Path) -> None:
    _open(page, server + "/")
    bad = tmp_path / "bad.csv"
    bad.write_text("a,b\n1,2\n", encoding="utf-8")
    page.set_input_files("#fit-file", str(bad))
    page.wait_for_function("() => Number(document.body.dataset.fits) >= 1")
    assert page.inner_text("#fit-errors").startswith("error: csv: ")
    assert page.is_hidden("#fit-results")


def test_export_reads_back_and_link_reopens_the_case(
    server: str, page: Any, browser: Any, tmp_path: Path
) -> None:
    _open(page, server + "/")
    page.click("#pin")
    page.fill("#slider-gearbox\\.ratio", "400")
    _wait_requests(page, 2)
    shown = _cells(page)
    with page.expect_download() as download:
        page.click("#download-toml")
    path = tmp_path / "exported.toml"
    download.value.save_as(str(path))
    # ecdsim deploy reads the exported file back to the numbers on the page.
    result = runner.invoke(cli, ["deploy", str(path), "--json"])
    assert result.exit_code == 0, result.output
    for i, case in enumerate(json.loads(result.stdout)["cases"]):
        for path_key in ("exact.deployment_time_s", "paper.deployment_time_s", "friction_Nm"):
            assert shown[f"{i}:{path_key}"] == pytest.approx(_value(case, path_key), rel=CELL_REL)
    assert tomllib.loads(path.read_text(encoding="utf-8"))["gearbox"]["ratio"] == pytest.approx(
        380 * (0.05 + 2.95 * 0.4)
    )

    # The address holds the case (and the pinned A): a new tab opened on it shows both.
    link = page.url
    assert "#case=" in link
    context = browser.new_context(viewport={"width": 1400, "height": 1000})
    try:
        other = context.new_page()
        other.set_default_timeout(30_000)
        _open(other, link)
        assert _cells(other) == shown
        assert other.inner_text("#source") == "from the link"
        assert other.is_enabled("#unpin")
        assert len(_cell_texts(other, "pinned-key")) == 18
    finally:
        context.close()


def test_keyboard_reaches_and_operates_every_control(server: str, page: Any) -> None:
    _open(page, server + "/")
    # The page's own controls (plotly's toolbar buttons are labelled buttons too).
    focusable = "button:not([disabled]), input, select, a[href]"
    # Those shown: a wing file's controls are not rendered on a hinge's page.
    controls: list[str] = page.evaluate(
        f"""() => [...document.querySelectorAll('{focusable}')]
              .filter(e => !e.closest('.modebar') && e.getClientRects().length > 0)
              .map(e => e.id || e.getAttribute('href'))"""
    )
    total = int(page.evaluate(f"document.querySelectorAll('{focusable}').length"))
    reached: list[str] = []
    for _ in range(total + 5):
        page.keyboard.press("Tab")
        reached.append(
            page.evaluate(
                "document.activeElement.id || document.activeElement.getAttribute('href') || ''"
            )
        )
    assert set(controls) <= set(reached), set(controls) - set(reached)
    # A slider moves with the arrow keys and recomputes.
    before = _requests(page)
    page.focus("#slider-gearbox\\.ratio")
    page.keyboard.press("ArrowRight")
    _wait_requests(page, before + 1)
    ratio = page.evaluate("window.ecdsim.sentConfig.gearbox.ratio")
    # One step of 1000 from 0.05x to 3x of 380: 380 + 2.95 * 380 / 1000 above the start
    # position round(0.95 / 2.95 * 1000) = 322 steps: 380 * (0.05 + 2.95 * 323 / 1000).
    assert ratio == pytest.approx(380 * (0.05 + 2.95 * 323 / 1000), rel=5e-6)
    # Buttons work from the keyboard: Enter on "Pin" pins the case.
    page.focus("#pin")
    page.keyboard.press("Enter")
    page.wait_for_function("() => window.ecdsim.pinned !== null")


def test_a_crafted_link_opens_a_case_that_cannot_start(
    server: str, page: Any, tmp_path: Path
) -> None:
    # The dynamic example with breakaway friction 3x the kinetic and FS at 0 degC 0.9 N*m.
    config = tomllib.loads(DYNAMIC_CONFIG.read_text(encoding="utf-8"))
    config["damper"]["static_friction_factor"] = 3.0
    config["load"]["system_friction"]["at_0C"] = "0.9 N*m"
    encoded = base64.urlsafe_b64encode(json.dumps(config).encode()).rstrip(b"=").decode()
    _open(page, f"{server}/#case={encoded}")
    assert page.inner_text("#source") == "from the link"
    assert page.evaluate("window.ecdsim.sentConfig") == config
    texts = _cell_texts(page)
    # The CLI on the same config says where the dynamic method sticks.
    path = tmp_path / "stuck.toml"
    path.write_text(page.evaluate("window.ecdsim.response.toml"), encoding="utf-8")
    result = runner.invoke(cli, ["deploy", str(path), "--json"])
    assert result.exit_code == 0, result.output
    cases = json.loads(result.stdout)["cases"]
    for i, case in enumerate(cases):
        dynamic = case["dynamic"]
        shown = texts[f"{i}:dynamic.deployment_time_s"]
        if dynamic["stuck"] and dynamic["stuck_angle_rad"] == 0.0:
            assert shown == "cannot start: friction at release >= spring torque"
        else:
            assert float(shown) == pytest.approx(dynamic["deployment_time_s"], rel=CELL_REL)
    assert cases[1]["dynamic"]["stuck_angle_rad"] == 0.0  # the case this test is about
    # Quasi-static at -40 degC: FECD + FS = 0.587024 + (0.9 + 0.0044 * 40) = 1.663024 N*m
    # > 1.58 N*m: stalls at (3.73 - 1.663024) * 1.57 / 2.15 rad = 86.48 deg.
    stall = math.degrees((3.73 - 1.663024) * 1.57 / 2.15)
    assert texts["0:exact.deployment_time_s"] == f"stalls at {float(f'{stall:.4g}'):g} deg"
    # "cannot start" is a cross at t = 0, 0 deg (issue 26 item 5), named short in the legend.
    crosses: list[dict[str, Any]] = page.evaluate(
        """() => document.getElementById('angle-plot').data
              .filter(t => t.mode === 'markers' && t.name.includes('dynamic'))
              .map(t => ({name: t.name, x: t.x, y: t.y}))"""
    )
    start = next(c for c in crosses if c["name"].startswith("25 degC"))
    assert (start["x"], start["y"]) == ([0], [0])
    assert "25 degC, dynamic: cannot start" in _plot(page, "angle-plot")["legend"]
    _shot(page, "09-cannot-start")
    _axe(page)


@pytest.mark.parametrize("case", ["!!!", "WzEsMl0", ""], ids=["not-base64", "a-list", "empty"])
def test_an_unreadable_link_opens_the_start_config_and_says_so(
    server: str, page: Any, case: str
) -> None:
    _open(page, f"{server}/#case={case}")
    assert "the link's case could not be read" in page.inner_text("#source")
    # The start config (the paper example) is shown: the hand value at 25 degC.
    assert _cells(page)["1:exact.deployment_time_s"] == pytest.approx(
        hand.exact_time(25.0), rel=CELL_REL
    )


def _geometry(page: Any, element: str) -> dict[str, Any]:
    """Where plotly drew a plot's parts (CSS px): the plot area (its drag layer), the
    legend, the title and the toolbar (None where there is none)."""
    found: dict[str, Any] = page.evaluate(
        """(id) => {
            const el = document.getElementById(id);
            const box = (sel) => {
                const n = el.querySelector(sel);
                if (!n) return null;
                const r = n.getBoundingClientRect();
                return (r.width || r.height) ? {left: r.left, right: r.right, top: r.top,
                                                bottom: r.bottom, width: r.width} : null;
            };
            return { div: box('.main-svg'), area: box('.nsewdrag'), legend: box('.legend'),
                     title: box('.gtitle'), modebar: box('.modebar') };
        }""",
        element,
    )
    return found


def _overlap(a: dict[str, float], b: dict[str, float]) -> bool:
    return not (
        a["right"] <= b["left"]
        or b["right"] <= a["left"]
        or a["bottom"] <= b["top"]
        or b["bottom"] <= a["top"]
    )


@pytest.mark.parametrize("width", [390, 1280])
def test_plots_keep_their_width_and_titles_on_a_phone_and_a_desktop(
    server: str, browser: Any, width: int
) -> None:
    """Issue 26 item 3: at 390 x 844 (a phone) and 1280 px, in the state with the most
    legend entries (a case that cannot start at two temperatures and stalls at a third),
    every plot's area is at least 80 % of the page's width on a phone (of the plot's
    width on a desktop), the legend is below the plot, and no title is covered by the
    toolbar or cut off."""
    config = tomllib.loads(DYNAMIC_CONFIG.read_text(encoding="utf-8"))
    config["damper"]["static_friction_factor"] = 3.0
    config["load"]["system_friction"]["at_0C"] = "0.9 N*m"
    encoded = base64.urlsafe_b64encode(json.dumps(config).encode()).rstrip(b"=").decode()
    context = browser.new_context(viewport={"width": width, "height": 844})
    try:
        page = context.new_page()
        page.set_default_timeout(30_000)
        _open(page, f"{server}/#case={encoded}")
        page.hover("#angle-plot .nsewdrag")  # the toolbar shows where the pointer is
        for element in ("angle-plot", "sweep-plot"):
            g = _geometry(page, element)
            share = g["area"]["width"] / (width if width < 700 else g["div"]["width"])
            assert share >= 0.8, (element, g)
            assert g["legend"]["top"] >= g["area"]["bottom"], (element, g)  # below the plot
            assert g["title"]["left"] >= 0
            assert g["title"]["right"] <= min(width, g["div"]["right"]) + 0.5, (element, g)
            if g["modebar"] is not None:
                assert not _overlap(g["title"], g["modebar"]), (element, g)
            else:
                assert width < 700  # only a phone goes without the toolbar
        legend = _plot(page, "angle-plot")["legend"]
        assert "-40 degC, dynamic: cannot start" in legend
        assert max(len(name) for name in legend) <= 45  # short entries
        _shot(page, f"10-layout-{width}px")
        _axe(page)
    finally:
        context.close()


def test_a_placeholder_load_is_flagged_until_it_is_edited(
    server: str, page: Any, tmp_path: Path
) -> None:
    """Issue 26 item 2 on the page: the fit's stand-in load shows a banner, dropped as
    soon as the spring torque is edited."""
    fitted = tmp_path / "fitted.toml"
    result = runner.invoke(cli, ["fit", "drop-test", str(DROP_TEST), "-o", str(fitted)])
    assert result.exit_code == 0, result.output
    _open(page, server + "/")
    assert page.is_hidden("#placeholder-banner")
    before = _requests(page)
    page.set_input_files("#upload", str(fitted))
    _wait_requests(page, before + 1)
    assert page.is_visible("#placeholder-banner")
    assert "Placeholder load" in page.inner_text("#placeholder-banner")
    _shot(page, "11-placeholder-load")
    _axe(page)
    page.fill("#field-load\\.start_torque", "4")
    page.dispatch_event("#field-load\\.start_torque", "change")
    _wait_requests(page, before + 2)
    assert page.is_hidden("#placeholder-banner")
    assert "placeholder" not in page.evaluate("window.ecdsim.sentConfig.load")
