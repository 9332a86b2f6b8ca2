"""The explorer under malformed and hostile requests (issue 12, items 1 to 6).

Every malformed request gets a 4xx with a JSON list of problems, never a 500; the
OpenAPI document declares what is sent.
"""

from __future__ import annotations

import json
import tomllib
from typing import Any

import pytest
from fastapi.testclient import TestClient

from ecdsim.config.loader import MAX_NESTING
from ecdsim.webapp.server import MAX_BODY_BYTES, create_app
from tests.conftest import PAPER_CONFIG

APP = create_app()
client = TestClient(APP)


def _config() -> dict[str, Any]:
    return tomllib.loads(PAPER_CONFIG.read_text(encoding="utf-8"))


@pytest.mark.parametrize("depth", [MAX_NESTING + 1, 500, 5000])
def test_deeply_nested_configs_are_refused(depth: int) -> None:
    # Written by hand: Python's own JSON encoder cannot nest 5000 deep.
    config = json.dumps(_config())
    body = f'{{"config": {config[:-1]}, "extra": {{"x": {"[" * depth}1{"]" * depth}}}}}}}'
    for endpoint in ("/api/deploy", "/api/config.toml", "/api/report"):
        response = client.post(endpoint, content=body, headers={"content-type": "application/json"})
        # Past the JSON parser's own limit the body is not JSON to it: 400, else 422.
        assert response.status_code == (400 if depth > 1000 else 422), endpoint
        (problem,) = response.json()["errors"]
        assert "nested too deeply" in problem or "error parsing the body" in problem


def test_deeply_nested_toml_is_refused() -> None:
    text = PAPER_CONFIG.read_text() + "\n[extra]\nx = " + "[" * 5000 + "]" * 5000 + "\n"
    response = client.post("/api/config/parse", json={"toml": text})
    assert response.status_code == 422
    assert "nested too deeply" in response.json()["errors"][0]


@pytest.mark.parametrize("value", [False, True, "25", 2.5])
def test_counts_must_be_integers(value: Any) -> None:
    response = client.post("/api/deploy", json={"config": _config(), "sweep_points": value})
    assert response.status_code == 422, response.text
    assert response.json()["errors"][0].startswith("sweep_points: ")


def test_unit_expressions_and_wrong_types_are_422() -> None:
    config = _config()
    config["load"]["start_torque"] = "3.73 N*m/0"
    response = client.post("/api/deploy", json={"config": config})
    assert response.status_code == 422
    assert "is not a unit expression" in response.json()["errors"][0]
    config = _config()
    config["analysis"]["methods"] = [["exact"]]
    response = client.post("/api/deploy", json={"config": config})
    assert response.status_code == 422
    assert response.json()["errors"][0].startswith("config: analysis.methods[0]")


def test_overflowing_inputs_are_422() -> None:
    config = _config()
    config["gearbox"]["ratio"] = 1e200
    response = client.post("/api/deploy", json={"config": config})
    assert response.status_code == 422
    assert "gearbox.ratio" in response.json()["errors"][0]


