"""The explorer: a FastAPI app serving a JSON API (OpenAPI at /openapi.json) and a static page.

Every result comes from :func:`ecdsim.report.builder.predict_config`, which calls
:func:`ecdsim.deployment.predict` exactly as ``ecdsim deploy`` does; the response's
``prediction`` is :meth:`~ecdsim.deployment.Prediction.to_dict`, the JSON of
``ecdsim deploy --json``. A request's config is the TOML file's content as JSON (quantities
as unit strings); it is written as TOML and read by :func:`ecdsim.config.parse_config`,
so that the web and the file go through one parser and the downloaded TOML is exactly
what was computed. Invalid configs give 422 with one message per problem, naming the
field. plotly.js is served from the installed ``plotly`` package (no CDN).
"""

from __future__ import annotations

import json
import logging
import time
import tomllib
from collections.abc import Callable
from importlib.resources import files
from pathlib import Path
from typing import Any, Literal

import numpy as np
from fastapi import FastAPI, HTTPException, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import FileResponse, HTMLResponse, JSONResponse, Response
from pydantic import BaseModel, ConfigDict, Field
from starlette.exceptions import HTTPException as StarletteHTTPException

from ecdsim._version import __version__
from ecdsim.config import Config, ConfigError, parse_config
from ecdsim.config.loader import MAX_NESTING, nesting_depth, parse_toml
from ecdsim.config.units import quoted
from ecdsim.config.wing_schema import WingConfig
from ecdsim.deployment import ModelDomainError, Prediction, predict
from ecdsim.report.builder import predict_config, render_html
from ecdsim.units_display import UnitSystem, check_system, convert_text, describe, key_units
from ecdsim.webapp.tomlwriter import UnrepresentableError, to_toml
from ecdsim.webapp.wingapi import MAX_TEMPERATURES as WING_MAX_TEMPERATURES
from ecdsim.webapp.wingapi import WING_REFUSAL, is_wing, load_wing_text
from ecdsim.webapp.workers import Busy, Reply, Timeout, WorkerDied, as_reply, shared_pool

_LOG = logging.getLogger(__name__)

STATIC = Path(str(files("ecdsim.webapp") / "static"))
EXAMPLE_CONFIG = files("ecdsim") / "data" / "paper_cc16.toml"
MAX_TEMPERATURES = WING_MAX_TEMPERATURES  # one bound for a hinge's and a wing's requests


class ConfigBody(BaseModel):
    """A configuration as JSON: the TOML file's tables and keys, quantities as unit strings."""

    model_config = ConfigDict(
        extra="forbid",
        json_schema_extra={
            "examples": [
                {
                    "config": {
                        "damper": {"damping_rate": "1.3e-4 N*m*s/rad",
                                   "coulomb_friction": "7.9e-4 N*m"},
                        "gearbox": {"ratio": 380, "damping_fraction": 0.26,
                                    "coulomb_friction": "4.5e-4 N*m"},
                        "load": {"start_torque": "3.73 N*m", "end_torque": "1.58 N*m",
                                 "travel": "1.57 rad"},
                    }
                }
            ]
        },
    )  # fmt: skip

    config: dict[str, Any] = Field(
        description="The configuration: same tables and keys as the TOML file (docs/config.md)."
    )


_UNITS_DESCRIPTION = (
    "Display unit system of the response (`si` or `us`, docs/json.md#display-units); "
    "null: the config's `[output] units` (si if absent). Numbers stay SI either way."
)


class DeployBody(ConfigBody):
    """A configuration, how finely to sample the curves, and the display unit system."""

    units: Literal["si", "us"] | None = Field(None, description=_UNITS_DESCRIPTION)

    # strict: JSON true/false or "25" are not counts (pydantic would read false as 0).
    time_points: int = Field(
        200, ge=2, le=2000, strict=True, description="Samples of angle against time."
    )
    sweep_points: int = Field(
        25,
        ge=0,
        le=201,
        strict=True,
        description="Temperatures of the deployment-time curve, spread between the coldest "
        "and the hottest configured temperature (0: none).",
    )


class ReportBody(ConfigBody):
    """A configuration and the report's unit system."""

    units: Literal["si", "us"] | None = Field(None, description=_UNITS_DESCRIPTION)


