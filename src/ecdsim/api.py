"""The notebook API: one call per study, results as tables and figures.

::

    import ecdsim
    result = ecdsim.deploy("examples/paper_cc16.toml", temperatures=[-40, 25, 100])
    result.to_dataframe()          # pandas, long format: temperature_C, method, quantities
    figures = result.plot()        # matplotlib figures
    result                         # in Jupyter: an HTML table

* :func:`deploy` predicts a deployment (``ecdsim deploy``);
* :func:`fit` reduces a drop-test CSV (``ecdsim fit drop-test``);
* :func:`size` searches a catalogue against the config's requirements (``ecdsim size``);
* ``ecdsim.montecarlo.open(folder)`` opens the samples of a finished Monte Carlo study.

Inputs may be pint quantities or plain numbers. A plain number is read in SI units,
except temperatures, which are degC like everywhere in ecdsim (``-40`` is -40 degC;
pass ``Q_(233.15, "K")`` for kelvin). Config keys can be changed without editing the
file with ``overrides={"gearbox.ratio": 400, "load.inertia": Q_(5, "kg*m^2")}``.

Bad input raises :class:`~ecdsim.config.ConfigError` with one line per problem naming
the field, the value and the expected unit; a model asked outside its domain raises
:class:`~ecdsim.deployment.ModelDomainError`. pandas is optional: ``to_dataframe()``
says how to install it (``pip install 'ecdsim[montecarlo]'``) when it is missing.
"""

from __future__ import annotations

import html
import math
import os
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ecdsim.config import Config, ConfigError

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from ecdsim.characterize.droptest import DropTestResult
    from ecdsim.deployment import ModelWarning, Prediction
    from ecdsim.model import Load
    from ecdsim.sizing.ratio import RatioIntervals
    from ecdsim.sizing.requirements import Requirements
    from ecdsim.sizing.search import SearchResult
    from ecdsim.units_display import UnitSystem

__all__ = [
    "DeployResults",
    "FitResults",
    "MissingDependencyError",
    "SizeResults",
    "deploy",
    "fit",
    "load",
    "size",
]

ConfigLike = str | os.PathLike[str] | Config | Mapping[str, Any]
HTML_ROWS = 60


class MissingDependencyError(ImportError):
    """An optional package is not installed; the message names the extra to install."""


def _pandas() -> Any:
    try:
        import pandas
    except ImportError:
        raise MissingDependencyError(
            "to_dataframe() needs pandas, which is not installed; "
            "install it with: pip install 'ecdsim[montecarlo]'"
        ) from None
    return pandas


class _Table:
    """Shared by the results: rows -> DataFrame and an HTML table for Jupyter."""

    caption = ""

    def rows(self) -> list[dict[str, Any]]:
        """One dict per row, SI values, units in the column names."""
        raise NotImplementedError

    def to_dataframe(self) -> Any:
        """The rows as a pandas DataFrame (needs pandas: ``pip install 'ecdsim[montecarlo]'``)."""
        rows = self.rows()
        columns = list(dict.fromkeys(k for row in rows for k in row))
        return _pandas().DataFrame(rows, columns=columns)

    def _repr_html_(self) -> str:
        rows = self.rows()
        columns = list(dict.fromkeys(k for row in rows for k in row))
        head = "".join(f"<th>{html.escape(c)}</th>" for c in columns)
        body = []
        for row in rows[:HTML_ROWS]:
            cells = "".join(f"<td>{html.escape(_text(row.get(c)))}</td>" for c in columns)
            body.append(f"<tr>{cells}</tr>")
        more = (
            f"<p>{len(rows) - HTML_ROWS} more rows: use .to_dataframe()</p>"
            if len(rows) > HTML_ROWS
            else ""
        )
        return (
            f"<table><caption>{html.escape(self.caption)}</caption>"
            f"<thead><tr>{head}</tr></thead><tbody>{''.join(body)}</tbody></table>{more}"
        )


def _nan(value: float | None) -> float:
    return math.nan if value is None else float(value)


def _text(value: object) -> str:
    if isinstance(value, float):
        return "" if math.isnan(value) else f"{value:.6g}"
    return "" if value is None else str(value)