def test_a_body_over_the_limit_is_413_with_or_without_a_length() -> None:
    huge = b'{"config": {"title": "' + b"x" * (MAX_BODY_BYTES + 10) + b'"}}'
    response = client.post(
        "/api/deploy", content=huge, headers={"content-type": "application/json"}
    )
    assert response.status_code == 413
    assert response.json() == {"errors": [f"body: larger than {MAX_BODY_BYTES} bytes"]}

    def chunks() -> Any:  # no Content-Length: a streamed body
        for _ in range(20):
            yield b"x" * (MAX_BODY_BYTES // 10)

    response = client.post(
        "/api/deploy", content=chunks(), headers={"content-type": "application/json"}
    )
    assert response.status_code == 413
    # A normal request on the same client still works afterwards.
    assert client.post("/api/deploy", json={"config": _config()}).status_code == 200


def test_report_refusals_are_json_and_declared_so() -> None:
    config = _config()
    config["gearbox"]["ratio"] = -1
    response = client.post("/api/report", json={"config": config})
    assert response.status_code == 422
    assert response.headers["content-type"] == "application/json"
    declared = APP.openapi()["paths"]["/api/report"]["post"]["responses"]
    assert set(declared["422"]["content"]) == {"application/json"}
    assert set(declared["200"]["content"]) == {"text/html"}


def test_a_slow_computation_gets_503_and_does_not_block_other_requests(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    import threading

    from ecdsim.webapp import server

    release = threading.Event()
    started = threading.Event()

    def stuck(config: Any) -> Any:  # stands in for a computation that never ends
        started.set()
        release.wait(30.0)
        raise RuntimeError("released")

    monkeypatch.setattr(server, "predict_config", stuck)
    monkeypatch.setattr(server, "COMPUTE_LIMIT_S", 0.5)
    app = server.create_app()
    with TestClient(app) as local:
        outcome: dict[str, Any] = {}

        def slow_request() -> None:
            outcome["slow"] = local.post("/api/deploy", json={"config": _config()})

        worker = threading.Thread(target=slow_request)
        worker.start()
        assert started.wait(10.0)
        # While the computation hangs, another request is served (event order, not time).
        assert local.get("/api/example").status_code == 200
        worker.join(30.0)
        release.set()
    response = outcome["slow"]
    assert response.status_code == 503
    assert response.json()["errors"][0].startswith("computation: took longer than 0.5 s")
    declared = app.openapi()["paths"]["/api/deploy"]["post"]["responses"]
    assert set(declared["503"]["content"]) == {"application/json"}


def _read_response(reader: Any) -> tuple[int, bytes]:
    """Status and body of one HTTP/1.1 response with a Content-Length, read from ``reader``."""
    status_line = reader.readline()
    assert status_line.startswith(b"HTTP/1.1 "), f"connection closed: {status_line!r}"
    length = 0
    while (line := reader.readline()) not in (b"\r\n", b""):
        name, _, value = line.decode("latin-1").partition(":")
        if name.strip().lower() == "content-length":
            length = int(value)
    return int(status_line.split()[1]), reader.read(length)


def test_a_500_leaves_a_kept_alive_connection_serving(monkeypatch: pytest.MonkeyPatch) -> None:
    # A real server (uvicorn) and one HTTP/1.1 client: a defect inside a request is a JSON
    # 500, and the next request on the same client is served normally.
    import socket
    import threading

    import uvicorn

    from ecdsim.webapp import server

    def defect(config: Any) -> Any:
        raise RuntimeError("a defect, not the user's fault")

    monkeypatch.setattr(server, "predict_config", defect)
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    srv = uvicorn.Server(
        uvicorn.Config(server.create_app(), host="127.0.0.1", port=port, log_level="critical")
    )
    thread = threading.Thread(target=srv.run, daemon=True)
    thread.start()
    try:
        for _ in range(2000):  # wait for start-up, polling (no wall-clock assertion)
            if srv.started:
                break
            threading.Event().wait(0.01)
        assert srv.started
        # One raw socket, so the test sees exactly one connection: an HTTP client library
        # would quietly reconnect if the server closed it after the 500 (which uvicorn
        # does when the app re-raises, the defect this test guards against).
        body = json.dumps({"config": _config()}).encode()
        post = (
            b"POST /api/deploy HTTP/1.1\r\nHost: t\r\nContent-Type: application/json\r\n"
            + f"Content-Length: {len(body)}\r\n\r\n".encode()
            + body
        )
        get = b"GET /api/example HTTP/1.1\r\nHost: t\r\n\r\n"
        with (
            socket.create_connection(("127.0.0.1", port), timeout=30.0) as connection,
            connection.makefile("rb") as reader,
        ):
            for _ in range(3):
                connection.sendall(post)
                status, payload = _read_response(reader)
                assert status == 500
                assert json.loads(payload) == {
                    "errors": ["internal error (RuntimeError); please report it"]
                }
                connection.sendall(get)
                status, _ = _read_response(reader)
                assert status == 200
    finally:
        srv.should_exit = True
        thread.join(timeout=10.0)