class TomlBody(BaseModel):
    """A configuration as TOML text."""

    model_config = ConfigDict(extra="forbid")
    toml: str = Field(description="TOML text of a configuration (docs/config.md).")


class ProblemDetail(BaseModel):
    """Why a request was refused: one readable line per problem, each naming its field."""

    errors: list[str]


class DeployResponse(BaseModel):
    """A prediction, the curves for plotting and the server-side compute time."""

    prediction: dict[str, Any] = Field(description="Exactly `ecdsim deploy --json` (docs/json.md).")
    trajectories: dict[str, Any] = Field(
        description="time_s, and per method angle_rad / speed_rad_s as [temperature][time]."
    )
    sweep: dict[str, Any] = Field(
        description="temperature_C and per method deployment_time_s (null where it stalls)."
    )
    toml: str = Field(description="The configuration as TOML (what /api/config.toml returns).")
    compute_ms: float = Field(description="Server-side time of the computation [ms].")
    display_units: Literal["si", "us"] = Field(
        description="The unit system to show the numbers in (the request's `units`, else the "
        "config's `[output] units`, else si)."
    )
    units: dict[str, Any] = Field(
        description="Every kind of quantity's display unit in that system: "
        "{kind: {unit, scale, offset}}, shown = SI value * scale + offset."
    )
    key_units: dict[str, str] = Field(
        description="The display unit label of every unit-bearing key in prediction, "
        "trajectories and sweep (e.g. temperature_C: degF)."
    )


class ExampleResponse(BaseModel):
    """The configuration the explorer starts from."""

    config: dict[str, Any]
    toml: str
    source: str
    display_units: Literal["si", "us"] = Field(
        "si", description="The config's `[output] units` (si if absent or unreadable)."
    )
    units: dict[str, Any] = Field(
        default_factory=dict,
        description="Every kind of quantity's display unit in display_units (as in /api/deploy).",
    )


# Every refusal is JSON, whatever the endpoint's own response type (the report is HTML):
# say so in the schema, so that the OpenAPI document matches what is sent.
_PROBLEM_JSON = {
    "content": {"application/json": {"schema": {"$ref": "#/components/schemas/ProblemDetail"}}}
}
_ERRORS: dict[int | str, dict[str, Any]] = {
    400: {"description": "Body is not JSON (FastAPI's own refusal)", **_PROBLEM_JSON},
    413: {"description": "Request body too large", **_PROBLEM_JSON},
    422: {"description": "Invalid input, one line per problem", **_PROBLEM_JSON},
}
# The largest request body read: a config is a few kB; anything near this is not one.
MAX_BODY_BYTES = 1_000_000
# The longest a computation may hold a request [s]; the paper example takes ~0.05 s and
# the largest request the limits allow (50 temperatures, dynamics) a few seconds.
COMPUTE_LIMIT_S = 60.0
_LIMITED: dict[int | str, dict[str, Any]] = {
    **_ERRORS,
    503: {"description": "The computation took longer than the time limit", **_PROBLEM_JSON},
}


async def within_time_limit(
    job: Callable[..., Reply], args: tuple[Any, ...], limit_s: float
) -> Response:
    """``job(*args)`` in a worker process (:mod:`ecdsim.webapp.workers`), for at most
    ``limit_s`` seconds, off the event loop: other requests are served meanwhile.

    Past the limit the client gets 503 and the worker is killed, so the computation stops
    using the CPU then (a thread, as before, ran on in the background). A request that
    finds every worker busy waits for one within the same limit.
    """
    import anyio

    pool = shared_pool(preload=(__name__,))  # the workers import this module as they start
    try:
        reply = await anyio.to_thread.run_sync(pool.call, job, args, limit_s)
    except Timeout:
        raise HTTPException(
            status_code=503,
            detail=[
                f"computation: took longer than {limit_s:g} s and was stopped; ask for "
                "fewer temperatures, points or a shorter stop_time"
            ],
        ) from None
    except Busy:
        raise HTTPException(
            status_code=503,
            detail=[
                f"computation: not started within {limit_s:g} s: the server's {pool.size} "
                "workers were busy; try again"
            ],
        ) from None
    except WorkerDied:
        _LOG.error("a computation's worker process ended while computing")
        raise HTTPException(
            status_code=500,
            detail=["internal error (the computation's process ended); please report it"],
        ) from None
    if reply.defect is not None:
        _LOG.error("internal error in a computation:\n%s", reply.defect)
    return Response(
        reply.body, status_code=reply.status, media_type=reply.media_type, headers=reply.headers
    )


