"""The explorer with a wing file, in headless Debian Chromium (as tests/test_webapp_e2e.py).

The page is read as a user sees it: the hinge-angle plot's title, axes and legend, the
animation's drawn panels (plotly's data, converted back from the page's unit) at the
slider's ends against the geometry of POST /api/wing (itself checked by hand in
tests/test_webapp_wing.py), the slider moved from the keyboard, play and pause, the
single hinge's controls hidden, the layout at 390 and 1280 px, and axe-core on each
state. Screenshots go to ``$ECDSIM_SHOTS`` as for the other browser tests.
"""

from __future__ import annotations

import base64
import json
import math
import tomllib
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import httpx
import numpy as np
import pytest

from tests.test_webapp_e2e import _axe, _geometry, _open, _plot, _serve, _shot, browser
from tests.test_webapp_wing import DEPLOYED, STOWED, WING_FILE, warm_wing_kernel

__all__ = ["browser"]  # the fixture, shared with tests/test_webapp_e2e.py

INCH_M = 0.0254


@pytest.fixture(scope="module")
def wing_server() -> Iterator[str]:
    warm_wing_kernel()
    yield from _serve(WING_FILE.read_text(encoding="utf-8"))


def _context(browser: Any, width: int) -> Any:
    context = browser.new_context(viewport={"width": width, "height": 900}, accept_downloads=True)
    page = context.new_page()
    page.set_default_timeout(60_000)
    errors: list[str] = []
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.on(
        "response",
        lambda r: errors.append(f"HTTP {r.status}: {r.url}") if r.status >= 400 else None,
    )
    return context, page, errors


def _drawn_panels(page: Any) -> list[list[list[float]]]:
    """The panels as drawn (each trace's four corners, the closing point dropped)."""
    panels: list[list[list[float]]] = page.evaluate(
        """() => document.getElementById('wing-shape-plot').data
                 .filter(t => t.fill === 'toself')
                 .map(t => t.x.slice(0, 4).map((x, i) => [x, t.y[i]]))"""
    )
    return panels


def _state(page: Any) -> dict[str, Any]:
    found: dict[str, Any] = page.evaluate(
        """() => ({ title: document.querySelector('#wing-shape-plot .gtitle').textContent,
                    text: document.getElementById('wing-state').textContent,
                    frame: window.ecdsimWing.frame, time: window.ecdsimWing.time,
                    valuetext: document.getElementById('wing-time').getAttribute('aria-valuetext'),
                    cursor: document.getElementById('wing-angle-plot').layout.shapes[0].x0 })"""
    )
    return found


