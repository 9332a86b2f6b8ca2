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
* :func:`sweep` varies config keys over a grid or a Latin hypercube (``ecdsim sweep``);
* ``ecdsim.montecarlo.open(folder)`` opens the samples of a finished Monte Carlo study.

Every table is long (tidy): temperature and method are columns, and every column name
ends in its SI unit (``deployment_time_s``, ``load.start_torque_Nm``; docs/json.md).

Inputs may be pint quantities or plain numbers. A plain number is read in SI units,
except temperatures, which are degC like everywhere in ecdsim (``-40`` is -40 degC;
pass ``Q_(233.15, "K")`` for kelvin). Config keys can be changed without editing the
file with ``overrides={"gearbox.ratio": 400, "load.inertia": Q_(5, "kg*m^2")}``.

Bad input raises :class:`~ecdsim.config.ConfigError` (a ValueError) with one line per
problem naming the field, the value and the expected unit (an unknown name, such as a
method that was not run, :class:`UnknownNameError`, naming the choices); a model asked
outside its domain raises
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
from typing import TYPE_CHECKING, Any, cast, overload

from ecdsim.config import Config, ConfigError

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from ecdsim.characterize.droptest import DropTestResult
    from ecdsim.deployment import ModelWarning, Prediction
    from ecdsim.model import Load
    from ecdsim.sizing.ratio import RatioIntervals
    from ecdsim.sizing.requirements import Requirements
    from ecdsim.sizing.search import SearchResult
    from ecdsim.sweeps import SweepResult
    from ecdsim.units_display import UnitSystem
    from ecdsim.wing.result import WingResult

__all__ = [
    "DeployResults",
    "FitResults",
    "MissingDependencyError",
    "SizeResults",
    "SweepResults",
    "UnknownNameError",
    "deploy",
    "deploy_wing",
    "fit",
    "load",
    "size",
    "sweep",
]

ConfigLike = str | os.PathLike[str] | Config | Mapping[str, Any]
HTML_ROWS = 60
# The deepest nesting of an ``overrides`` mapping (as files and the explorer's requests).
MAX_OVERRIDE_DEPTH = 32


class MissingDependencyError(ImportError):
    """An optional package is not installed; the message names the extra to install."""


class UnknownNameError(ConfigError):
    """A name that is not one of the choices (a method, a unit system, a plot); a
    ValueError whose one line names the value and the choices."""


def _choose(what: str, value: object, choices: Sequence[str]) -> str:
    """``value`` if it is one of ``choices``; else :class:`UnknownNameError` naming both."""
    from ecdsim.config.units import quoted

    if isinstance(value, str) and value in choices:
        return value
    raise UnknownNameError([f"{what}: {quoted(value)} is not one of {list(choices)}"])


def _pandas() -> Any:
    try:
        import pandas
    except ImportError:
        from ecdsim.invocation import install_hint

        raise MissingDependencyError(
            f"to_dataframe() needs pandas, which is not installed; {install_hint('montecarlo')}"
        ) from None
    return pandas


class _Table:
    """Shared by the results: rows -> DataFrame and an HTML table for Jupyter."""

    caption = ""

    def rows(self) -> list[dict[str, Any]]:
        """One dict per row, SI values, units in the column names."""
        raise NotImplementedError

    def _flag(self) -> str | None:
        """The placeholder-load warning of the config behind the rows, if it has one."""
        return None

    def to_dataframe(self) -> Any:
        """The rows as a pandas DataFrame (needs pandas: ``pip install 'ecdsim[montecarlo]'``).

        Flags are pandas' nullable ``boolean``, counts ``Int64``, so that a column only
        some rows have (the dynamic method's ``stuck``) keeps its type (ecdsim.tidy).
        """
        from ecdsim.tidy import dataframe

        _pandas()
        return dataframe(self.rows())

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
        flag = self._flag()
        # The report's banner: a stand-in load makes no row the mechanism's.
        banner = (
            ""
            if flag is None
            else f'<p role="alert" style="{BANNER_STYLE}">{html.escape(flag)}</p>'
        )
        return (
            f"{banner}<table><caption>{html.escape(self.caption)}</caption>"
            f"<thead><tr>{head}</tr></thead><tbody>{''.join(body)}</tbody></table>{more}"
        )


BANNER_STYLE = (
    "background: #fdecea; color: #000; border-left: 6px solid #b00020; "
    "padding: .4em .8em; font-weight: 600"
)


def _placeholder_flag(config: Config) -> str | None:
    """The placeholder-load warning text of ``config``, or None (a real load)."""
    from ecdsim.config.placeholder import is_placeholder, warning_text

    return warning_text(config.source) if is_placeholder(config) else None


