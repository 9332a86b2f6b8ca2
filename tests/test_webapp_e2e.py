"""The explorer end to end in headless Debian Chromium, driven by Playwright (no download).

The server runs in a background thread on a free loopback port. The test loads the paper
example, moves the gear-ratio slider, and checks that the plot and the table change and
equal the API's JSON for the config the page holds. Without /usr/bin/chromium the test
fails naming the package (make test installs it); it is never skipped.
"""

from __future__ import annotations

import socket
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import httpx
import pytest
import uvicorn

from ecdsim.webapp.server import create_app

CHROMIUM = Path("/usr/bin/chromium")
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
# The table shows 6 significant digits (toPrecision(6)): half a unit in the 6th digit.
CELL_REL = 5.1e-6


@pytest.fixture(scope="module")
def server() -> Iterator[str]:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    config = uvicorn.Config(create_app(), host="127.0.0.1", port=port, log_level="warning")
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


def _cells(page: Any) -> dict[str, float | None]:
    texts: dict[str, str] = page.evaluate(
        """() => Object.fromEntries([...document.querySelectorAll('#results td[data-key]')]
              .map(td => [td.dataset.case + ':' + td.dataset.key, td.textContent]))"""
    )
    return {k: None if v == "stall" else float(v) for k, v in texts.items()}


def _wait_requests(page: Any, count: int) -> None:
    page.wait_for_function(f"() => Number(document.body.dataset.requests) >= {count}")
    page.wait_for_function("() => !window.ecdsim.inFlight && !window.ecdsim.pending")


def test_explorer_end_to_end(server: str) -> None:
    if not CHROMIUM.is_file():
        pytest.fail(f"{CHROMIUM} is missing: apt-get install -y chromium (make test does it)")
    from playwright.sync_api import sync_playwright

    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=str(CHROMIUM), args=ARGS, headless=True)
        try:
            page = browser.new_page()
            page.set_default_timeout(20_000)
            failed: list[str] = []
            page.on("requestfailed", lambda r: failed.append(r.url))
            page.goto(server + "/")
            _wait_requests(page, 1)
            page.click("#load-example")
            _wait_requests(page, 2)
            assert page.evaluate("typeof Plotly") == "object"  # served locally, no CDN
            before = _cells(page)
            angle_before = page.evaluate("document.getElementById('angle-plot').data[0].y")
            assert len(before) == 3 * 2 * 2 + 3 * 2  # 3 temperatures x (2 methods x 2 + 2)

            # Slider 0..1000 spans N from 0.05x to 3x the start 380: 400 -> N = 467.4, still
            # no stall at -40 degC (FECD + FS = 1.48 N*m < 1.58 N*m end torque).
            page.fill("#slider-gearbox\\.ratio", "400")  # a range input: dispatches input
            _wait_requests(page, 3)
            after = _cells(page)
            angle_after = page.evaluate("document.getElementById('angle-plot').data[0].y")
            config = page.evaluate("window.ecdsim.sentConfig")
            assert config["gearbox"]["ratio"] == pytest.approx(380 * (0.05 + 2.95 * 0.4))
            assert after != before
            assert angle_after != angle_before

            # The same inputs through the API: the page shows exactly these numbers.
            api = httpx.post(server + "/api/deploy", json={"config": config}, timeout=30.0)
            assert api.status_code == 200
            cases = api.json()["prediction"]["cases"]
            for key, shown in after.items():
                index, path = key.split(":")
                value: Any = cases[int(index)]
                for part in path.split("."):
                    value = value[part]
                assert shown is not None, key
                assert shown == pytest.approx(value, rel=CELL_REL), key
            # A larger gear ratio damps more (BECD ~ N^2): slower at every temperature.
            for i in range(3):
                slower = after[f"{i}:exact.deployment_time_s"]
                faster = before[f"{i}:exact.deployment_time_s"]
                assert slower is not None
                assert faster is not None
                assert slower > faster
            assert not failed, failed
        finally:
            browser.close()