def deploy_job(
    config: dict[str, Any],
    units: UnitSystem | None,
    time_points: int,
    sweep_points: int,
    default_units: UnitSystem | None,
) -> Reply:
    """``POST /api/deploy``'s computation (in a worker): the prediction and its curves."""

    def compute() -> Response:
        loaded, text = load_body(config)
        began = time.perf_counter()
        prediction = _predict(loaded)
        document = prediction.to_dict()
        extra = curves(prediction, loaded, time_points, sweep_points)
        elapsed = 1000.0 * (time.perf_counter() - began)
        system = display_system(loaded, units, default_units)
        document["display_units"] = system
        for warning in document["warnings"]:
            # The message stays SI (stable JSON); the page shows this one.
            warning["display_message"] = convert_text(warning["message"], system)
        payload = {
            "prediction": document,
            **extra,
            "toml": text,
            "compute_ms": elapsed,
            **display_block(system, document, extra),
        }
        return Response(json.dumps(payload, allow_nan=False), media_type="application/json")

    return as_reply(compute)


def report_job(
    config: dict[str, Any], units: UnitSystem | None, default_units: UnitSystem | None
) -> Reply:
    """``POST /api/report``'s computation (in a worker): the HTML report."""

    def compute() -> Response:
        if is_wing(config):  # the wing's report (ecdsim.report.wing)
            from ecdsim.webapp.wingapi import wing_report_response

            return wing_report_response(config, units, default_units, _refuse, body_text)
        loaded, text = load_body(config)
        system = display_system(loaded, units, default_units)
        html = render_html(loaded, _predict(loaded), text, system)
        return HTMLResponse(
            html, headers={"Content-Disposition": 'attachment; filename="ecdsim-report.html"'}
        )

    return as_reply(compute)


def _refuse(problems: list[str]) -> HTTPException:
    return HTTPException(status_code=422, detail=problems)


def body_text(raw: dict[str, Any]) -> str:
    """A config's TOML text; HTTP 422 if it is nested too deeply or has no TOML form."""
    if nesting_depth(raw) > MAX_NESTING:
        # Bounded before anything walks it (to_toml and the TOML reader recurse).
        raise _refuse([f"config: nested too deeply (at most {MAX_NESTING} levels)"])
    try:
        return to_toml(raw)
    except UnrepresentableError as exc:
        raise _refuse([f"config.{exc}"]) from None


def load_body(raw: dict[str, Any]) -> tuple[Config, str]:
    """The validated config and its TOML text; HTTP 422 with every problem if invalid
    (a wing file: one line naming ``POST /api/wing``)."""
    text = body_text(raw)
    if is_wing(raw):
        raise _refuse([WING_REFUSAL])
    try:
        config = parse_config(text, "config")
    except ConfigError as exc:
        raise _refuse(str(exc).splitlines()) from None
    if len(config.temperatures) > MAX_TEMPERATURES:
        raise _refuse(
            [f"analysis.temperatures: {len(config.temperatures)} given; at most {MAX_TEMPERATURES}"]
        )
    return config, text


def _load_wing(raw: dict[str, Any]) -> WingConfig:
    """A wing file's config validated; HTTP 422 with every problem if invalid."""
    try:
        return load_wing_text(body_text(raw))
    except ConfigError as exc:
        raise _refuse(str(exc).splitlines()) from None


def display_system(
    config: Config | WingConfig, asked: str | None, default: UnitSystem | None = None
) -> UnitSystem:
    """The unit system to show: the request's, else ``default`` (``ecdsim app --units``),
    else the config's ``[output] units``."""
    if asked is not None:
        return check_system(asked)
    return default if default is not None else check_system(config.spec.output.units)


def display_block(system: UnitSystem, *documents: Any) -> dict[str, Any]:
    """The response fields that say how to show its SI numbers (docs/json.md#display-units)."""
    return {
        "display_units": system,
        "units": describe(system),
        "key_units": key_units(list(documents), system),
    }


