"""The explorer's bench fit: a drop-test CSV in, the fit of ``ecdsim fit drop-test`` out.

``POST /api/fit/drop-test`` takes the CSV text (what the page reads from a dropped file)
and runs :func:`ecdsim.characterize.droptest.fit_drop_test` on it, exactly as the CLI
does: the answer's ``fit`` is the document of ``ecdsim fit drop-test --json``. Beside it,
the curves of the paper's Fig. 8 (drive torque against speed per temperature with each
line) and of the laws over temperature with their 95 % bands, and, where the fitted ECD
can be written, the parameter file of ``ecdsim fit drop-test -o FILE --config CONFIG``
(``toml``, and ``config`` as the API's JSON form) so that the page can use the fitted
damper in the model: the request's config as written, with the fitted ECD in place of
its ``[damper]`` and ``[gearbox]``. With no ``config`` in the request the file's
``[load]`` is the CLI's marked placeholder.
"""

from __future__ import annotations

import math
import re
import tempfile
import tomllib
from collections.abc import Awaitable, Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
from fastapi import FastAPI, HTTPException
from fastapi.responses import Response
from pydantic import BaseModel, ConfigDict, Field

if TYPE_CHECKING:
    from ecdsim.characterize.droptest import DropTestResult
    from ecdsim.characterize.stats import Estimate
    from ecdsim.config import Config
    from ecdsim.webapp.workers import Reply

# A dropped file is read whole into the request: the body limit (1,000,000 bytes) bounds
# it too; this bound is on the decoded text, for a clear message.
MAX_CSV_CHARS = 900_000
# The name the request's config goes by in the parameter file's header: the file name
# under which the page exports the same config (/api/config.toml).
CONFIG_NAME = "ecdsim-config.toml"
# Samples of each law over temperature for the plots.
LAW_POINTS = 61
_SAFE_NAME = re.compile(r"[^A-Za-z0-9._-]+")


class FitBody(BaseModel):
    """A drop-test CSV file's text, and how to fit it (as ``ecdsim fit drop-test``)."""

    model_config = ConfigDict(extra="forbid")

    csv: str = Field(
        max_length=MAX_CSV_CHARS,
        description="The drop-test CSV file's text: unit-bearing headers (docs/characterize.md).",
    )
    filename: str = Field(
        "drop_test.csv",
        min_length=1,
        max_length=200,
        description="The file's name, shown as the data source.",
    )
    reference_temperature: float = Field(
        25.0,
        ge=-273.15,
        le=1000.0,
        allow_inf_nan=False,
        description="T_ref of the damping laws [degC] (--reference-temperature).",
    )
    noise: Literal["torque", "timing"] = Field("torque", description="--noise model.")
    units: Literal["si", "us"] | None = Field(
        None,
        description="Display unit system recorded in fit.display_units (--units); null: "
        "the config's [output] units, si without a config. Numbers stay SI.",
    )
    config: dict[str, Any] | None = Field(
        None,
        description="The configuration the fitted ECD goes into (--config): the parameter "
        "file is it with the fit's [damper] and [gearbox]; same JSON form as /api/deploy. "
        "Without it the load is a marked placeholder.",
    )


class FitResponse(BaseModel):
    """The fit, the curves to plot it and the fitted configuration."""

    fit: dict[str, Any] = Field(
        description="Exactly `ecdsim fit drop-test --json [--units U]` (source: the file name)."
    )
    curves: dict[str, Any] = Field(
        description="torque_speed: per temperature the points and line; laws: the laws "
        "over temperature_C with 95 % bands, and the per-temperature values with intervals."
    )
    toml: str | None = Field(
        description="The parameter file of `ecdsim fit drop-test -o FILE [--config CONFIG]`; "
        "null where the fitted ECD cannot be written (export_error says why)."
    )
    config: dict[str, Any] | None = Field(description="`toml` in the JSON form of /api/deploy.")
    export_error: str | None = Field(description="Why there is no parameter file, or null.")


def _finite(value: float) -> float | None:
    return float(value) if math.isfinite(value) else None


def _floats(values: Any) -> list[float | None]:
    return [_finite(float(v)) for v in np.ravel(values)]


def _estimate(estimate: Estimate) -> dict[str, Any]:
    ci = estimate.ci95
    return {
        "value": _finite(estimate.value),
        "ci95": None if ci is None else [_finite(ci[0]), _finite(ci[1])],
    }


def fit_curves(result: DropTestResult) -> dict[str, Any]:
    """What the page plots: Fig. 8's lines and the laws with their bands (JSON-ready)."""
    fits = result.fits
    top = max((float(np.max(f.corrected)) for f in fits), default=1.0) * 1.1
    lines = []
    for fit in fits:
        b, f = fit.line.slope, fit.line.intercept
        lines.append(
            {
                "temperature_C": fit.temperature,
                "rows": [int(r) for r in fit.rows],
                "speed_rad_s": _floats(fit.corrected),
                "torque_Nm": _floats(fit.torque),
                "outlier": [bool(o) for o in np.ravel(fit.line.outliers)],
                "line_speed_rad_s": [0.0, top],
                "line_torque_Nm": _floats([f.value, f.value + b.value * top]),
                "damping_rate_Nms_per_rad": _estimate(b),
                "friction_Nm": _estimate(f),
            }
        )
    laws: dict[str, Any] = {"temperature_C": [], "damping_rate": {}, "friction": None}
    temps = np.array([f.temperature for f in fits], dtype=float)
    if result.laws is not None and temps.size:
        span = max(float(np.ptp(temps)), 1.0)
        grid = np.linspace(float(temps.min()) - 0.1 * span, float(temps.max()) + 0.1 * span,
                           LAW_POINTS)  # fmt: skip
        laws["temperature_C"] = grid.tolist()

        def curve(law: Any) -> dict[str, Any]:
            band = law.band(grid)
            return {
                "value": _floats(law(grid)),
                "low": None if band is None else _floats(band[0]),
                "high": None if band is None else _floats(band[1]),
            }

        laws["damping_rate"] = {name: curve(law) for name, law in result.laws.damping.items()}
        if result.laws.friction is not None:
            laws["friction"] = curve(result.laws.friction)
    return {"torque_speed": lines, "laws": laws}