def _marked(name: str, flag: str | None) -> str:
    """A result's name in its repr, with the placeholder title when its load is one."""
    from ecdsim.config.placeholder import TITLE

    return f"{name!r}" if flag is None else f"{name!r} ({TITLE})"


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
    Raises :class:`ConfigError`. A config whose ``[load]`` is a marked placeholder (``ecdsim
    fit drop-test -o`` without ``--config``) gives a
    :class:`~ecdsim.config.placeholder.PlaceholderLoadWarning`, as :func:`deploy`,
    :func:`size` and :func:`sweep` do.
    """
    from ecdsim.config import placeholder

    config = _load(config_or_path, overrides)
    placeholder.warn(config)
    return config


def _load(config_or_path: ConfigLike, overrides: Mapping[str, object] | None) -> Config:
    """:func:`load` without the placeholder warning (each study warns for its own call)."""
    import hashlib
    import json

    from ecdsim.config.loader import load_config, validate
    from ecdsim.model import DeploymentSystem

    overrides = _overrides(overrides)
    if isinstance(config_or_path, Config):
        if overrides:
            raise ConfigError(
                ["overrides: a loaded Config cannot take overrides; pass its path or mapping"]
            )
        return config_or_path
    if isinstance(config_or_path, str | os.PathLike) and not overrides:
        return load_config(Path(config_or_path))
    document, source = _document(config_or_path, overrides)
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


def _document(
    config_or_path: ConfigLike, overrides: Mapping[str, object]
) -> tuple[dict[str, Any], str]:
    """The TOML document (overrides applied) and its source name, before validation.

    A loaded :class:`Config` gives the document of the file it was read from.
    """
    from ecdsim.config.loader import parse_toml, read_config_text
    from ecdsim.config.overrides import apply_overrides

    if isinstance(config_or_path, Config):
        import hashlib

        path = Path(config_or_path.source)
        # Only a Config read from a file as it is now (not one built with overrides or
        # from a mapping, which the file would not reproduce).
        if not path.is_file() or (
            hashlib.sha256(path.read_bytes()).hexdigest() != config_or_path.sha256
        ):
            raise ConfigError(
                [
                    f"{config_or_path.source}: this Config is not its file as read; pass the "
                    "path or mapping (with its overrides) instead"
                ]
            )
        config_or_path = path
    if isinstance(config_or_path, Mapping):
        raw: dict[str, Any] = dict(config_or_path)
        source = "<mapping>"
    elif isinstance(config_or_path, str | os.PathLike):
        path = Path(config_or_path)
        source = str(path)
        raw = parse_toml(read_config_text(path), source)
    else:
        raise ConfigError(
            [
                f"config_or_path = {type(config_or_path).__name__}: expected a path, "
                "a TOML mapping or an ecdsim Config"
            ]
        )
    # None removes a key (the field's default applies, or the section is absent): with
    # merging, the way to drop a key of a table, e.g. a thermal resistance (adiabatic).
    removed = [key for key, value in overrides.items() if value is None]
    document = apply_overrides(raw, {k: v for k, v in overrides.items() if v is not None})
    for key in removed:
        *tables, last = key.split(".")
        node: Any = document
        for part in tables:
            node = node.get(part) if isinstance(node, dict) else None
        if isinstance(node, dict):
            node.pop(last, None)
    return document, source


def _overrides(overrides: object) -> dict[str, object]:
    """``overrides`` as flat dotted keys with plain Python values.

    A nested mapping merges into its table key by key (``{"gearbox": {"ratio": 400}}``
    sets ``gearbox.ratio`` and keeps the table's other keys), as TOML's dotted keys do;
    a value of None removes its key; NumPy scalars and arrays become Python numbers and
    lists. Keys must be strings.
    Raises :class:`ConfigError` naming the key.
    """
    from ecdsim.config.units import quoted

    if overrides is None:
        return {}
    if not isinstance(overrides, Mapping):
        raise ConfigError(
            [f"overrides = {quoted(overrides)}: expected a mapping of dotted config keys to values"]
        )
    flat: dict[str, object] = {}
    problems: list[str] = []
    # Level by level, without recursion (a deep mapping must not exhaust the stack).
    from collections import deque

    queue: deque[tuple[str, Mapping[Any, Any], int]] = deque([("", overrides, 0)])
    while queue:
        prefix, mapping, depth = queue.popleft()
        if depth > MAX_OVERRIDE_DEPTH:
            problems.append(
                f"overrides: {prefix[:80]}... is nested deeper than {MAX_OVERRIDE_DEPTH} levels"
            )
            continue
        for key, value in mapping.items():
            if not isinstance(key, str):
                where = f" in {prefix.rstrip('.')}" if prefix else ""
                problems.append(
                    f"overrides: key {quoted(key)}{where} is not a config key; expected a "
                    "dotted name such as 'gearbox.ratio'"
                )
                continue
            if isinstance(value, Mapping) and not _is_quantity(value):
                queue.append((f"{prefix}{key}.", value, depth + 1))
            else:
                flat[f"{prefix}{key}"] = _plain(value)
    if problems:
        raise ConfigError(problems)
    return flat


def _is_quantity(value: object) -> bool:
    return hasattr(value, "magnitude") and hasattr(value, "to")


def _plain(value: object) -> object:
    """NumPy scalars as Python numbers, arrays as lists; anything else as it is."""
    try:
        import numpy as np
    except ImportError:  # pragma: no cover - numpy is a core dependency
        return value
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, list | tuple):
        return [_plain(v) for v in value]
    return value


def _temperatures(values: object) -> tuple[float, ...]:
    """Temperatures [degC] from numbers (degC), strings ("77 degF") or pint quantities.

    Every form is read by :func:`ecdsim.config.units.parse_temperature`, which converts
    degF, K and degR exactly (``"-40 degF"`` and ``Q_(-40, "degF")`` are -40 degC).
    """
    import numbers

    from ecdsim.config.units import QuantityError, parse_temperature, quoted

    items: list[object] = []
    if _is_quantity(values):
        quantity: Any = values
        unit = str(quantity.units)
        try:
            items = [f"{float(cast(Any, m))!r} {unit}" for m in _iterate(quantity.magnitude)]
        except (TypeError, ValueError, OverflowError):
            raise ConfigError([f"temperatures: {quoted(values)} is not a temperature"]) from None
    else:
        items = list(_iterate(values))
    if not items:
        raise ConfigError(["temperatures: empty; expected at least one temperature"])
    out = []
    problems = []
    for item in items:
        text = item
        try:
            # float() of an integer beyond float64 (10**400) raises OverflowError: a
            # value that is no temperature, refused below like any other.
            if not isinstance(item, bool) and isinstance(item, numbers.Real):
                text = f"{float(item)!r} degC"
            elif _is_quantity(item):
                quantity = item
                text = f"{float(quantity.magnitude)!r} {quantity.units}"
            elif isinstance(item, str) and not any(c.isalpha() for c in item):
                text = f"{item} degC"
            out.append(parse_temperature(text))
        except QuantityError as exc:
            problems.append(f"temperatures: {exc}")
        except (TypeError, ValueError, OverflowError):
            problems.append(f"temperatures: {quoted(item)} is not a temperature")
    if problems:
        raise ConfigError(problems)
    return tuple(out)


def _iterate(values: object) -> Iterable[object]:
    if isinstance(values, str | bytes) or not isinstance(values, Iterable):
        return [values]
    try:
        import numpy as np

        if isinstance(values, np.ndarray):
            return [v.item() for v in values.ravel()]
    except ImportError:  # pragma: no cover - numpy is a core dependency
        pass
    return list(values)


def _methods(values: object) -> tuple[str, ...]:
    from ecdsim.config.units import quoted
    from ecdsim.methods import SOLVERS

    names = (values,) if isinstance(values, str) else tuple(_iterate(values))
    problems = [
        f"methods: {quoted(m)} is not a method; expected one of {sorted(SOLVERS)}"
        for m in names
        if not isinstance(m, str) or m not in SOLVERS
    ]
    if not names:
        problems.append(f"methods: empty; expected one or more of {sorted(SOLVERS)}")
    if problems:
        raise UnknownNameError(problems)
    return tuple(str(m) for m in names)


# ----------------------------------------------------------------------------- deploy


@dataclass(frozen=True, repr=False)
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

    @property
    def placeholder_load(self) -> bool:
        """True when the config's ``[load]`` is a marked placeholder: no deployment here
        is the mechanism's (the repr, the HTML table and :meth:`to_dict` say so too)."""
        return self._flag() is not None

    def _flag(self) -> str | None:
        return _placeholder_flag(self.config)

    def to_dict(self) -> dict[str, Any]:
        """The JSON document of ``ecdsim deploy --json`` (docs/json.md): SI,
        ``display_units`` ``"si"``, and ``"placeholder_load": true`` when the config's
        load is a marked placeholder."""
        from ecdsim.config.placeholder import JSON_KEY

        document = self.prediction.to_dict()
        document["display_units"] = "si"
        if self.placeholder_load:
            document[JSON_KEY] = True
        return document

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

    def __repr__(self) -> str:
        """One line: the system, the temperatures and methods, each method's times."""
        return _short_repr(self)

    def _method(self, method: object) -> str:
        return _choose("method", method, list(self.prediction.solutions))

    def deployment_time(self, method: str = "exact") -> dict[float, float]:
        """Deployment time [s] by ``method`` at each temperature [degC] (inf: stalled).

        With ``[load.gravity]`` this is the ground test (1 g, offloaded as configured);
        :meth:`flight_deployment_time` gives the same system in flight (0 g). A method
        that was not run raises :class:`UnknownNameError` naming the methods that were.
        """
        times = self.prediction.solutions[self._method(method)].deployment_time
        temps = self.prediction.temperatures
        return {float(t): float(x) for t, x in zip(temps, times, strict=True)}

    def flight_deployment_time(self, method: str = "exact") -> dict[float, float] | None:
        """The flight (0 g) twin's deployment time [s] at each temperature [degC].

        None without ``[load.gravity]`` (the prediction is then the flight itself).
        """
        name = self._method(method)
        flight = self.prediction.flight
        if flight is None:
            return None
        times = flight.solutions[name].deployment_time
        return {float(t): float(x) for t, x in zip(flight.temperatures, times, strict=True)}

    @overload
    def plot(self, units: UnitSystem = "si", *, ax: None = None, kind: str = ...) -> list[Figure]:
        pass

    @overload
    def plot(self, units: UnitSystem = "si", *, ax: Axes, kind: str = ...) -> Axes:
        pass

    def plot(
        self, units: UnitSystem = "si", *, ax: Axes | None = None, kind: str = "angle"
    ) -> list[Figure] | Axes:
        """Angle and speed against time, and ECD torque against speed (paper Fig. 4-6, 8).

        Without ``ax``: a list of figures, with the dynamic method also its own (events
        marked, damper heating). With ``ax`` (a matplotlib Axes): draws one plot there,
        ``kind`` = ``"angle"``, ``"speed"`` or ``"torque_speed"``, and returns ``ax``.
        ``units``: ``"si"`` or ``"us"`` (labels in degF, lbf*in).
        """
        from ecdsim.plotting import plot_deployment, plot_speed, plot_torque_speed
        from ecdsim.units_display import check_system

        system = check_system(units, "units")
        if ax is not None:
            chosen = _choose("kind", kind, list(PLOT_KINDS))
            draw = {"angle": plot_deployment, "speed": plot_speed}.get(chosen, plot_torque_speed)
            draw(self.prediction, units=system, ax=ax)
            return ax
        figures = [
            plot_deployment(self.prediction, units=system),
            plot_speed(self.prediction, units=system),
            plot_torque_speed(self.prediction, units=system),
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
                    figures.append(plot_dynamic(self.prediction, quantity, system, result=result))
                if heated(result):
                    figures.append(plot_damper_temperature(self.prediction, system, result=result))
        return figures

    def timeseries(self, times: object = None, n_points: int = 400) -> Any:
        """The motion as a long (tidy) DataFrame: one row per (temperature, method, time).

        Columns ``temperature_C``, ``method``, ``time_s``, ``angle_rad`` (deployed angle
        from the start of travel), ``speed_rad_s`` (input shaft). ``times`` [s]: the
        instants (default ``n_points`` from 0 to 1.1 times the longest deployment, as
        the plots). Each method's own trajectory: the quasi-static methods' closed forms,
        the dynamic method's integrated motion; NaN where a method did not solve a case.
        """
        import numpy as np

        from ecdsim.plotting import time_span

        pd = _pandas()
        if times is None:
            if isinstance(n_points, bool) or not isinstance(n_points, int) or n_points < 2:
                raise ConfigError([f"n_points = {n_points!r}: expected an integer >= 2"])
            grid = np.linspace(0.0, time_span(self.prediction), n_points)
        else:
            try:
                grid = np.asarray(times, dtype=float).reshape(-1)
            except (TypeError, ValueError):
                raise ConfigError(["times: expected numbers [s]"]) from None
            if grid.size == 0 or not np.all(np.isfinite(grid)) or np.any(grid < 0.0):
                raise ConfigError(["times: expected one or more finite times >= 0 s"])
        temps = np.ravel(self.prediction.temperatures)
        frames = []
        for name, solution in self.prediction.solutions.items():
            trajectory = self.prediction.trajectory(name, grid)
            angle = np.asarray(trajectory.angle, dtype=float).reshape(grid.size, -1)
            speed = np.asarray(trajectory.speed, dtype=float).reshape(grid.size, -1)
            shape = self.prediction.temperatures.shape
            solved = np.ravel(np.broadcast_to(solution.solved_mask, shape))
            angle = np.where(solved[None, :], angle, np.nan)
            speed = np.where(solved[None, :], speed, np.nan)
            frames.append(
                pd.DataFrame(
                    {
                        "temperature_C": np.repeat(temps, grid.size),
                        "method": pd.array([name] * (temps.size * grid.size), dtype="string"),
                        "time_s": np.tile(grid, temps.size),
                        "angle_rad": angle.T.reshape(-1),
                        "speed_rad_s": speed.T.reshape(-1),
                    }
                )
            )
        # Temperature first, then method in the order run, then time.
        frame = pd.concat(frames, ignore_index=True)
        order = {name: i for i, name in enumerate(self.prediction.solutions)}
        frame["_order"] = frame["method"].map(order)
        frame = frame.sort_values(["temperature_C", "_order", "time_s"], kind="stable")
        return frame.drop(columns="_order").reset_index(drop=True)


PLOT_KINDS = ("angle", "speed", "torque_speed")


def _short_repr(result: DeployResults) -> str:
    prediction = result.prediction
    temps = ", ".join(f"{float(cast(Any, t)):g}" for t in _iterate(prediction.temperatures))
    parts = []
    for name, solution in prediction.solutions.items():
        times = ", ".join(_seconds(float(cast(Any, t))) for t in _iterate(solution.deployment_time))
        parts.append(f"{name} [{times}]")
    count = len(prediction.warnings)
    name = _marked(result.config.system.name, result._flag())
    return (
        f"<DeployResults {name} at [{temps}] degC: deployment time "
        f"{'; '.join(parts)}; {count} warning{'s' if count != 1 else ''}>"
    )


def _seconds(value: float) -> str:
    if math.isnan(value):
        return "nan"
    return "stall" if math.isinf(value) else f"{value:.4g} s"


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
    from ecdsim.config import placeholder
    from ecdsim.deployment import predict, with_flight

    config = _load(config_or_path, overrides)
    placeholder.warn(config)
    temps = config.temperatures if temperatures is None else _temperatures(temperatures)
    chosen = config.methods if methods is None else _methods(methods)
    dynamics = config.spec.dynamics()
    # With [load.gravity] the flight twin too, as `ecdsim deploy` shows it.
    prediction = with_flight(predict(config.system, temps, chosen, dynamics=dynamics), dynamics)
    return DeployResults(config, prediction)


def deploy_wing(
    path: str | os.PathLike[str],
    temperatures: object = None,
    *,
    rtol: float | None = None,
    stop_time: float | None = None,
) -> WingResult:
    """A wing file's deployment at each temperature (``ecdsim deploy WING.toml``).

    Returns the :class:`~ecdsim.wing.result.WingResult`: per temperature each hinge's
    angle and speed against time, the latching sequence, each latch's speed, kinetic
    energy and peak torque or impulse, the stuck hinges and the energy account
    (``to_dict()``, ``to_dataframe()``; docs/wing.md). ``temperatures`` as for
    :func:`deploy` (default the file's ``[analysis] temperatures``); ``rtol`` and
    ``stop_time`` [s] override the file's. Raises :class:`ConfigError`.

    >>> r = deploy_wing("examples/wing_cc16_three_panel.toml", temperatures=25)
    >>> [round(latch.time, 2) for latch in r.cases[0].latches]
    [26.86, 53.75, 53.77]
    """
    from ecdsim.config.wing_schema import load_wing_config
    from ecdsim.sizing.catalogue import load_catalogue
    from ecdsim.wing.solver import WingUnsupported
    from ecdsim.wing.solver import deploy_wing as solve

    config = load_wing_config(Path(path), read_catalogue=load_catalogue)
    temps = config.temperatures if temperatures is None else _temperatures(temperatures)
    try:
        return solve(
            config.wing,
            list(temps),
            rtol=config.rtol if rtol is None else rtol,
            stop_time=config.stop_time if stop_time is None else stop_time,
        )
    except WingUnsupported as exc:
        raise ConfigError([str(exc)], str(path)) from None


# ----------------------------------------------------------------------------- fit


@dataclass(frozen=True, repr=False)
class FitResults(_Table):
    """A drop test reduced: BECD and FECD at each temperature, and laws over temperature.

    Attributes
    ----------
    result : the library's full result (:class:`~ecdsim.characterize.droptest.DropTestResult`)
    """

    result: DropTestResult
    caption = "drop-test fit"

    def __repr__(self) -> str:
        """One line: the source, the fitted temperatures and BECD, FECD at each."""
        fits = self.result.fits
        each = "; ".join(
            f"{f.temperature:g} degC: {f.line.slope.value:.4g} N*m*s/rad, "
            f"{f.line.intercept.value:.4g} N*m"
            for f in fits[:6]
        )
        more = f"; {len(fits) - 6} more" if len(fits) > 6 else ""
        count = len(self.result.warnings)
        return (
            f"<FitResults {self.result.table.source!r}: {len(fits)} temperatures "
            f"[{each}{more}]; {count} warning{'s' if count != 1 else ''}>"
        )

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

    @overload
    def plot(self, units: UnitSystem = "si", *, ax: None = None, kind: str = ...) -> list[Figure]:
        pass

    @overload
    def plot(self, units: UnitSystem = "si", *, ax: Axes, kind: str = ...) -> Axes:
        pass

    def plot(
        self, units: UnitSystem = "si", *, ax: Axes | None = None, kind: str = "torque_speed"
    ) -> list[Figure] | Axes:
        """Torque against speed with the fitted lines (paper Fig. 8), BECD and FECD over T
        with their laws, and the lines' residuals.

        Without ``ax``: a list of the three figures (the second with both parameters).
        With ``ax`` (a matplotlib Axes): draws one plot there, ``kind`` =
        ``"torque_speed"``, ``"damping_rate"`` (BECD over T), ``"friction"`` (FECD over T)
        or ``"residuals"``, and returns ``ax``. ``units``: ``"si"`` or ``"us"``.
        """
        from ecdsim.characterize.plots import (
            plot_line_residuals,
            plot_parameter,
            plot_parameters,
        )
        from ecdsim.characterize.plots import plot_torque_speed as fit_lines
        from ecdsim.units_display import check_system

        system = check_system(units, "units")
        fits = self.result.fits
        temperatures = [f.temperature for f in fits]
        damping = [f.line.slope for f in fits]
        friction = [f.line.intercept for f in fits]
        if ax is not None:
            chosen = _choose("kind", kind, list(FIT_PLOT_KINDS))
            if chosen == "torque_speed":
                fit_lines(self.result, system, ax=ax)
            elif chosen == "residuals":
                plot_line_residuals(self.result, system, ax=ax)
            else:
                values = damping if chosen == "damping_rate" else friction
                plot_parameter(chosen, temperatures, values, self.result.laws, system, ax=ax)
            return ax
        return [
            fit_lines(self.result, system),
            plot_parameters(temperatures, damping, friction, self.result.laws, system),
            plot_line_residuals(self.result, system),
        ]


FIT_PLOT_KINDS = ("torque_speed", "damping_rate", "friction", "residuals")


def fit(
    data: str | os.PathLike[str] | Any,
    reference_temperature: object = 25.0,
    *,
    noise: str = "torque",
) -> FitResults:
    """Fit BECD(T) and FECD(T) to a drop test (``ecdsim fit drop-test``).

    ``data``: the CSV file, or a pandas DataFrame with the same unit-bearing columns
    (``temperature [degC]``, ``mass [g]``, ...; docs/characterize.md), e.g. the file read
    with ``pandas.read_csv``. ``reference_temperature``: T_ref of the damping laws (a
    number in degC, a string or a pint quantity); ``noise``: where the scatter lies
    (``"torque"`` or ``"timing"``, docs/characterize.md).
    """
    from ecdsim.characterize.droptest import NOISE_MODELS, fit_drop_test, noise_model

    temps = _temperatures(reference_temperature)
    if len(temps) != 1:
        raise ConfigError([f"reference_temperature: expected one temperature, got {len(temps)}"])
    try:
        noise_model(noise)
    except (ValueError, TypeError):
        _choose("noise", noise, list(NOISE_MODELS))
    if isinstance(data, str | os.PathLike):
        return FitResults(fit_drop_test(Path(data), temps[0], noise=noise))
    if not (hasattr(data, "to_csv") and hasattr(data, "columns")):
        raise ConfigError(
            [f"data = {type(data).__name__}: expected a CSV path or a pandas DataFrame"]
        )
    return FitResults(_fit_frame(data, temps[0], noise))


def _fit_frame(frame: Any, reference_temperature: float, noise: str) -> DropTestResult:
    """Fit a DataFrame: written as the CSV it stands for and read by the same reader, so
    that its columns, units and rows are checked exactly as a file's are."""
    import dataclasses
    import tempfile

    from ecdsim.characterize.droptest import (
        STANDARD_GRAVITY,
        read_drop_test,
        reduce_drop_test,
    )

    bad = [c for c in frame.columns if not isinstance(c, str)]
    if bad:
        raise ConfigError(
            [f"DataFrame column {bad[0]!r}: expected a header such as 'temperature [degC]'"]
        )
    with tempfile.TemporaryDirectory(prefix="ecdsim-fit-") as folder:
        path = Path(folder) / "dataframe.csv"
        frame.to_csv(path, index=False)
        try:
            table = read_drop_test(path, STANDARD_GRAVITY)
        except ConfigError as exc:
            raise ConfigError(exc.problems, "<DataFrame>") from None
    table = dataclasses.replace(table, source="<DataFrame>")
    return reduce_drop_test(table, reference_temperature, STANDARD_GRAVITY, noise=noise)


# ----------------------------------------------------------------------------- size


@dataclass(frozen=True, repr=False)
class SizeResults(_Table):
    """A catalogue search against the config's ``[requirements]``, best first.

    Attributes
    ----------
    search : the ranked candidates (:class:`~ecdsim.sizing.search.SearchResult`)
    intervals : exact feasible gear-ratio intervals of the best candidate (or None)
    requirements : what was required
    load : the load the candidates were sized for
    placeholder : the warning when that load is a marked placeholder, else None
    """

    search: SearchResult
    intervals: RatioIntervals | None
    requirements: Requirements
    load: Load
    placeholder: str | None = None
    caption = "sizing: candidates against the requirements, best first"

    @property
    def placeholder_load(self) -> bool:
        """True when the load sized for is a marked placeholder (no candidate's times are
        the mechanism's; ``placeholder`` holds the warning)."""
        return self.placeholder is not None

    def _flag(self) -> str | None:
        return self.placeholder

    def __repr__(self) -> str:
        """One line: how many candidates, how many pass, the best one."""
        candidates = self.search.candidates
        passed = sum(1 for c in candidates if c.passed)
        best = next((c for c in candidates if c.error is None), None)
        shown = (
            "no valid candidate"
            if best is None
            else f"best {best.candidate.damper.name!r} + {best.candidate.gearbox.name!r} at "
            f"ratio {best.candidate.ratio:g} ({'passes' if best.passed else 'fails'})"
        )
        from ecdsim.config.placeholder import TITLE

        flag = "" if self.placeholder is None else f" ({TITLE})"
        return f"<SizeResults{flag} {len(candidates)} candidates, {passed} pass; {shown}>"

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

    @overload
    def plot(
        self, top: int = 5, units: UnitSystem = "si", *, ax: None = None, kind: str = ...
    ) -> list[Figure]:
        pass

    @overload
    def plot(self, top: int = 5, units: UnitSystem = "si", *, ax: Axes, kind: str = ...) -> Axes:
        pass

    def plot(
        self,
        top: int = 5,
        units: UnitSystem = "si",
        *,
        ax: Axes | None = None,
        kind: str = "times",
    ) -> list[Figure] | Axes:
        """Deployment time over temperature of the ``top`` candidates, and ratio margins.

        Without ``ax``: a list of figures, the times and (when a candidate is valid) the
        best one's margins against the gear ratio. With ``ax`` (a matplotlib Axes): draws
        one plot there, ``kind`` = ``"times"`` or ``"margins"``, and returns ``ax``.
        ``units``: ``"si"`` or ``"us"`` (the temperatures of the times plot).
        """
        import numpy as np

        from ecdsim.sizing.plots import plot_candidate_times, plot_ratio_margins
        from ecdsim.sizing.search import deployment_time_curves
        from ecdsim.units_display import check_system

        system = check_system(units, "units")
        chosen = _choose("kind", kind, list(SIZE_PLOT_KINDS)) if ax is not None else None
        if isinstance(top, bool) or not isinstance(top, int) or top < 1:
            raise ConfigError([f"top = {top!r}: expected a number of candidates >= 1"])
        if chosen == "margins":
            if self.intervals is None:
                raise ConfigError(
                    ["kind: 'margins' needs a valid candidate, and no candidate is valid"]
                )
            plot_ratio_margins(self.intervals, ax=ax)
            return cast("Axes", ax)
        valid = [c for c in self.search.candidates if c.error is None][:top]
        temps = np.linspace(
            min(self.requirements.temperatures), max(self.requirements.temperatures), 57
        )
        times = (
            deployment_time_curves([c.candidate for c in valid], self.load, temps)
            if valid
            else np.zeros((0, temps.size))
        )
        if ax is not None:
            plot_candidate_times(valid, temps, times, self.requirements, system, ax=ax)
            return ax
        figures = [plot_candidate_times(valid, temps, times, self.requirements, system)]
        if self.intervals is not None:
            figures.append(plot_ratio_margins(self.intervals))
        return figures


SIZE_PLOT_KINDS = ("times", "margins")


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
    from ecdsim.config import placeholder
    from ecdsim.sizing.catalogue import load_catalogue
    from ecdsim.sizing.ratio import ratio_intervals
    from ecdsim.sizing.requirements import Requirements
    from ecdsim.sizing.search import search

    config = _load(config_or_path, overrides)
    placeholder.warn(config)
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
    return SizeResults(result, intervals, requirements, load_, _placeholder_flag(config))


# ----------------------------------------------------------------------------- sweep


@dataclass(frozen=True, repr=False)
class SweepResults(_Table):
    """A what-if sweep: every point's prediction at each temperature by each method.

    Attributes
    ----------
    result : the library's table (:class:`ecdsim.sweeps.SweepResult`): rows, varied keys,
        errors of points the model could not evaluate
    config : the base config (overrides applied)
    """

    result: SweepResult
    config: Config

    @property
    def caption(self) -> str:  # type: ignore[override]
        """The table's caption: the system's name and the varied keys."""
        return f"{self.result.title}: sweep of {', '.join(v.key for v in self.result.varies)}"

    @property
    def placeholder_load(self) -> bool:
        """True when the base config's ``[load]`` is a marked placeholder."""
        return self._flag() is not None

    def _flag(self) -> str | None:
        return _placeholder_flag(self.config)

    @property
    def errors(self) -> list[tuple[int, str]]:
        """``(point, message)`` of the points the model could not evaluate."""
        return list(self.result.errors)

    def __repr__(self) -> str:
        """One line: the varied keys, the points, the rows."""
        points = len({row["point"] for row in self.result.rows})
        keys = ", ".join(v.column for v in self.result.varies)
        errors = len(self.result.errors)
        return (
            f"<SweepResults {_marked(self.result.title, self._flag())}: {points} points of "
            f"[{keys}], "
            f"{len(self.result.rows)} rows, {errors} point error{'s' if errors != 1 else ''}>"
        )

    def rows(self) -> list[dict[str, Any]]:
        """One row per (point, temperature, method): ``point``, each varied key (SI, the
        unit's suffix in the name: ``load.start_torque_Nm``), then the columns of
        :meth:`DeployResults.rows`, and ``error`` for a point the model cannot evaluate."""
        return [dict(row) for row in self.result.rows]

    def to_dataframe(self) -> Any:
        """The table as a pandas DataFrame (the columns of :meth:`rows`)."""
        _pandas()
        return self.result.to_dataframe()

    def write(self, path: str | os.PathLike[str]) -> Path:
        """Write the table atomically: Parquet (units, config hash and version in its
        metadata) if ``path`` ends .parquet, else CSV, as ``ecdsim sweep -o``."""
        return self.result.write(Path(path))

    @overload
    def plot(
        self,
        output: str = "deployment_time_s",
        method: str | None = None,
        *,
        units: UnitSystem = "si",
        ax: None = None,
        panel: float | str | None = None,
    ) -> Figure:
        pass

    @overload
    def plot(
        self,
        output: str = "deployment_time_s",
        method: str | None = None,
        *,
        units: UnitSystem = "si",
        ax: Axes,
        panel: float | str | None = None,
    ) -> Axes:
        pass

    def plot(
        self,
        output: str = "deployment_time_s",
        method: str | None = None,
        *,
        units: UnitSystem = "si",
        ax: Axes | None = None,
        panel: float | str | None = None,
    ) -> Figure | Axes:
        """``output`` against the varied keys by ``method`` (``ecdsim sweep --plot``).

        Without ``ax``: the figure (a panel per temperature for two or more keys; points
        against each key for a Latin hypercube). With ``ax`` (a matplotlib Axes): draws
        one panel there, titled, its legend inside, and returns ``ax``; ``panel`` chooses
        it, one of :meth:`panels` (a temperature [degC], or a varied key; default the
        first). ``units``: ``"si"`` or ``"us"``.
        """
        from ecdsim.units_display import check_system

        system = check_system(units, "units")
        varied = {v.column for v in self.result.varies}
        columns = [c for c in self.result.columns if c not in varied]
        _choose("output", output, columns)
        if method is not None:
            _choose("method", method, list(self.result.methods))
        if panel is not None:
            choices = self.panels(method)
            if panel not in choices or isinstance(panel, bool):
                from ecdsim.config.units import quoted

                raise UnknownNameError([f"panel: {quoted(panel)} is not one of {choices}"])
        if ax is None:
            return self.result.plot(output, method, system, panel=panel)
        self.result.plot(output, method, system, ax=ax, panel=panel)
        return ax

    def panels(self, method: str | None = None) -> list[float | str]:
        """The panels :meth:`plot` can draw on one Axes: the temperatures [degC] of a
        sweep of two or more keys, or the varied keys of a Latin hypercube; [] when the
        figure is one panel."""
        if method is not None:
            _choose("method", method, list(self.result.methods))
        return self.result.panels(method)


def sweep(
    config_or_path: ConfigLike,
    vary: Mapping[str, object] | Sequence[str],
    *,
    latin: int | None = None,
    seed: int = 0,
    temperatures: object = None,
    methods: str | Sequence[str] | None = None,
    overrides: Mapping[str, object] | None = None,
) -> SweepResults:
    """Vary config keys over a full factorial grid or a Latin hypercube (``ecdsim sweep``).

    ``vary``: ``{"gearbox.ratio": [300, 380, 450], "load.start_torque": "3.2:4.2:5 N*m"}``
    (a list of values: numbers in SI, strings with units, pint quantities; or a string
    ``START:STOP:N [UNIT]``), or the command line's ``["gearbox.ratio=300:450:4", ...]``.
    ``latin``: that many points of a Latin hypercube drawn with ``seed`` instead of the
    grid. ``temperatures``, ``methods``, ``overrides``: as :func:`deploy`.

    >>> s = sweep("examples/paper_cc16.toml", {"gearbox.ratio": [300, 400]},
    ...           temperatures=25, methods="exact")
    >>> s.to_dataframe()[["gearbox.ratio", "deployment_time_s"]].round(2).values.tolist()
    [[300.0, 15.26], [400.0, 30.53]]
    """
    from ecdsim.config import placeholder
    from ecdsim.sweeps import SweepError, design, parse_vary, run_sweep

    config = _load(config_or_path, overrides)
    placeholder.warn(config)
    temps = config.temperatures if temperatures is None else _temperatures(temperatures)
    chosen = config.methods if methods is None else _methods(methods)
    specs = _vary_specs(vary)
    problems: list[str] = []
    varies = []
    for spec in specs:
        try:
            varies.append(parse_vary(spec, "vary"))
        except SweepError as exc:
            problems.extend(exc.problems)
    if latin is not None and (isinstance(latin, bool) or not isinstance(latin, int) or latin < 1):
        problems.append(f"latin = {latin!r}: expected a number of points >= 1")
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        problems.append(f"seed = {seed!r}: expected an integer >= 0")
    if problems:
        raise ConfigError(problems)
    raw, _ = _document(config_or_path, _overrides(overrides))
    try:
        points = design(varies, latin, seed)
        result = run_sweep(raw, config.source, varies, points, temps, chosen, config.sha256)
    except SweepError as exc:
        raise ConfigError(exc.problems) from None
    return SweepResults(result, config)


def _vary_specs(vary: object) -> list[str]:
    """``vary`` as the command line's ``KEY=VALUES`` strings."""
    from ecdsim.config.units import quoted

    if isinstance(vary, str):
        return [vary]
    if isinstance(vary, Mapping):
        specs = []
        for key, values in vary.items():
            if not isinstance(key, str):
                raise ConfigError([f"vary: key {quoted(key)} is not a config key"])
            if isinstance(values, str):
                specs.append(f"{key}={values}")
                continue
            items = [_vary_value(key, v) for v in _iterate(values)]
            specs.append(f"{key}={','.join(items)}")
        return specs
    if isinstance(vary, Iterable):
        specs = list(vary)
        bad = [v for v in specs if not isinstance(v, str)]
        if bad:
            raise ConfigError([f"vary: {quoted(bad[0])} is not a KEY=VALUES string"])
        return specs
    raise ConfigError(
        [f"vary = {quoted(vary)}: expected a mapping of config keys to values, or KEY=VALUES"]
    )


def _vary_value(key: str, value: object) -> str:
    """One value of a varied key as ``--vary`` text: a number, or a number and unit."""
    import numbers

    from ecdsim.config.units import quoted

    value = _plain(value)
    if _is_quantity(value):
        quantity: Any = value
        return f"{float(quantity.magnitude)!r} {quantity.units}"
    if not isinstance(value, bool) and isinstance(value, numbers.Real):
        return repr(float(value))
    if isinstance(value, str) and "," not in value:
        return value
    raise ConfigError([f"vary {key}: {quoted(value)} is not a number or a quantity string"])
