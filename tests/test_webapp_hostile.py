"""The explorer under malformed and hostile requests (issue 12, items 1 to 6).

Every malformed request gets a 4xx with a JSON list of problems, never a 500; the
OpenAPI document declares what is sent.
"""

from __future__ import annotations

import contextlib
import json
import os
import tomllib
from pathlib import Path
from typing import Any

import pytest
from fastapi.testclient import TestClient

from ecdsim.config.loader import MAX_NESTING
from ecdsim.webapp.server import MAX_BODY_BYTES, create_app
from tests.conftest import PAPER_CONFIG, ROOT

APP = create_app()
client = TestClient(APP, base_url="http://localhost")


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


def _children() -> set[int]:
    """The process ids of this process's children (Linux: /proc)."""
    found = set()
    for stat in Path("/proc").glob("[0-9]*/stat"):
        with contextlib.suppress(OSError):
            fields = stat.read_text().rpartition(")")[2].split()
            if int(fields[1]) == os.getpid():  # fields: state, ppid, ...
                found.add(int(stat.parent.name))
    return found


def test_a_computation_past_the_limit_is_stopped_not_abandoned(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    # Issue 23 item 6: the 503 came at the limit but the computation ran on in a thread
    # (the server's CPU time rose from 70 s to 149 s in the next 90 s). Now the worker
    # process computing it is killed at the deadline: it no longer exists when the 503
    # arrives, so it uses no CPU after it.
    import threading

    from ecdsim.webapp import server
    from tests import webapp_jobs

    monkeypatch.setattr(server, "report_job", webapp_jobs.burn_forever)
    app = server.create_app(compute_limit_s=3.0)
    pid_file = tmp_path / "pid"
    config = {**_config(), "title": str(pid_file)}
    with TestClient(app, base_url="http://localhost") as local:
        outcome: dict[str, Any] = {}

        def slow_request() -> None:
            outcome["slow"] = local.post("/api/report", json={"config": config})

        worker = threading.Thread(target=slow_request)
        worker.start()
        for _ in range(6000):  # until the job runs in its worker (polling, no time verdict)
            if pid_file.exists() and pid_file.read_text():
                break
            threading.Event().wait(0.01)
        pid = int(pid_file.read_text())
        assert pid != os.getpid()  # a process of its own, burning a CPU
        # While it burns, other requests are served, computations too (another worker).
        assert local.get("/api/example").status_code == 200
        assert local.post("/api/deploy", json={"config": _config()}).status_code == 200
        worker.join(60.0)
    response = outcome["slow"]
    assert response.status_code == 503
    assert response.json() == {
        "errors": [
            "computation: took longer than 3 s and was stopped; ask for fewer temperatures, "
            "points or a shorter stop_time"
        ]
    }
    with pytest.raises(ProcessLookupError):  # killed and reaped before the 503 was sent
        os.kill(pid, 0)
    assert pid not in _children()
    declared = app.openapi()["paths"]["/api/report"]["post"]["responses"]
    assert set(declared["503"]["content"]) == {"application/json"}


def test_a_real_slow_request_leaves_no_computation_running() -> None:
    # The request: a compliant mesh (stiff, 0.25 deg of lost motion) at six
    # temperatures and 25 swept ones, far longer than the limit set here. After its 503
    # no process of this one is left computing: only idle workers wait, using no CPU.
    from ecdsim.webapp import server
    from ecdsim.webapp.workers import shared_pool

    config = tomllib.loads((ROOT / "examples" / "paper_cc16_dynamic.toml").read_text())
    config["gearbox"].update(lost_motion="0.25 deg", stiffness="1e8 N*m/rad")
    config["analysis"]["temperatures"] = [f"{t} degC" for t in (-40, -10, 25, 60, 80, 100)]
    app = server.create_app(compute_limit_s=0.5)
    response = TestClient(app, base_url="http://localhost").post(
        "/api/deploy", json={"config": config}
    )
    assert response.status_code == 503, response.text[:300]
    idle = {w.process.pid for w in shared_pool()._idle}
    running = _children() - idle
    # Whatever else runs below this process (none is the explorer's), none burns a CPU:
    for pid in running:
        with contextlib.suppress(OSError):
            assert "ecdsim.webapp.workers" not in Path(f"/proc/{pid}/cmdline").read_text()


def test_no_free_worker_within_the_limit_is_a_503_naming_it(tmp_path: Path) -> None:
    import threading

    from ecdsim.webapp.workers import Busy, Timeout, WorkerPool
    from tests import webapp_jobs

    pool = WorkerPool(1)
    pid_file = tmp_path / "pid"
    outcome: list[BaseException] = []

    def hold() -> None:
        try:
            pool.call(webapp_jobs.burn_forever, ({"title": str(pid_file)},), 5.0)
        except BaseException as exc:
            outcome.append(exc)

    holder = threading.Thread(target=hold)
    holder.start()
    for _ in range(6000):
        if pid_file.exists() and pid_file.read_text():
            break
        threading.Event().wait(0.01)
    with pytest.raises(Busy):  # the one worker holds its slot until its own limit
        pool.call(webapp_jobs.defect, ({},), 0.05)
    holder.join(60.0)
    assert [type(e) for e in outcome] == [Timeout]
    pool.close()


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
    from tests import webapp_jobs

    monkeypatch.setattr(server, "deploy_job", webapp_jobs.defect)  # run in a worker
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
            b"POST /api/deploy HTTP/1.1\r\nHost: localhost\r\nContent-Type: application/json\r\n"
            + f"Content-Length: {len(body)}\r\n\r\n".encode()
            + body
        )
        get = b"GET /api/example HTTP/1.1\r\nHost: localhost\r\n\r\n"
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