def _parameter_file(
    result: DropTestResult, filename: str, config_text: str | None
) -> tuple[str | None, str | None]:
    """The ``-o`` file's text as the CLI writes it, or why it cannot be written.

    With ``config_text`` (the request's config as TOML, what /api/config.toml exports as
    :data:`CONFIG_NAME`), as ``--config CONFIG_NAME``: that file with the fitted ECD in
    place of its ``[damper]`` and ``[gearbox]``; without, the placeholder-load file.
    """
    from ecdsim.characterize.export import (
        ExportError,
        fitted_config_text,
        fitted_ecd,
        fitted_parameter_text,
        largest_torque,
        provenance,
    )

    fits = result.fits
    try:
        ecd = fitted_ecd(
            [f.temperature for f in fits],
            [f.line.slope for f in fits],
            [f.line.intercept for f in fits],
            result.laws,
        )
    except ExportError as exc:
        return None, str(exc)
    lines = provenance(
        f"ecdsim fit drop-test --noise {result.noise}", filename, result.table.sha256
    )
    if config_text is not None:
        return fitted_config_text(config_text, ecd, lines, CONFIG_NAME), None
    text = fitted_parameter_text(
        ecd,
        None,
        largest_torque([t for f in fits for t in f.torque]),
        f"ECD fitted from drop tests ({filename})",
        lines,
    )
    return text, None


def fit_drop_test_text(
    body: FitBody,
    load_body: Callable[[dict[str, Any]], tuple[Config, str]],
    _refuse: Callable[[list[str]], HTTPException],
) -> dict[str, Any]:
    """Fit the CSV text as ``ecdsim fit drop-test`` fits the file (HTTP 422 if unusable).

    ``load_body`` and ``_refuse`` are the server's (:class:`ServerHelpers`): this module
    never imports the server that imports it.
    """
    from ecdsim.characterize.droptest import fit_drop_test
    from ecdsim.config import ConfigError

    config_text: str | None = None
    units: str = body.units or "si"
    if body.config is not None:
        config, config_text = load_body(body.config)
        units = body.units or config.spec.output.units
    name = _SAFE_NAME.sub("_", Path(body.filename).name).strip("._") or "drop_test.csv"
    with tempfile.TemporaryDirectory(prefix="ecdsim-fit-") as folder:
        path = Path(folder) / name
        path.write_text(body.csv, encoding="utf-8")
        try:
            result = fit_drop_test(path, body.reference_temperature, noise=body.noise)
        except ConfigError as exc:
            lines = str(exc).replace(str(path), name).splitlines()
            raise _refuse([f"csv: {line}" for line in lines]) from None
    if not result.fits:
        problems = [f"not fitted: {f.message()}" for f in result.failed]
        raise _refuse([f"csv: {p}" for p in [*problems, "no temperature could be fitted"]])
    document = result.to_dict()
    document["source"] = name
    document["warnings"] = [w.to_dict() for w in result.warnings]
    document["parameter_file"] = None
    document["plots"] = []
    document["display_units"] = units
    text, why = _parameter_file(result, name, config_text)
    return {
        "fit": document,
        "curves": fit_curves(result),
        "toml": text,
        "config": tomllib.loads(text) if text is not None else None,
        "export_error": why,
    }


def fit_job(
    body: dict[str, Any],
    load_body: Callable[[dict[str, Any]], tuple[Config, str]],
    refuse: Callable[[list[str]], HTTPException],
) -> Reply:
    """``POST /api/fit/drop-test``'s computation (in a worker process, killed at the time
    limit: :mod:`ecdsim.webapp.workers`); ``body`` is the request's validated fields, the
    helpers the server's (pickled by reference, as the job itself)."""
    import json

    from ecdsim.webapp.workers import as_reply

    def compute() -> Response:
        payload = fit_drop_test_text(FitBody.model_validate(body), load_body, refuse)
        return Response(json.dumps(payload, allow_nan=False), media_type="application/json")

    return as_reply(compute)


Limited = Callable[[Callable[..., "Reply"], tuple[Any, ...]], Awaitable[Response]]


@dataclass(frozen=True)
class ServerHelpers:
    """What the route borrows from the explorer's server (handed over by it, so that this
    module never imports the server that imports it): its refusal, its config reader and
    its time-limited runner of jobs."""

    refuse: Callable[[list[str]], HTTPException]
    load_body: Callable[[dict[str, Any]], tuple[Config, str]]
    limited: Limited


def add_fit_routes(
    app: FastAPI, errors: dict[int | str, dict[str, Any]], server: ServerHelpers
) -> None:
    """Register ``POST /api/fit/drop-test`` on the explorer app; ``server.limited(job,
    args)`` runs a job within the server's time limit."""

    @app.post("/api/fit/drop-test", response_model=FitResponse, responses=errors)
    async def fit_drop_test_endpoint(body: FitBody) -> Response:
        """Fit a drop-test CSV as `ecdsim fit drop-test --json`, with the Fig. 8 curves."""
        args = (body.model_dump(), server.load_body, server.refuse)
        return await server.limited(fit_job, args)