# ----------------------------------------------------------------------------- inputs


def load(config_or_path: ConfigLike, overrides: Mapping[str, object] | None = None) -> Config:
    """A validated config from a path, a TOML mapping or a :class:`Config`, with overrides.

    ``overrides`` maps dotted config keys to values (quantity strings, pint quantities,
    or plain SI numbers); a loaded :class:`Config` cannot take overrides (pass its path).
    Raises :class:`ConfigError`.
    """
    import hashlib
    import json
    import tomllib

    from ecdsim.config.loader import load_config, read_config_text, validate
    from ecdsim.config.overrides import apply_overrides
    from ecdsim.model import DeploymentSystem

    if isinstance(config_or_path, Config):
        if overrides:
            raise ConfigError(
                ["overrides: a loaded Config cannot take overrides; pass its path or mapping"]
            )
        return config_or_path
    if isinstance(config_or_path, Mapping):
        raw: dict[str, Any] = dict(config_or_path)
        source = "<mapping>"
    elif isinstance(config_or_path, str | os.PathLike):
        path = Path(config_or_path)
        if not overrides:
            return load_config(path)
        source = str(path)
        try:
            raw = tomllib.loads(read_config_text(path))
        except tomllib.TOMLDecodeError as exc:
            raise ConfigError([f"not valid TOML: {exc}"], source) from None
    else:
        raise ConfigError(
            [
                f"config_or_path = {type(config_or_path).__name__}: expected a path, "
                "a TOML mapping or an ecdsim Config"
            ]
        )
    document = apply_overrides(raw, overrides or {})
    spec = validate(document, source)
    text = json.dumps(document, sort_keys=True, default=str)
    return Config(
        system=DeploymentSystem(ecd=spec.ecd(), load=spec.load.to_model(), name=spec.title),
        temperatures=tuple(spec.analysis.temperatures),
        methods=tuple(spec.analysis.methods),
        spec=spec,
        source=source,
        sha256=hashlib.sha256(text.encode("utf-8")).hexdigest(),
    )


def _temperatures(values: object) -> tuple[float, ...]:
    """Temperatures [degC] from numbers (degC), strings ("77 degF") or pint quantities."""
    from ecdsim.config.units import QuantityError, parse_temperature

    quantity: Any = values
    if hasattr(quantity, "magnitude") and hasattr(quantity, "to"):
        try:
            magnitudes = quantity.to("degC").magnitude
        except Exception as exc:  # pint's DimensionalityError and friends
            raise ConfigError(
                [f"temperatures = {values}: not a temperature ({type(exc).__name__})"]
            ) from None
        # pint converts degF through kelvin (77 degF -> 25.000000000000057 degC): 12
        # significant digits keep the value and drop the rounding noise.
        items: list[Any] = [_round(m) for m in _iterate(magnitudes)]
    else:
        items = list(_iterate(values))
    if not items:
        raise ConfigError(["temperatures: empty; expected at least one temperature"])
    out = []
    problems = []
    for item in items:
        text = item
        if isinstance(item, int | float) and not isinstance(item, bool):
            text = f"{float(item)!r} degC"
        elif hasattr(item, "magnitude") and hasattr(item, "to"):
            text = f"{_round(item.to('degC').magnitude)!r} degC"
        elif isinstance(item, str) and not any(c.isalpha() for c in item):
            text = f"{item} degC"
        try:
            out.append(parse_temperature(text))
        except QuantityError as exc:
            problems.append(f"temperatures: {exc}")
    if problems:
        raise ConfigError(problems)
    return tuple(out)


def _round(value: Any) -> float:
    return float(f"{float(value):.12g}")


def _iterate(values: object) -> Iterable[object]:
    if isinstance(values, str | bytes) or not isinstance(values, Iterable):
        return [values]
    try:
        import numpy as np

        if isinstance(values, np.ndarray):
            return [float(v) for v in values.ravel()]
    except ImportError:  # pragma: no cover - numpy is a core dependency
        pass
    return list(values)