def test_a_wing_file_shows_its_hinges_and_unfolds(wing_server: str, browser: Any) -> None:
    api = httpx.post(
        wing_server + "/api/wing",
        json={"config": tomllib.loads(WING_FILE.read_text(encoding="utf-8"))},
        timeout=120.0,
    ).json()
    context, page, errors = _context(browser, 1280)
    try:
        _open(page, wing_server + "/")
        assert page.evaluate("document.body.dataset.mode") == "wing"
        # The single hinge's inputs and plots are not shown; the wing's are.
        for hidden in ("#sliders", "#angle-plot", "#sweep-plot", "#compare", "#fit-section"):
            assert not page.is_visible(hidden), hidden
        assert page.is_visible("#wing-angle-plot")
        assert page.evaluate("document.getElementById('errors').textContent") == ""
        angles = _plot(page, "wing-angle-plot")
        assert angles["title"].startswith("Hinge angles against time")
        assert angles["x"] == "time since release [s]"
        assert angles["y"] == "deployed angle [deg]"
        for entry in ("-40 degC", "25 degC", "100 degC", "hinge root", "hinge middle", "latches"):
            assert entry in angles["legend"], angles["legend"]
        # Per temperature: three hinge curves and the latch marks.
        latch_traces = page.evaluate(
            """() => document.getElementById('wing-angle-plot').data
                     .filter(t => t.mode === 'markers' && t.x[0] !== null).map(t => t.x)"""
        )
        expected = [[latch["time_s"] for latch in c["latches"]] for c in api["result"]["cases"]]
        assert latch_traces == expected
        # The animation starts at release: the stowed wing, drawn in m (SI page).
        np.testing.assert_allclose(_drawn_panels(page), STOWED, rtol=0, atol=1e-9)
        start = _state(page)
        assert start["frame"] == 0
        assert start["title"].startswith("The wing at t = 0 s, -40 degC")
        assert "root moving, middle moving, outer moving" in start["text"]
        _shot(page, "wing-01-release-1280px")
        _axe(page)
        # Tab reaches every control shown (the wing's slider, temperature and Play too).
        focusable = "button:not([disabled]), input, select, a[href]"
        controls = page.evaluate(
            f"""() => [...document.querySelectorAll('{focusable}')]
                  .filter(e => !e.closest('.modebar') && e.getClientRects().length > 0)
                  .map(e => e.id || e.getAttribute('href'))"""
        )
        assert {"wing-time", "wing-play", "wing-temperature", "temperatures"} <= set(controls)
        page.evaluate("document.activeElement.blur()")  # from the top of the page
        # Plotly's toolbar buttons and the scrolling table regions take Tabs too.
        stops = int(page.evaluate(f"document.querySelectorAll('{focusable}, [tabindex]').length"))
        reached = []
        for _ in range(stops + 5):
            page.keyboard.press("Tab")
            reached.append(page.evaluate("document.activeElement.id || ''"))
        assert {"wing-time", "wing-play", "wing-temperature"} <= set(reached), reached
        # Download report: the wing's report (ecdsim report WING.toml) of the same result.
        with page.expect_download() as download:
            page.click("#download-report")
        report = Path(download.value.path()).read_text(encoding="utf-8")
        assert '<script type="application/json" id="ecdsim-data">' in report
        assert "Three-panel wing" in report

        # The slider from the keyboard: End is the last sample, the deployed wing.
        page.focus("#wing-time")
        page.keyboard.press("End")
        end = _state(page)
        np.testing.assert_allclose(_drawn_panels(page), DEPLOYED, rtol=0, atol=1e-9)
        assert end["frame"] == len(api["cases"][0]["time_s"]) - 1
        assert end["cursor"] == pytest.approx(api["cases"][0]["time_s"][-1], rel=1e-12)
        assert "root latched, middle latched, outer latched" in end["text"]
        # Halfway (arrow keys from the start): after the root's latch at -40 degC and
        # before the others', so the root alone is latched and the drawing is neither end.
        page.keyboard.press("Home")
        for _ in range(60):
            page.keyboard.press("PageUp")  # 10 % of the range per press in Chromium
            if _state(page)["time"] >= 0.55 * api["cases"][0]["time_s"][-1]:
                break
        middle = _state(page)
        root_latch = api["result"]["cases"][0]["latches"][0]
        assert root_latch["hinge"] == "root"
        assert (
            root_latch["time_s"]
            < middle["time"]
            < api["result"]["cases"][0]["latches"][1]["time_s"]
        )
        assert "root latched, middle moving, outer moving" in middle["text"]
        assert middle["title"] != start["title"]
        assert middle["valuetext"].startswith("t = ")
        drawn = _drawn_panels(page)
        assert np.max(np.abs(np.subtract(drawn, STOWED))) > 0.1
        assert np.max(np.abs(np.subtract(drawn, DEPLOYED))) > 0.1
        # The frame shown is one of the solution's own samples, at or before the slider.
        times = api["cases"][0]["time_s"]
        assert times[middle["frame"]] <= middle["time"] < times[middle["frame"] + 1]
        np.testing.assert_allclose(
            drawn, api["cases"][0]["outlines_m"][middle["frame"]], atol=1e-12
        )
        _shot(page, "wing-02-unfolding-1280px")

        # Play runs the clock forwards; pause holds it.
        page.keyboard.press("Home")
        page.click("#wing-play")
        assert page.get_attribute("#wing-play", "aria-pressed") == "true"
        page.wait_for_function("() => window.ecdsimWing.time > 1.0")
        page.click("#wing-play")
        assert page.get_attribute("#wing-play", "aria-pressed") == "false"
        held = _state(page)["time"]
        page.wait_for_timeout(400)
        assert _state(page)["time"] == held
        _axe(page)

        # Another temperature: its own samples, from release.
        page.select_option("#wing-temperature", index=2)
        assert _state(page)["title"].startswith("The wing at t = 0 s, 100 degC")
        page.focus("#wing-time")
        page.keyboard.press("End")
        assert _state(page)["frame"] == len(api["cases"][2]["time_s"]) - 1
        # US units: lengths in inches (1 in = 0.0254 m exactly), temperatures in degF.
        page.select_option("#units", "us")
        page.wait_for_function(
            "() => window.ecdsim.displayUnits === 'us' && !window.ecdsim.inFlight"
        )
        page.wait_for_function(
            "() => document.querySelector('#wing-shape-plot .xtitle').textContent.includes('[in]')"
        )
        np.testing.assert_allclose(
            np.array(_drawn_panels(page)) * INCH_M, DEPLOYED, rtol=0, atol=1e-9
        )
        assert "212 degF" in _plot(page, "wing-angle-plot")["legend"]
        assert not errors, errors
    finally:
        context.close()