def _raw_system(raw: dict[str, Any]) -> UnitSystem:
    """The ``[output] units`` of a parsed TOML document, si if absent or not a system."""
    output = raw.get("output")
    value = output.get("units", "si") if isinstance(output, dict) else "si"
    return "us" if value == "us" else "si"


def _predict(config: Config) -> Prediction:
    try:
        return predict_config(config)
    except ModelDomainError as exc:
        raise _refuse([str(exc)]) from None


def _finite_or_none(values: Any) -> list[float | None]:
    return [float(v) if np.isfinite(v) else None for v in np.ravel(values)]


def curves(
    prediction: Prediction, config: Config, time_points: int, sweep_points: int
) -> dict[str, Any]:
    """Angle and speed against time, and deployment time against temperature (a sweep)."""
    from ecdsim.plotting import time_span

    times = np.linspace(0.0, time_span(prediction), time_points)
    n_temps = prediction.temperatures.size
    trajectories: dict[str, Any] = {"time_s": times.tolist(), "methods": {}}
    for name in prediction.solutions:
        trajectory = prediction.trajectory(name, times)
        angle = np.asarray(trajectory.angle).reshape(time_points, n_temps)
        speed = np.asarray(trajectory.speed).reshape(time_points, n_temps)
        trajectories["methods"][name] = {
            "angle_rad": [_finite_or_none(angle[:, j]) for j in range(n_temps)],
            "speed_rad_s": [_finite_or_none(speed[:, j]) for j in range(n_temps)],
        }
    sweep: dict[str, Any] = {"temperature_C": [], "methods": {}}
    if sweep_points > 0:
        low, high = min(config.temperatures), max(config.temperatures)
        temps = np.linspace(low, high, sweep_points) if high > low else np.array([low])
        swept = predict(config.system, temps, config.methods, dynamics=config.spec.dynamics())
        sweep["temperature_C"] = temps.tolist()
        for name, solution in swept.solutions.items():
            sweep["methods"][name] = {
                "deployment_time_s": _finite_or_none(solution.deployment_time)
            }
    return {"trajectories": trajectories, "sweep": sweep}


# The longest a client may take to send a request's body [s]: 1,000,000 bytes (the
# limit) at 33 kB/s. A client that promises a Content-Length and sends it a byte at a
# time would otherwise hold its connection and a request open for ever.
BODY_TIMEOUT_S = 30.0


class BodyLimit:
    """ASGI middleware: refuse a request body over ``limit`` bytes with 413 and JSON, and
    one not received within ``timeout_s`` seconds with 408.

    The body is read (up to the limit) before the app sees it and then replayed, so that
    a body without a Content-Length header is bounded too.
    """

    def __init__(self, app: Any, limit: int, timeout_s: float = BODY_TIMEOUT_S) -> None:
        self.app = app
        self.limit = limit
        self.timeout_s = timeout_s

    async def __call__(self, scope: Any, receive: Any, send: Any) -> None:
        """Pass the request on with its body read, or answer 413 or 408."""
        import anyio

        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        chunks: list[bytes] = []
        size = 0
        more = True
        deadline = anyio.current_time() + self.timeout_s
        while more:
            message = None
            with anyio.move_on_after(max(deadline - anyio.current_time(), 0.0)):
                message = await receive()
            if message is None:
                await _too_slow(self.timeout_s, size, scope, send)
                return
            if message["type"] != "http.request":
                await self.app(scope, _replay([message]), send)
                return
            chunk = message.get("body", b"")
            size += len(chunk)
            if size > self.limit:
                await _too_large(self.limit, send)
                return
            chunks.append(chunk)
            more = message.get("more_body", False)
        body = {"type": "http.request", "body": b"".join(chunks), "more_body": False}
        await self.app(scope, _replay([body], receive), send)