def _methods(values: str | Sequence[str]) -> tuple[str, ...]:
    from ecdsim.methods import SOLVERS

    names = (values,) if isinstance(values, str) else tuple(values)
    problems = [
        f"methods: {m!r} is not a method; expected one of {sorted(SOLVERS)}"
        for m in names
        if m not in SOLVERS
    ]
    if not names:
        problems.append(f"methods: empty; expected one or more of {sorted(SOLVERS)}")
    if problems:
        raise ConfigError(problems)
    return names


# ----------------------------------------------------------------------------- deploy


@dataclass(frozen=True)
class DeployResults(_Table):
    """A deployment predicted at each temperature by each method.

    Attributes
    ----------
    config : the validated config (overrides applied)
    prediction : the library's full result (:class:`ecdsim.deployment.Prediction`)
    """

    config: Config
    prediction: Prediction

    @property
    def caption(self) -> str:  # type: ignore[override]
        """The table's caption: the system's name."""
        return self.config.system.name

    @property
    def warnings(self) -> list[ModelWarning]:
        """Findings: stalls, linear range exceeded, tables extrapolated, ..."""
        return list(self.prediction.warnings)

    def rows(self) -> list[dict[str, Any]]:
        """One row per (temperature, method), SI, units in the column names.

        Columns: ``temperature_C``, ``method``, the ECD's ``damping_rate_Nms_per_rad``
        (BECD_T) and ``friction_Nm`` (FECD_T), ``system_friction_Nm`` (FS_T),
        ``total_friction_Nm``, then the method's ``deployment_time_s``,
        ``start_speed_rad_s``, ``end_speed_rad_s``, ``max_speed_rad_s``, ``stalled``,
        ``stall_angle_rad`` and the dynamic method's own fields (docs/json.md).
        """
        from ecdsim.sweeps import prediction_rows

        return prediction_rows(self.prediction)

    def deployment_time(self, method: str = "exact") -> dict[float, float]:
        """Deployment time [s] by ``method`` at each temperature [degC] (inf: stalled).

        With ``[load.gravity]`` this is the ground test (1 g, offloaded as configured);
        :meth:`flight_deployment_time` gives the same system in flight (0 g).
        """
        times = self.prediction.solutions[method].deployment_time
        temps = self.prediction.temperatures
        return {float(t): float(x) for t, x in zip(temps, times, strict=True)}

    def flight_deployment_time(self, method: str = "exact") -> dict[float, float] | None:
        """The flight (0 g) twin's deployment time [s] at each temperature [degC].

        None without ``[load.gravity]`` (the prediction is then the flight itself).
        """
        flight = self.prediction.flight
        if flight is None:
            return None
        times = flight.solutions[method].deployment_time
        return {float(t): float(x) for t, x in zip(flight.temperatures, times, strict=True)}

    def plot(self, units: UnitSystem = "si") -> list[Figure]:
        """Angle and speed against time, and ECD torque against speed (paper Fig. 4-6, 8).

        With the dynamic method, also its own figures (events marked, damper heating).
        """
        from ecdsim.plotting import plot_deployment, plot_speed, plot_torque_speed

        figures = [
            plot_deployment(self.prediction, units=units),
            plot_speed(self.prediction, units=units),
            plot_torque_speed(self.prediction, units=units),
        ]
        if "dynamic" in self.prediction.solutions:
            from ecdsim.plotting_dynamic import (
                dynamic_result,
                heated,
                plot_damper_temperature,
                plot_dynamic,
            )

            result = dynamic_result(self.prediction)
            if result is not None:
                for quantity in ("angle", "speed"):
                    figures.append(plot_dynamic(self.prediction, quantity, units, result=result))
                if heated(result):
                    figures.append(plot_damper_temperature(self.prediction, units, result=result))
        return figures


