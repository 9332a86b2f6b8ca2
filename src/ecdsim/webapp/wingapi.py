"""The explorer's wing: a wing file in, each hinge's angle and the unfolding wing out.

``POST /api/wing`` takes a wing file's content as JSON (the TOML file's tables and keys,
quantities as unit strings, as every explorer endpoint) and solves it with
:func:`ecdsim.wing.solver.deploy_wing`, exactly as ``ecdsim deploy WING.toml`` does: the
answer's ``result`` is the document of ``ecdsim deploy WING.toml --json``. Beside it,
per temperature, the frames of the animation: at the solution's own time samples, each
hinge's deployed angle and the panels' outlines in the plane, computed by
:func:`ecdsim.plotting_wing.drawn_outlines`, the function the ``--plot`` shape strip
draws (one source). A solution with more samples than :func:`frame_limit` allows
(:data:`MAX_FRAMES`, fewer with more than five temperatures) is thinned to that many of
its own samples (evenly by index, the first and last kept): no frame is interpolated.

``POST /api/report`` answers a wing file with the wing's report
(:func:`wing_report_response`, as ``ecdsim report WING.toml``); the other single-hinge
endpoints refuse a wing file with one line naming this one.
"""

from __future__ import annotations

import json
import time
from collections.abc import Awaitable, Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
from fastapi import FastAPI, HTTPException
from fastapi.responses import Response
from pydantic import BaseModel, ConfigDict, Field

if TYPE_CHECKING:
    from ecdsim.config.wing_schema import WingConfig
    from ecdsim.units_display import UnitSystem
    from ecdsim.webapp.workers import Reply
    from ecdsim.wing.model import Wing
    from ecdsim.wing.result import WingCase

# The most frames (time samples) sent per temperature: enough for a smooth animation,
# few enough that three temperatures of a three-panel wing stay under about 1 MB of JSON
# (the example wing has 490 to 560 samples per temperature: all are sent).
MAX_FRAMES = 600
# The most frames over all temperatures (a three-panel wing's frame is 24 numbers: 3000
# frames are some 1.5 MB of JSON); with more than five temperatures each gets fewer, at
# least MIN_FRAMES.
MAX_TOTAL_FRAMES = 3000
MIN_FRAMES = 100
# The most temperatures of one request, as for a single hinge (the server's
# MAX_TEMPERATURES is this number: the server imports this module, not the reverse).
MAX_TEMPERATURES = 50
# The line a single-hinge endpoint answers a wing file with.
WING_REFUSAL = (
    "config: a wing file ([wing]) is not a single hinge's config; the explorer solves it "
    "with POST /api/wing (docs/explorer.md)"
)


def is_wing(raw: object) -> bool:
    """True for a config (the API's JSON form of a TOML file) that is a wing file."""
    return isinstance(raw, dict) and "wing" in raw


class WingBody(BaseModel):
    """A wing file's content as JSON, and the display unit system."""

    model_config = ConfigDict(
        extra="forbid",
        json_schema_extra={
            "examples": [
                {
                    "config": {
                        "wing": {
                            "panels": [{"mass": "1 kg", "length": "0.5 m",
                                        "cg_along": "0.25 m", "inertia": "0.0208 kg*m^2"}],
                            "hinges": [{"stowed_angle": "90 deg", "deployed_angle": "0 deg",
                                        "start_torque": "3.73 N*m", "end_torque": "1.58 N*m",
                                        "ecd": "none"}],
                        }
                    }
                }
            ]
        },
    )  # fmt: skip

    config: dict[str, Any] = Field(
        description="The wing file: same tables and keys as the TOML file (docs/wing.md)."
    )
    units: Literal["si", "us"] | None = Field(
        None,
        description="Display unit system of the response (`si` or `us`); null: the "
        "file's `[output] units` (si if absent). Numbers stay SI either way.",
    )