class HostCheck:
    """ASGI middleware: answer only requests addressed to this server by a name it has.

    The explorer has no authentication; what keeps other web pages out is the browser's
    same-origin rule, which DNS rebinding defeats: a page from ``evil.example`` whose
    name then resolves to 127.0.0.1 reads ``/api/example`` (the user's config) as its
    own origin. Its requests carry ``Host: evil.example``; so a request is answered only
    when its Host names an IP address (a page served from an address is that server's
    own), ``localhost`` or a name under ``.localhost`` (which browsers resolve to the
    loopback themselves, RFC 6761), or the name the server was bound to (``--host``;
    with a wildcard address, also this machine's host name). Anything else is refused
    with 400 and one line saying which names are answered. A request without a Host
    header (HTTP/1.0; browsers always send one) passes.
    """

    def __init__(self, app: Any, names: frozenset[str]) -> None:
        self.app = app
        self.names = names

    async def __call__(self, scope: Any, receive: Any, send: Any) -> None:
        """Pass a request whose Host is one of this server's names; refuse the rest."""
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        raw = next((v for k, v in scope.get("headers", []) if k == b"host"), None)
        if raw is None or host_is_ours(raw.decode("latin-1"), self.names):
            await self.app(scope, receive, send)
            return
        problem = (
            f"host: {quoted(raw.decode('latin-1'))} is not a name of this server; open it as "
            "localhost or by its address (other names are refused against DNS rebinding)"
        )
        await _json_response(400, {"errors": [problem]}, send)


def host_name(header: str) -> str:
    """The name in a Host header, without the port, lower case, without a final dot.

    >>> host_name("LocalHost.:8765"), host_name("[::1]:8765"), host_name("10.0.0.5")
    ('localhost', '::1', '10.0.0.5')
    """
    text = header.strip()
    if text.startswith("["):  # an IPv6 literal
        return text[1:].partition("]")[0].lower()
    if text.count(":") > 1:  # an IPv6 address without brackets (as --host takes it)
        return text.lower()
    return text.rpartition(":")[0].lower().rstrip(".") if ":" in text else text.lower().rstrip(".")


def host_is_ours(header: str, names: frozenset[str]) -> bool:
    """True if a request's Host header addresses this server (:class:`HostCheck`)."""
    import ipaddress

    name = host_name(header)
    try:
        ipaddress.ip_address(name)
    except ValueError:
        return name == "localhost" or name.endswith(".localhost") or name in names
    return True


WILDCARD_HOSTS = frozenset({"0.0.0.0", "::", ""})


def server_names(host: str | None) -> frozenset[str]:
    """The names :class:`HostCheck` answers besides addresses and localhost: the bound
    ``host`` and, bound to every interface, this machine's names."""
    if host is None:
        return frozenset()
    names = {host_name(host)}
    if host in WILDCARD_HOSTS:
        import socket

        names |= {socket.gethostname().lower(), socket.getfqdn().lower()}
    return frozenset(names)


def exposure_warning(host: str, port: int) -> str | None:
    """One line warning that ``--host`` makes the explorer reachable from other machines,
    or None for a loopback address (``127.0.0.1``, ``::1``, ``localhost``)."""
    import ipaddress

    try:
        loopback = ipaddress.ip_address(host_name(host)).is_loopback
    except ValueError:
        loopback = host_name(host) == "localhost"
    if loopback:
        return None
    return (
        f"warning: --host {host} makes the explorer reachable from other machines on port "
        f"{port}, and it has no authentication: anyone who reaches it reads your config "
        "and uses this machine's CPU; keep 127.0.0.1 unless the network is trusted"
    )


class InternalErrorAsJson:
    """ASGI middleware: an unexpected exception becomes a JSON 500, and is not re-raised.

    Logged with its traceback for the developer; the client gets one line and a response
    that completes normally, so its kept-alive connection stays usable.
    """

    def __init__(self, app: Any) -> None:
        self.app = app

    async def __call__(self, scope: Any, receive: Any, send: Any) -> None:
        """Run the app; on an exception before the response started, answer 500."""
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        started = False

        async def tracking_send(message: Any) -> None:
            nonlocal started
            if message["type"] == "http.response.start":
                started = True
            await send(message)

        try:
            await self.app(scope, receive, tracking_send)
        except Exception as exc:
            _LOG.exception("internal error answering %s", scope.get("path", "?"))
            if started:  # nothing sensible left to send; let the server close it
                raise
            message = f"internal error ({type(exc).__name__}); please report it"
            await _json_response(500, {"errors": [message]}, send)


def _replay(messages: list[Any], then: Any = None) -> Any:
    queue = list(messages)

    async def receive() -> Any:
        if queue:
            return queue.pop(0)
        if then is not None:
            return await then()
        return {"type": "http.disconnect"}

    return receive