def deploy(
    config_or_path: ConfigLike,
    temperatures: object = None,
    methods: str | Sequence[str] | None = None,
    *,
    overrides: Mapping[str, object] | None = None,
) -> DeployResults:
    """Predict the deployment at each temperature by each method (``ecdsim deploy``).

    Parameters
    ----------
    config_or_path : a TOML file, its parsed mapping, or a :class:`~ecdsim.config.Config`
    temperatures : one or more temperatures: numbers [degC], strings (``"77 degF"``) or
        pint quantities; default the config's ``[analysis] temperatures``
    methods : ``"paper"``, ``"exact"``, ``"dynamic"`` or a list; default the config's
    overrides : dotted config keys -> values (see :func:`load`)

    >>> r = deploy("examples/paper_cc16.toml", temperatures=25, methods="exact")
    >>> round(r.deployment_time()[25.0], 2)
    26.86
    """
    from ecdsim.deployment import predict, with_flight

    config = load(config_or_path, overrides)
    temps = config.temperatures if temperatures is None else _temperatures(temperatures)
    chosen = config.methods if methods is None else _methods(methods)
    dynamics = config.spec.dynamics()
    # With [load.gravity] the flight twin too, as `ecdsim deploy` shows it.
    prediction = with_flight(predict(config.system, temps, chosen, dynamics=dynamics), dynamics)
    return DeployResults(config, prediction)


# ----------------------------------------------------------------------------- fit


@dataclass(frozen=True)
class FitResults(_Table):
    """A drop test reduced: BECD and FECD at each temperature, and laws over temperature.

    Attributes
    ----------
    result : the library's full result (:class:`~ecdsim.characterize.droptest.DropTestResult`)
    """

    result: DropTestResult
    caption = "drop-test fit"

    def rows(self) -> list[dict[str, Any]]:
        """One row per fitted temperature: BECD, FECD, their standard errors and 95 % CIs."""
        rows = []
        for fit_ in self.result.fits:
            line = fit_.line
            d_low, d_high = line.slope.ci95 or (math.nan, math.nan)
            f_low, f_high = line.intercept.ci95 or (math.nan, math.nan)
            rows.append(
                {
                    "temperature_C": fit_.temperature,
                    "damping_rate_Nms_per_rad": line.slope.value,
                    "damping_rate_se_Nms_per_rad": _nan(line.slope.standard_error),
                    "damping_rate_ci95_low_Nms_per_rad": d_low,
                    "damping_rate_ci95_high_Nms_per_rad": d_high,
                    "friction_Nm": line.intercept.value,
                    "friction_se_Nm": _nan(line.intercept.standard_error),
                    "friction_ci95_low_Nm": f_low,
                    "friction_ci95_high_Nm": f_high,
                    "r_squared": line.r_squared,
                    "n_points": int(fit_.torque.size),
                }
            )
        return rows

    def laws(self) -> dict[str, Any] | None:
        """The temperature laws as ``ecdsim fit drop-test --json`` gives them (or None)."""
        return None if self.result.laws is None else self.result.laws.to_dict()

    def plot(self) -> list[Figure]:
        """Torque against speed with the fitted lines (paper Fig. 8), and BECD, FECD over T."""
        from ecdsim.characterize.plots import plot_line_residuals, plot_parameters
        from ecdsim.characterize.plots import plot_torque_speed as fit_lines

        fits = self.result.fits
        return [
            fit_lines(self.result),
            plot_parameters(
                [f.temperature for f in fits],
                [f.line.slope for f in fits],
                [f.line.intercept for f in fits],
                self.result.laws,
            ),
            plot_line_residuals(self.result),
        ]


def fit(
    csv_path: str | os.PathLike[str],
    reference_temperature: object = 25.0,
    *,
    noise: str = "torque",
) -> FitResults:
    """Fit BECD(T) and FECD(T) to a drop-test CSV (``ecdsim fit drop-test``).

    ``reference_temperature``: T_ref of the damping laws (a number in degC, a string or a
    pint quantity); ``noise``: where the scatter lies (docs/characterize.md).
    """
    from ecdsim.characterize.droptest import fit_drop_test, noise_model

    temps = _temperatures(reference_temperature)
    if len(temps) != 1:
        raise ConfigError([f"reference_temperature: expected one temperature, got {len(temps)}"])
    try:
        noise_model(noise)
    except ValueError as exc:
        raise ConfigError([f"noise: {exc}"]) from None
    return FitResults(fit_drop_test(Path(csv_path), temps[0], noise=noise))