class WingResponse(BaseModel):
    """A wing's deployment, the animation's frames and the server-side compute time."""

    result: dict[str, Any] = Field(description="Exactly `ecdsim deploy WING.toml --json`.")
    panels: list[str] = Field(description="The panels' names, root first.")
    hinges: list[str] = Field(description="The hinges' names, root first.")
    travel_rad: list[float] = Field(description="Each hinge's travel (its latch's angle).")
    extent_m: float = Field(description="The wing's length, root hinge to tip.")
    stowed_outlines_m: list[Any] = Field(
        description="The panels' drawn outlines stowed: [panel][corner][x, y]."
    )
    deployed_outlines_m: list[Any] = Field(
        description="The panels' drawn outlines deployed (every hinge at its latch)."
    )
    cases: list[dict[str, Any]] = Field(
        description="Per temperature: temperature_C, time_s (the frames' times, the "
        "solution's own samples), angle_rad [hinge][frame] and outlines_m "
        "[frame][panel][corner][x, y]."
    )
    toml: str = Field(description="The wing file as TOML (what /api/config.toml returns).")
    compute_ms: float = Field(description="Server-side time of the computation [ms].")
    display_units: Literal["si", "us"]
    units: dict[str, Any] = Field(description="{kind: {unit, scale, offset}} as /api/deploy.")
    key_units: dict[str, str] = Field(description="The display unit of every key with a unit.")


def frame_indices(samples: int, limit: int = MAX_FRAMES) -> list[int]:
    """Indices of the samples shown as frames: all of them, or ``limit`` spread evenly
    by index with the first and the last kept.

    >>> frame_indices(5), frame_indices(10, 4)
    ([0, 1, 2, 3, 4], [0, 3, 6, 9])
    """
    if samples <= limit:
        return list(range(samples))
    return sorted({int(round(k)) for k in np.linspace(0, samples - 1, limit)})


def _outlines(wing: Wing, angles: Any) -> list[Any]:
    from ecdsim.plotting_wing import drawn_outlines

    result: list[Any] = drawn_outlines(wing, np.asarray(angles, dtype=float)).tolist()
    return result