async def _too_slow(timeout_s: float, size: int, scope: Any, send: Any) -> None:
    promised = next(
        (v.decode("latin-1") for k, v in scope.get("headers", []) if k == b"content-length"),
        None,
    )
    of = f" of the {promised} its Content-Length promised" if promised is not None else ""
    problem = f"body: not received within {timeout_s:g} s ({size} bytes arrived{of})"
    await _json_response(408, {"errors": [problem]}, send, close=True)


async def _too_large(limit: int, send: Any) -> None:
    await _json_response(413, {"errors": [f"body: larger than {limit} bytes"]}, send)


async def _json_response(status: int, content: Any, send: Any, *, close: bool = False) -> None:
    payload = json.dumps(content).encode()
    headers = [
        (b"content-type", b"application/json"),
        (b"content-length", str(len(payload)).encode()),
    ]
    if close:  # the rest of the request is not read: the connection cannot be reused
        headers.append((b"connection", b"close"))
    await send({"type": "http.response.start", "status": status, "headers": headers})
    await send({"type": "http.response.body", "body": payload})


def create_app(
    config_text: str | None = None,
    units: UnitSystem | None = None,
    *,
    compute_limit_s: float | None = None,
    host: str | None = None,
    body_timeout_s: float = BODY_TIMEOUT_S,
) -> FastAPI:
    """The explorer app, starting from ``config_text`` (TOML) or the paper's example.

    ``units`` (``ecdsim app --units``) is the display unit system of a request that does
    not choose one; None leaves it to each config's ``[output] units``.
    ``compute_limit_s``: the longest a computation may run (default
    :data:`COMPUTE_LIMIT_S`); past it the request gets 503 and the computation is stopped.
    ``host``: the address the server is bound to (``ecdsim app --host``); requests must
    address it by that name, an IP address or localhost (:class:`HostCheck`).
    ``body_timeout_s``: the longest a client may take to send a request's body (408).
    """
    start_text = config_text if config_text is not None else EXAMPLE_CONFIG.read_text("utf-8")
    source = "your config" if config_text is not None else "paper example (section 6)"
    example_text = EXAMPLE_CONFIG.read_text("utf-8")

    app = FastAPI(
        title="ecdsim explorer API",
        version=__version__,
        description=(
            "Deployment predictions for eddy current dampers (docs/report.md). Configs are "
            "JSON with the TOML file's keys and unit strings; invalid input gives 422 with "
            "one message per problem."
        ),
    )

    @app.exception_handler(RequestValidationError)
    async def _invalid(request: Request, exc: RequestValidationError) -> JSONResponse:
        problems = []
        for error in exc.errors():
            where = ".".join(str(p) for p in error.get("loc", ()) if p != "body") or "body"
            problems.append(f"{where}: {error.get('msg', 'invalid')}")
        return JSONResponse(status_code=422, content={"errors": problems})

    # A defect, not the user's fault: answered as JSON by a middleware that does not
    # re-raise. (An exception handler for Exception runs in Starlette's outermost
    # ServerErrorMiddleware, which re-raises after answering; uvicorn then closes the
    # connection, so a kept-alive client's next request could meet a reset.)
    app.add_middleware(InternalErrorAsJson)
    app.add_middleware(BodyLimit, limit=MAX_BODY_BYTES, timeout_s=body_timeout_s)
    app.add_middleware(HostCheck, names=server_names(host))  # outermost: checked first

    # Starlette's class: FastAPI's own refusals (400 for a body that is not JSON, 404,
    # 405) derive from it, and they too answer with the errors list.
    @app.exception_handler(StarletteHTTPException)
    async def _refused(request: Request, exc: StarletteHTTPException) -> JSONResponse:
        raw: Any = exc.detail
        detail = raw if isinstance(raw, list) else [str(raw)]
        # Keep the refusal's headers: a 405 must say which methods are allowed (RFC 9110).
        return JSONResponse(
            status_code=exc.status_code, content={"errors": detail}, headers=exc.headers
        )

    @app.get("/", response_class=HTMLResponse, include_in_schema=False)
    def index() -> FileResponse:
        return FileResponse(STATIC / "index.html", media_type="text/html")

    @app.get("/static/app.js", include_in_schema=False)
    def app_js() -> FileResponse:
        return FileResponse(STATIC / "app.js", media_type="text/javascript")

    @app.get("/static/wing.js", include_in_schema=False)
    def wing_js() -> FileResponse:
        return FileResponse(STATIC / "wing.js", media_type="text/javascript")

    @app.get("/static/plotly.min.js", include_in_schema=False)
    def plotly_js() -> FileResponse:
        import plotly

        path = Path(plotly.__file__).parent / "package_data" / "plotly.min.js"
        return FileResponse(path, media_type="text/javascript")

    @app.get("/api/example", response_model=ExampleResponse)
    def example(which: str = "start") -> dict[str, Any]:
        """The configuration the explorer starts from, or (which=paper) the paper's example."""
        if which not in {"start", "paper"}:
            raise _refuse([f"which: {which!r} is not one of 'start', 'paper'"])
        text = example_text if which == "paper" else start_text
        raw = tomllib.loads(text)
        system = units if units is not None else _raw_system(raw)
        return {
            "config": raw,
            "toml": text,
            "source": "paper example (section 6)" if which == "paper" else source,
            "display_units": system,
            "units": describe(system),
        }

    limit_s = COMPUTE_LIMIT_S if compute_limit_s is None else compute_limit_s

    async def limited(job: Callable[..., Reply], args: tuple[Any, ...]) -> Response:
        # Refused here, before pickling for the worker recurses through it; the worker's
        # reader applies the exact limit (a request body holds the config one level down).
        if nesting_depth(args, MAX_NESTING + 2) > MAX_NESTING + 2:
            raise _refuse([f"config: nested too deeply (at most {MAX_NESTING} levels)"])
        return await within_time_limit(job, args, limit_s)

    @app.post("/api/deploy", response_model=DeployResponse, responses=_LIMITED)
    async def deploy(body: DeployBody) -> Response:
        """Predict the deployment of a config, as `ecdsim deploy --json`, plus curves."""
        args = (body.config, body.units, body.time_points, body.sweep_points, units)
        return await limited(deploy_job, args)

    @app.post("/api/config/parse", response_model=ExampleResponse, responses=_ERRORS)
    def parse(body: TomlBody) -> dict[str, Any]:
        """Validate TOML text and return it as the JSON config the API takes."""
        try:
            raw = parse_toml(body.toml)
        except ConfigError as exc:
            raise _refuse([f"toml: {problem}" for problem in exc.problems]) from None
        if is_wing(raw):
            wing = _load_wing(raw)
            system = display_system(wing, None, units)
        else:
            config, _ = load_body(raw)
            system = display_system(config, None, units)
        return {
            "config": raw,
            "toml": body.toml,
            "source": "uploaded",
            "display_units": system,
            "units": describe(system),
        }

    @app.post(
        "/api/config.toml",
        response_class=Response,
        responses={200: {"content": {"application/toml": {}}}, **_ERRORS},
    )
    def config_toml(body: ConfigBody) -> Response:
        """The (edited) config as a TOML file to download."""
        if is_wing(body.config):
            text = body_text(body.config)
            _load_wing(body.config)
        else:
            _, text = load_body(body.config)
        return Response(
            text,
            media_type="application/toml",
            headers={"Content-Disposition": 'attachment; filename="ecdsim-config.toml"'},
        )

    @app.post(
        "/api/report",
        response_class=HTMLResponse,
        responses={200: {"content": {"text/html": {}}}, **_LIMITED},
    )
    async def report(body: ReportBody) -> Response:
        """The self-contained HTML report of the config (as `ecdsim report`)."""
        return await limited(report_job, (body.config, body.units, units))

    # The bench fit (drop test) has its own module: ecdsim.webapp.fitapi.
    from ecdsim.webapp.fitapi import ServerHelpers, add_fit_routes

    add_fit_routes(app, _LIMITED, ServerHelpers(_refuse, load_body, limited))
    # A wing file (docs/wing.md): its own endpoint, ecdsim.webapp.wingapi.
    from ecdsim.webapp.wingapi import WingHelpers, add_wing_routes

    add_wing_routes(app, _LIMITED, WingHelpers(_refuse, body_text, limited, display_block), units)
    return app