# ----------------------------------------------------------------------------- size


@dataclass(frozen=True)
class SizeResults(_Table):
    """A catalogue search against the config's ``[requirements]``, best first.

    Attributes
    ----------
    search : the ranked candidates (:class:`~ecdsim.sizing.search.SearchResult`)
    intervals : exact feasible gear-ratio intervals of the best candidate (or None)
    requirements : what was required
    load : the load the candidates were sized for
    """

    search: SearchResult
    intervals: RatioIntervals | None
    requirements: Requirements
    load: Load
    caption = "sizing: candidates against the requirements, best first"

    def rows(self) -> list[dict[str, Any]]:
        """One row per (candidate, temperature): rank, pass, margin and the exact results."""
        rows = []
        for c in self.search.candidates:
            base = {
                "rank": c.rank,
                "damper": c.candidate.damper.name,
                "gearbox": c.candidate.gearbox.name,
                "gear_ratio": c.candidate.ratio,
                "passed": c.passed,
                "margin": math.nan if c.margin is None else c.margin,
                "error": c.error or "",
            }
            for i, temp in enumerate(c.temperatures):
                rows.append(
                    {
                        **base,
                        "temperature_C": float(temp),
                        "deployment_time_s": _at(c.deployment_time, i),
                        "end_speed_rad_s": _at(c.end_speed, i),
                        "input_torque_Nm": _at(c.input_torque, i),
                        "damping_rate_Nms_per_rad": _at(c.damping_rate, i),
                        "friction_Nm": _at(c.friction, i),
                        "stalled": bool(_at(c.stalled, i)),
                    }
                )
        return rows

    def plot(self, top: int = 5) -> list[Figure]:
        """Deployment time over temperature of the ``top`` candidates, and ratio margins."""
        import numpy as np

        from ecdsim.sizing.plots import plot_candidate_times, plot_ratio_margins
        from ecdsim.sizing.search import deployment_time_curves

        valid = [c for c in self.search.candidates if c.error is None][:top]
        temps = np.linspace(
            min(self.requirements.temperatures), max(self.requirements.temperatures), 57
        )
        times = (
            deployment_time_curves([c.candidate for c in valid], self.load, temps)
            if valid
            else np.zeros((0, temps.size))
        )
        figures = [plot_candidate_times(valid, temps, times, self.requirements)]
        if self.intervals is not None:
            figures.append(plot_ratio_margins(self.intervals))
        return figures


def _at(values: Any, i: int) -> Any:
    import numpy as np

    array = np.ravel(np.asarray(values))
    return array[i].item() if array.size > i else math.nan


def size(
    config_or_path: ConfigLike,
    catalogue: str | os.PathLike[str],
    *,
    overrides: Mapping[str, object] | None = None,
) -> SizeResults:
    """Rank a catalogue's dampers and gearboxes against ``[requirements]`` (``ecdsim size``).

    The exact gear-ratio intervals are computed for the best-ranked valid candidate.
    Raises :class:`ConfigError` for a config without ``[requirements]`` or a bad catalogue.
    """
    from ecdsim.sizing.catalogue import load_catalogue
    from ecdsim.sizing.ratio import ratio_intervals
    from ecdsim.sizing.requirements import Requirements
    from ecdsim.sizing.search import search

    config = load(config_or_path, overrides)
    if config.spec.requirements is None:
        raise ConfigError(["requirements: missing; size needs a [requirements] section"])
    requirements = Requirements.from_spec(config.spec.requirements)
    found = load_catalogue(Path(catalogue))
    load_ = config.system.load
    try:
        result = search(found, load_, requirements)
    except ValueError as exc:
        raise ConfigError([f"{catalogue}: {exc}"]) from None
    valid = [c for c in result.candidates if c.error is None]
    intervals = None
    if valid:
        best = valid[0].candidate
        intervals = ratio_intervals(
            found.damper(best.damper.name), found.gearbox(best.gearbox.name), load_, requirements
        )
    return SizeResults(result, intervals, requirements, load_)