@pytest.mark.parametrize("width", [390, 1280])
def test_the_wing_page_keeps_its_plots_wide_on_a_phone(
    wing_server: str, browser: Any, width: int
) -> None:
    context, page, errors = _context(browser, width)
    try:
        _open(page, wing_server + "/")
        page.focus("#wing-time")
        page.keyboard.press("End")
        for _ in range(4):
            page.keyboard.press("PageDown")
        for element in ("wing-angle-plot", "wing-shape-plot"):
            g = _geometry(page, element)
            share = g["area"]["width"] / (width if width < 700 else g["div"]["width"])
            assert share >= 0.8, (element, g)
            assert g["legend"]["top"] >= g["area"]["bottom"], (element, g)
            assert g["title"]["left"] >= 0
            assert g["title"]["right"] <= min(width, g["div"]["right"]) + 0.5, (element, g)
        slider = page.evaluate(
            "() => document.getElementById('wing-time').getBoundingClientRect().width"
        )
        assert slider >= 0.5 * min(width, 700)  # usable with a thumb on a phone
        scroll = page.evaluate("document.documentElement.scrollWidth")
        assert scroll <= width  # the page itself does not scroll sideways
        _shot(page, f"wing-03-layout-{width}px")
        _axe(page)
        assert not errors, errors
    finally:
        context.close()


def test_a_stuck_hinge_is_shown_stuck(wing_server: str, browser: Any) -> None:
    """The outer hinge's friction (5 N*m) above its spring's start torque (3.73 N*m): it
    cannot break away, so the wing stays short of deployed. Opened from a link, as a
    shared case is."""
    config = tomllib.loads(WING_FILE.read_text(encoding="utf-8"))
    config["wing"]["hinges"][2]["friction"] = {"slope": "0 N*m/K", "at_0C": "5 N*m"}
    config["analysis"]["temperatures"] = ["25 degC"]
    api = httpx.post(wing_server + "/api/wing", json={"config": config}, timeout=120.0).json()
    (case,) = api["result"]["cases"]
    assert case["status"] == "stuck"
    assert case["stuck_hinges"] == ["outer"]
    encoded = base64.urlsafe_b64encode(json.dumps(config).encode()).rstrip(b"=").decode()
    context, page, errors = _context(browser, 1280)
    try:
        _open(page, f"{wing_server}/#case={encoded}")
        cells = page.evaluate(
            "() => [...document.querySelectorAll('#wing-table td')].map(td => td.textContent)"
        )
        assert "not deployed (stuck)" in cells
        # Its angle at the end in degrees, to the page's 4 digits.
        final = math.degrees(case["final_angle_rad"]["outer"])
        assert f"stuck at {float(f'{final:.4g}'):g} deg" in cells, cells
        # The stick is marked on the angle plot at the run's stick time.
        sticks = page.evaluate(
            """() => document.getElementById('wing-angle-plot').data
                     .filter(t => t.name && t.name.endsWith(': sticks')).map(t => t.x)"""
        )
        stick_times = [
            e["time_s"] for e in case["events"] if e["event"] == "stick" and e["hinge"] == "outer"
        ]
        assert sticks == [stick_times]
        page.focus("#wing-time")
        page.keyboard.press("End")
        assert "root latched, middle latched, outer stuck" in _state(page)["text"]
        assert "hinge, stuck" in _plot(page, "wing-shape-plot")["legend"]
        _shot(page, "wing-04-stuck-1280px")
        _axe(page)
        assert not errors, errors
    finally:
        context.close()