# --- issue 23 item 6: Host names, slow bodies, an exposed server -------------------------


@pytest.mark.parametrize(
    "host",
    ["localhost", "localhost:8765", "LOCALHOST.", "127.0.0.1:8765", "[::1]:8765", "app.localhost"],
)
def test_requests_to_this_servers_names_are_answered(host: str) -> None:
    response = client.get("/api/example", headers={"host": host})
    assert response.status_code == 200, response.text


@pytest.mark.parametrize("host", ["evil.example:8765", "localhost.evil.example", "testserver"])
def test_a_page_of_another_name_cannot_read_the_config(host: str) -> None:
    # DNS rebinding: a page from evil.example whose name then resolves to 127.0.0.1 is
    # same-origin with the explorer to the browser; its requests say Host: evil.example.
    for method, path in (("GET", "/api/example"), ("POST", "/api/deploy"), ("GET", "/")):
        response = client.request(method, path, headers={"host": host}, json={"config": {}})
        assert response.status_code == 400, (path, response.text)
        assert response.json() == {
            "errors": [
                f"host: {host!r} is not a name of this server; open it as localhost or by "
                "its address (other names are refused against DNS rebinding)"
            ]
        }
        assert "paper" not in response.text


def test_the_bound_name_and_on_a_wildcard_the_machines_names_are_answered() -> None:
    import socket

    named = TestClient(create_app(host="explorer.lan"), base_url="http://explorer.lan")
    assert named.get("/api/example").status_code == 200
    assert named.get("/api/example", headers={"host": "other.lan"}).status_code == 400
    everywhere = TestClient(create_app(host="0.0.0.0"), base_url="http://localhost")
    for name in (socket.gethostname(), "10.1.2.3:8765"):
        assert everywhere.get("/api/example", headers={"host": name}).status_code == 200


def _serve(app: Any) -> tuple[Any, Any, int]:
    import socket
    import threading

    import uvicorn

    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    srv = uvicorn.Server(uvicorn.Config(app, host="127.0.0.1", port=port, log_level="critical"))
    thread = threading.Thread(target=srv.run, daemon=True)
    thread.start()
    for _ in range(2000):  # wait for start-up, polling (no wall-clock assertion)
        if srv.started:
            break
        threading.Event().wait(0.01)
    assert srv.started
    return srv, thread, port


def test_a_body_slower_than_its_content_length_is_timed_out() -> None:
    # A client that promised 1000 bytes and sent 10 held its connection and a request
    # open for ever (slowloris); now it gets 408 when the body's time is up, and the
    # connection is closed.
    import socket

    from ecdsim.webapp import server

    srv, thread, port = _serve(server.create_app(body_timeout_s=0.5))
    try:
        with (
            socket.create_connection(("127.0.0.1", port), timeout=30.0) as connection,
            connection.makefile("rb") as reader,
        ):
            connection.sendall(
                b"POST /api/deploy HTTP/1.1\r\nHost: localhost\r\n"
                b"Content-Type: application/json\r\nContent-Length: 1000\r\n\r\n" + b'{"config":'
            )
            status, payload = _read_response(reader)
            assert status == 408
            assert json.loads(payload) == {
                "errors": [
                    "body: not received within 0.5 s (10 bytes arrived of the 1000 its "
                    "Content-Length promised)"
                ]
            }
            assert reader.read() == b""  # closed by the server
    finally:
        srv.should_exit = True
        thread.join(timeout=10.0)


@pytest.mark.parametrize(
    ("host", "warned"),
    [("0.0.0.0", True), ("::", True), ("192.168.1.20", True), ("127.0.0.1", False),
     ("localhost", False), ("::1", False)],
)  # fmt: skip
def test_an_exposed_server_is_warned_about(
    monkeypatch: pytest.MonkeyPatch, host: str, warned: bool
) -> None:
    import uvicorn
    from typer.testing import CliRunner

    from ecdsim.cli.app import app

    started: dict[str, Any] = {}
    monkeypatch.setattr(
        uvicorn, "run", lambda application, **kw: started.update(kw, app=application)
    )
    result = CliRunner().invoke(app, ["app", "--host", host, "--port", "8766"])
    assert result.exit_code == 0, result.output
    assert started["host"] == host
    warning = (
        f"warning: --host {host} makes the explorer reachable from other machines on port "
        "8766, and it has no authentication: anyone who reaches it reads your config and "
        "uses this machine's CPU; keep 127.0.0.1 unless the network is trusted"
    )
    assert (warning in result.stderr) == warned, result.stderr
    # The app answers the bound name (and, on a wildcard address, the machine's names).
    probe = TestClient(started["app"], base_url="http://localhost")
    assert probe.get("/api/example").status_code == 200