def frame_limit(temperatures: int) -> int:
    """The most frames of each temperature when ``temperatures`` are solved at once.

    >>> frame_limit(3), frame_limit(10), frame_limit(50)
    (600, 300, 100)
    """
    return max(MIN_FRAMES, min(MAX_FRAMES, MAX_TOTAL_FRAMES // max(temperatures, 1)))


def case_frames(wing: Wing, case: WingCase, limit: int = MAX_FRAMES) -> dict[str, Any]:
    """One temperature's frames: times, each hinge's angle and the outlines (module notes)."""
    chosen = frame_indices(case.time.shape[0], limit)
    angles = case.angle[chosen]
    return {
        "temperature_C": case.temperature,
        "time_s": case.time[chosen].tolist(),
        "angle_rad": [angles[:, j].tolist() for j in range(case.hinges)],
        "outlines_m": [_outlines(wing, row) for row in angles],
    }


def wing_document(config: WingConfig) -> dict[str, Any]:
    """The result and the frames of a validated wing file (the answer's SI part)."""
    from ecdsim.wing.solver import deploy_wing

    wing = config.wing
    result = deploy_wing(
        wing, list(config.temperatures), rtol=config.rtol, stop_time=config.stop_time
    )
    return {
        "result": result.to_dict(),
        "panels": [panel.name for panel in wing.panels],
        "hinges": list(result.hinges),
        "travel_rad": wing.travels.tolist(),
        "extent_m": float(sum(panel.length for panel in wing.panels)),
        "stowed_outlines_m": _outlines(wing, np.zeros(wing.size)),
        "deployed_outlines_m": _outlines(wing, wing.travels),
        "cases": [case_frames(wing, case, frame_limit(len(result.cases))) for case in result.cases],
    }


def load_wing_text(text: str) -> WingConfig:
    """A wing file's TOML text validated (catalogue files relative to the working folder);
    :class:`ecdsim.config.ConfigError` lists every problem."""
    from ecdsim.config.wing_schema import parse_wing_config
    from ecdsim.sizing.catalogue import load_catalogue

    return parse_wing_config(text, "config", Path(), load_catalogue)


Limited = Callable[[Callable[..., "Reply"], tuple[Any, ...]], Awaitable[Response]]


@dataclass(frozen=True)
class WingHelpers:
    """What the route borrows from the explorer's server (handed over by it, so that this
    module never imports the server that imports it)."""

    refuse: Callable[[list[str]], HTTPException]
    to_text: Callable[[dict[str, Any]], str]
    limited: Limited
    display_block: Callable[..., dict[str, Any]]


def _solved(
    raw: dict[str, Any],
    refuse: Callable[..., HTTPException],
    to_text: Callable[..., str],
) -> tuple[WingConfig, str]:
    """The request's wing file validated, and its TOML text; 422 with every problem."""
    from ecdsim.config import ConfigError

    text = to_text(raw)
    try:
        config = load_wing_text(text)
    except ConfigError as exc:
        raise refuse(str(exc).splitlines()) from None
    if len(config.temperatures) > MAX_TEMPERATURES:
        raise refuse(
            [f"analysis.temperatures: {len(config.temperatures)} given; at most {MAX_TEMPERATURES}"]
        )
    return config, text


def _system(config: WingConfig, units: str | None, default_units: str | None) -> UnitSystem:
    """The request's units, else ``ecdsim app --units``, else the file's ``[output] units``."""
    from ecdsim.units_display import check_system

    chosen = units if units is not None else default_units
    return check_system(chosen if chosen is not None else config.spec.output.units)


def wing_report_response(
    raw: dict[str, Any],
    units: str | None,
    default_units: str | None,
    refuse: Callable[..., HTTPException],
    to_text: Callable[..., str],
) -> Response:
    """``POST /api/report`` for a wing file (in a worker): the wing's HTML report, as
    ``ecdsim report WING.toml`` writes it (:mod:`ecdsim.report.wing`)."""
    from fastapi.responses import HTMLResponse

    from ecdsim.report.wing import render_wing_html
    from ecdsim.wing.solver import deploy_wing

    config, text = _solved(raw, refuse, to_text)
    try:
        result = deploy_wing(
            config.wing, list(config.temperatures), rtol=config.rtol, stop_time=config.stop_time
        )
    except ValueError as exc:  # WingUnsupported: what the solver does not take yet
        raise refuse([f"config: {exc}"]) from None
    html = render_wing_html(config, result, text, _system(config, units, default_units))
    return HTMLResponse(
        html, headers={"Content-Disposition": 'attachment; filename="ecdsim-report.html"'}
    )


def wing_job(
    raw: dict[str, Any],
    units: str | None,
    default_units: str | None,
    helpers: tuple[Callable[..., Any], Callable[..., Any], Callable[..., Any]],
) -> Reply:
    """``POST /api/wing``'s computation (in a worker): the result and its frames."""
    from ecdsim.webapp.workers import as_reply

    refuse, to_text, display_block = helpers

    def compute() -> Response:
        config, text = _solved(raw, refuse, to_text)
        began = time.perf_counter()
        try:
            document = wing_document(config)
        except ValueError as exc:  # WingUnsupported: what the solver does not take yet
            raise refuse([f"config: {exc}"]) from None
        elapsed = 1000.0 * (time.perf_counter() - began)
        system = _system(config, units, default_units)
        payload = {
            **document,
            "toml": text,
            "compute_ms": elapsed,
            **display_block(system, document),
        }
        return Response(json.dumps(payload, allow_nan=False), media_type="application/json")

    return as_reply(compute)


def add_wing_routes(
    app: FastAPI,
    errors: dict[int | str, dict[str, Any]],
    server: WingHelpers,
    default_units: str | None,
) -> None:
    """Register ``POST /api/wing`` on the explorer app."""

    @app.post("/api/wing", response_model=WingResponse, responses=errors)
    async def wing_endpoint(body: WingBody) -> Response:
        """Solve a wing file as `ecdsim deploy WING.toml --json`, with the animation's frames."""
        helpers = (server.refuse, server.to_text, server.display_block)
        return await server.limited(wing_job, (body.config, body.units, default_units, helpers))


__all__ = [
    "MAX_FRAMES",
    "MAX_TEMPERATURES",
    "WING_REFUSAL",
    "add_wing_routes",
    "case_frames",
    "frame_indices",
    "frame_limit",
    "is_wing",
    "load_wing_text",
    "wing_document",
    "wing_report_response",
]
