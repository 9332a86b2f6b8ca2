"""What-if sweeps: vary any config keys, predict at every point, and gather a tidy table.

A sweep varies config keys by their dotted names (``gearbox.ratio``, ``load.inertia``;
see :mod:`ecdsim.config.overrides`) over a full factorial grid or a Latin hypercube,
runs :func:`ecdsim.deployment.predict` at every point with the config's temperatures and
methods, and returns one row per (point, temperature, method): the varied values (in
SI, the unit in the column name), then the same quantities as
:func:`prediction_rows` (the notebook API's ``deploy(...).to_dataframe()``).

Value syntax (``ecdsim sweep --vary``):

* ``KEY=START:STOP:N`` or ``KEY=START:STOP:N UNIT``: N >= 2 evenly spaced values
  (Latin hypercube: the continuous range START..STOP, N ignored);
* ``KEY=V1,V2,...``: a list, each a number with an optional unit (``1 kg*m^2``).

A plain number is read in the key's SI unit (temperatures in degC).
"""

from __future__ import annotations

import itertools
import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ecdsim.config.units import NUMBER_PATTERN, Kind

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure
    from numpy.typing import NDArray

    from ecdsim._types import FloatArray
    from ecdsim.deployment import Prediction
    from ecdsim.units_display import UnitSystem

MAX_POINTS = 100_000

_RANGE = re.compile(rf"^\s*({NUMBER_PATTERN})\s*:\s*({NUMBER_PATTERN})\s*:\s*(\S+?)\s*(?:\s(.*))?$")
_ITEM = re.compile(rf"^\s*({NUMBER_PATTERN})\s*(.*?)\s*$")
_KEY = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*(\.[A-Za-z_][A-Za-z0-9_]*)*$")


class SweepError(ValueError):
    """A bad sweep specification; ``problems`` holds one line each."""

    def __init__(self, problems: list[str]) -> None:
        self.problems = list(problems)
        super().__init__("\n".join(self.problems))


@dataclass(frozen=True)
class Vary:
    """One varied key.

    Attributes
    ----------
    key : dotted config key
    values : the values as the config reads them (numbers, or "number unit" strings)
    si : the same values in the key's SI unit (degC for temperatures; NaN if unknown)
    low, high : the range's ends for a Latin hypercube (None for a list)
    unit : the SI unit of ``si`` ("" for a plain number, None if the key has no unit)
    """

    key: str
    values: tuple[object, ...]
    si: tuple[float, ...]
    low: object | None = None
    high: object | None = None
    unit: str | None = None

    @property
    def column(self) -> str:
        """The table column: the key with its SI unit's suffix (``load.start_torque_Nm``;
        ``gearbox.ratio`` for a plain number), as every ecdsim table names it (ecdsim.tidy).
        """
        from ecdsim.tidy import key_column

        return key_column(self.key, self.unit)


def _fields(key: str) -> Any:
    """The module that knows ``key``'s kind: a wing file's key paths
    (:mod:`ecdsim.config.wing_keys`, ``wing.hinges[1].friction.at_0C``), else a single
    hinge's dotted keys (:mod:`ecdsim.config.overrides`)."""
    from ecdsim.config import overrides, wing_keys

    return wing_keys if wing_keys.is_wing_key(key) else overrides


def _si(key: str, value: object) -> float:
    fields = _fields(key)
    config_value, field_kind = fields.config_value, fields.field_kind
    kind: Kind | None = field_kind(key)
    if kind is None:
        return float(value) if isinstance(value, int | float) else math.nan
    return kind.parse(config_value(key, value))


def parse_vary(text: str, option: str = "--vary") -> Vary:
    """Read one ``KEY=VALUES`` specification; :class:`SweepError` (one line) if bad."""
    from ecdsim.config.units import QuantityError

    key, sep, spec = text.partition("=")
    key = key.strip()
    shown = key or text
    syntax = "expected KEY=START:STOP:N [UNIT] or KEY=V1,V2,... (e.g. gearbox.ratio=200:600:21)"
    from ecdsim.config.wing_keys import is_wing_key

    if not sep or not (_KEY.match(key) or is_wing_key(key)):
        raise SweepError([f"{option} {text!r}: {shown!r} is not a config key; {syntax}"])
    if not spec.strip():
        raise SweepError([f"{option} {key}: no values; {syntax}"])
    unit = _fields(key).field_unit(key)
    low: object | None = None
    high: object | None = None
    match = _RANGE.match(spec)
    if match:
        start, stop, count, unit_text = match.groups()
        if not re.fullmatch(r"\d+", count) or int(count) < 2:
            raise SweepError(
                [f"{option} {key}: the count {count!r} is not an integer >= 2; {syntax}"]
            )
        n = int(count)
        if n > MAX_POINTS:
            raise SweepError([f"{option} {key}: {n} values, more than {MAX_POINTS}"])
        numbers = np.linspace(float(start), float(stop), n)
        values: list[object] = [
            f"{float(x)!r} {unit_text}" if unit_text else float(x) for x in numbers
        ]
        low, high = values[0], values[-1]
    elif ":" in spec:
        raise SweepError([f"{option} {key}: {spec!r} is not START:STOP:N; {syntax}"])
    else:
        values = []
        for item in spec.split(","):
            found = _ITEM.match(item)
            if found is None:
                raise SweepError(
                    [f"{option} {key}: {item.strip()!r} is not a number with an optional unit"]
                )
            number, unit_text = found.groups()
            values.append(f"{number} {unit_text}" if unit_text else float(number))
    try:
        si = tuple(_si(key, v) for v in values)
    except (QuantityError, ValueError) as exc:
        raise SweepError([f"{option} {key}: {exc}"]) from None
    return Vary(key, tuple(values), si, low, high, unit)


def design(
    varies: Sequence[Vary], latin: int | None = None, seed: int = 0
) -> list[dict[str, tuple[object, float]]]:
    """The sweep's points: each a mapping key -> (config value, SI value).

    Full factorial (every combination, the last key varying fastest) when ``latin`` is
    None; else ``latin`` points of a Latin hypercube drawn with ``seed``: a range key
    is sampled uniformly over START..STOP (in the range's own unit), a list key picks
    its values in equal strata.
    """
    if not varies:
        raise SweepError(["--vary: give at least one KEY=VALUES"])
    keys = [v.key for v in varies]
    if len(set(keys)) != len(keys):
        twice = sorted({k for k in keys if keys.count(k) > 1})
        raise SweepError([f"--vary {k}: given more than once" for k in twice])
    if latin is None:
        total = math.prod(len(v.values) for v in varies)
        if total > MAX_POINTS:
            raise SweepError([f"--vary: {total} points, more than {MAX_POINTS}; use --latin N"])
        return [
            {v.key: (v.values[i], v.si[i]) for v, i in zip(varies, combo, strict=True)}
            for combo in itertools.product(*(range(len(v.values)) for v in varies))
        ]
    if latin < 1 or latin > MAX_POINTS:
        raise SweepError([f"--latin {latin}: expected 1 to {MAX_POINTS} points"])
    from ecdsim.config.seeds import seed_problem  # the one rule for seeds

    bad_seed = seed_problem(seed)
    if bad_seed is not None:
        raise SweepError([f"--seed {seed}: {bad_seed}"])
    rng = np.random.default_rng(seed)
    points: list[dict[str, tuple[object, float]]] = [{} for _ in range(latin)]
    for v in varies:
        # One stratum per point, in random order, and a uniform position within it.
        u = (rng.permutation(latin) + rng.random(latin)) / latin
        for point, ui in zip(points, u, strict=True):
            if v.low is not None and v.high is not None:
                a, b = v.si[0], v.si[-1]
                si = a + float(ui) * (b - a)
                lo_value = v.low
                if isinstance(lo_value, str):
                    # the range's own unit: interpolate the magnitudes, keep the unit text
                    lo_num = float(lo_value.split()[0])
                    hi_num = float(str(v.high).split()[0])
                    unit_text = lo_value.split(maxsplit=1)[1]
                    value: object = f"{lo_num + float(ui) * (hi_num - lo_num)!r} {unit_text}"
                    si = _si(v.key, value)
                else:
                    value = si
                point[v.key] = (value, si)
            else:
                i = min(int(ui * len(v.values)), len(v.values) - 1)
                point[v.key] = (v.values[i], v.si[i])
    return points


def _scalar(value: object) -> object:
    if value is None:
        return math.nan
    if isinstance(value, bool | int | float | str):
        return value
    return None


def prediction_rows(prediction: Prediction) -> list[dict[str, Any]]:
    """One row per (temperature, method): inputs at T and the method's results, SI.

    Column names carry their units as ``docs/json.md`` spells them (``temperature_C``,
    ``deployment_time_s``, ``damping_rate_Nms_per_rad``); a missing value is NaN. A
    nested object of the method's block becomes columns (``energy_J.spring_work`` ->
    ``energy_spring_work_J``, :func:`ecdsim.tidy.flatten`).
    """
    from ecdsim.tidy import flatten

    document = prediction.to_dict()
    rows = []
    for case in document["cases"]:
        shared = {
            "temperature_C": case["temperature_C"],
            "damping_rate_Nms_per_rad": case["damping_rate_Nms_per_rad"],
            "friction_Nm": case["friction_Nm"],
            "system_friction_Nm": case["system_friction_Nm"],
            "total_friction_Nm": case["total_friction_Nm"],
        }
        for method in document["methods"]:
            row: dict[str, Any] = {"temperature_C": shared["temperature_C"], "method": method}
            row.update({k: v for k, v in shared.items() if k != "temperature_C"})
            for name, value in flatten(case[method]).items():
                scalar = _scalar(value)
                if scalar is not None:
                    row[name] = scalar
            rows.append(row)
    return rows


@dataclass
class SweepResult:
    """A finished sweep: the rows, the varied keys, and what every point ran.

    Attributes
    ----------
    rows : one dict per (point, temperature, method)
    varies : the varied keys
    title : the config's title
    methods : the methods run at each point
    errors : ``(point index, message)`` for points the model could not evaluate
    config_sha256 : SHA-256 of the base config (stamped into a Parquet file's metadata)
    """

    rows: list[dict[str, Any]]
    varies: list[Vary]
    title: str
    methods: tuple[str, ...]
    errors: list[tuple[int, str]] = field(default_factory=list)
    config_sha256: str = ""

    @property
    def columns(self) -> list[str]:
        """Every column, in order of first appearance."""
        seen: dict[str, None] = {}
        for row in self.rows:
            seen.update(dict.fromkeys(row))
        return list(seen)

    def to_dataframe(self) -> Any:
        """The table as a pandas DataFrame (flags nullable ``boolean``, counts ``Int64``)."""
        from ecdsim.tidy import dataframe

        return dataframe(self.rows, self.columns)

    def metadata(self) -> dict[str, Any]:
        """What a Parquet file of the table carries besides its columns: the units of
        the columns, the config's hash, ecdsim's version, the varied keys and methods."""
        from ecdsim._version import __version__
        from ecdsim.tidy import units_of

        return {
            "ecdsim_version": __version__,
            "kind": "sweep",
            "system": self.title,
            "config_sha256": self.config_sha256,
            "varied": [v.key for v in self.varies],
            "methods": list(self.methods),
            # a varied plain number (gearbox.ratio) is dimensionless: "1", as CF writes it
            "units": {
                **{v.column: "1" for v in self.varies if v.unit == ""},
                **units_of(self.columns),
            },
        }

    def to_document(self) -> dict[str, Any]:
        """The JSON document of ``ecdsim sweep --json``: :meth:`metadata` and the rows
        (NaN as null; docs/json.md)."""
        return {**self.metadata(), "rows": [_json_row(row) for row in self.rows]}

    def to_csv(self) -> str:
        """The table as CSV text (NaN as an empty cell, numbers with full precision)."""
        import csv
        import io

        buffer = io.StringIO()
        writer = csv.writer(buffer, lineterminator="\n")
        columns = self.columns
        writer.writerow(columns)
        for row in self.rows:
            writer.writerow([_cell(row.get(c)) for c in columns])
        return buffer.getvalue()

    def write(self, path: str | Path) -> Path:
        """Write the table atomically: Parquet if ``path`` ends .parquet, else CSV.

        Parquet needs pyarrow (``pip install 'ecdsim[montecarlo]'``).
        """
        from ecdsim import atomic

        target = Path(path)
        if target.suffix.lower() != ".parquet":
            return atomic.write_text(target, self.to_csv())
        try:
            import pyarrow.parquet as pq
        except ImportError:
            from ecdsim.invocation import install_hint

            raise ModuleNotFoundError(
                f"Parquet output needs pyarrow; {install_hint('montecarlo')}"
            ) from None
        table = parquet_table(self.to_dataframe(), self.metadata())
        return atomic.write_with(target, lambda handle: pq.write_table(table, handle))

    def plot(
        self,
        column: str = "deployment_time_s",
        method: str | None = None,
        units: UnitSystem = "si",
        *,
        output: str | None = None,
        ax: Axes | None = None,
        panel: float | str | None = None,
    ) -> Figure:
        """``column`` of the sweep against its varied keys, by one method.

        ``method`` defaults to the most exact method run (dynamic, else exact, else
        paper: :func:`ecdsim.plotting.most_exact`). A full factorial sweep draws one panel
        per temperature with the key of most levels along x and one line per level of the
        other key (per combination of the others, when there are more, up to
        :data:`MAX_LINES`); a Latin hypercube (or more combinations) draws the points
        against each varied key, a colour per temperature. A point that stalls (or sticks,
        or cannot start) has no deployment: it is marked by a cross at the top of its
        panel, in its line's colour, never dropped. ``output`` is the old name of
        ``column`` (before issue 26).

        ``ax`` (a matplotlib Axes): draw one panel there, titled and with its legend inside
        it, and return its figure; ``panel`` chooses which (one of :meth:`panels`: a
        temperature [degC] or a varied key; default the first). ``panel`` without ``ax``
        draws that panel alone on a new figure.
        """
        column = output if output is not None else column
        chosen, rows = self._method_rows(method)
        if column not in self.columns:
            known = [c for c in self.columns if c not in {v.column for v in self.varies}]
            raise KeyError(f"{column!r} is not an output of this sweep; known: {known}")
        choices = self.panels(chosen)
        if panel is not None and panel not in choices:
            raise KeyError(f"{panel!r} is not a panel of this plot; panels: {choices}")
        lines = _line_plan(self.varies, rows)
        if ax is not None or panel is not None:
            return self._one_panel(rows, column, chosen, units, lines, ax, panel)
        if lines is None:
            return self._scatter(rows, column, chosen, units)
        return self._lines(rows, column, chosen, units, *lines)

    def panels(self, method: str | None = None) -> list[float | str]:
        """The panels of :meth:`plot`'s figure by ``method``: the temperatures [degC] of a
        sweep of two or more keys (a panel per temperature), or the varied keys of points
        drawn against each key (a Latin hypercube of two or more keys); [] for a figure of
        one panel."""
        _, rows = self._method_rows(method)
        lines = _line_plan(self.varies, rows)
        if lines is None:
            return [v.key for v in self.varies] if len(self.varies) > 1 else []
        return sorted({float(r["temperature_C"]) for r in rows}) if lines[1] else []

    def _method_rows(self, method: str | None) -> tuple[str, list[dict[str, Any]]]:
        """The method plotted (``method``, else the most exact run) and its rows."""
        from ecdsim.plotting import most_exact

        chosen = method or most_exact(self.methods)
        rows = [r for r in self.rows if r.get("method") == chosen]
        if chosen not in self.methods or not rows:
            raise KeyError(f"{chosen!r} is not a method of this sweep; ran: {list(self.methods)}")
        return chosen, rows

    def _frame(
        self, column: str, method: str, units: UnitSystem, how: str, inches: float
    ) -> tuple[str, str]:
        """The title, wrapped to ``inches`` (the figure's or one axes' width), and the y
        label (``column`` with its display unit)."""
        from ecdsim.plotting import plot_title

        what = f"{_label(column, units)} by the {method} method, {how}".rstrip(", ")
        width = max(int(12 * inches), 30)  # characters of the title's font per line
        return plot_title(self.title, what, width=width), _label(column, units)

    def _lines(
        self,
        rows: list[dict[str, Any]],
        column: str,
        method: str,
        units: UnitSystem,
        x_vary: Vary,
        others: list[Vary],
    ) -> Figure:
        from ecdsim.plotting import _figure
        from ecdsim.units_display import Shown

        temps = sorted({float(r["temperature_C"]) for r in rows})
        # One key: one panel, a line per temperature in its colour. More keys: a panel per
        # temperature, a line per level of the others.
        panels: list[float | None] = list(temps) if others else [None]
        n = len(panels)
        cols = min(n, 3)
        fig = _figure(width=max(6.0, 4.3 * cols), height=4.8 if n <= 3 else 8.4)
        axes: list[Any] = []
        stalls_drawn = False
        for k, panel in enumerate(panels):
            ax = fig.add_subplot(
                (n + cols - 1) // cols, cols, k + 1, sharey=axes[0] if axes else None
            )
            axes.append(ax)
            stalls_drawn |= _line_panel(ax, rows, column, units, x_vary, others, panel)
            if panel is not None:
                ax.set_title(f"T = {Shown(units).text(panel, 'temperature')}", fontsize="medium")
            if k % cols == 0:
                ax.set_ylabel(_label(column, units))
        handles, labels, title = _legend_entries(axes[0], others, stalls_drawn)
        _figure_legend(fig, handles, labels, title)
        title, _ = self._frame(column, method, units, _how(others), fig.get_figwidth())
        fig.suptitle(title)
        return fig

    def _scatter(
        self, rows: list[dict[str, Any]], column: str, method: str, units: UnitSystem
    ) -> Figure:
        from ecdsim.plotting import _figure

        n = len(self.varies)
        cols = min(n, 3)
        fig = _figure(width=max(5.5, 4.3 * cols), height=4.6 if n <= 3 else 8.4)
        axes: list[Any] = []
        stalls_drawn = False
        for k, vary in enumerate(self.varies):
            ax = fig.add_subplot(
                (n + cols - 1) // cols, cols, k + 1, sharey=axes[0] if axes else None
            )
            axes.append(ax)
            stalls_drawn |= _scatter_panel(ax, rows, column, units, vary)
            if k % cols == 0:
                ax.set_ylabel(_label(column, units))
        handles, labels, _ = _legend_entries(axes[0], [], stalls_drawn)
        _figure_legend(fig, handles, labels, "temperature")
        title, _ = self._frame(column, method, units, "every point", fig.get_figwidth())
        fig.suptitle(title)
        return fig

    def _one_panel(
        self,
        rows: list[dict[str, Any]],
        column: str,
        method: str,
        units: UnitSystem,
        lines: tuple[Vary, list[Vary]] | None,
        ax: Axes | None,
        panel: float | str | None,
    ) -> Figure:
        """One panel of the figure on ``ax`` (or a new figure), titled, its legend inside."""
        from ecdsim.plotting import target
        from ecdsim.units_display import Shown

        fig, ax = target(ax)
        choices = self.panels(method)
        chosen = panel if panel is not None else (choices[0] if choices else None)
        if lines is None:
            vary = next((v for v in self.varies if v.key == chosen), self.varies[0])
            stalls = _scatter_panel(ax, rows, column, units, vary)
            others: list[Vary] = []
            how = "every point"
            legend_title = "temperature"
        else:
            x_vary, others = lines
            temperature = float(chosen) if chosen is not None else None
            stalls = _line_panel(ax, rows, column, units, x_vary, others, temperature)
            how = _how(others)
            if temperature is not None:
                how += f", T = {Shown(units).text(temperature, 'temperature')}"
            legend_title = None
        ax.set_ylabel(_label(column, units))
        handles, labels, title = _legend_entries(ax, others, stalls)
        ax.legend(handles, labels, title=legend_title or title, fontsize="small")
        inches = fig.get_figwidth() * ax.get_position().width  # the axes' own width
        heading, _ = self._frame(column, method, units, how, inches)
        ax.set_title(heading, fontsize="medium")
        return fig


def _how(others: list[Vary]) -> str:
    """What the lines of a panel are, for its title."""
    return f"one line per {' and '.join(v.key for v in others)}" if others else ""


def _line_panel(
    ax: Any,
    rows: list[dict[str, Any]],
    column: str,
    units: UnitSystem,
    x_vary: Vary,
    others: list[Vary],
    panel: float | None,
) -> bool:
    """One panel of a full factorial sweep: ``column`` against ``x_vary``, a line per
    temperature (one key), or at temperature ``panel`` a line per level of ``others``.
    True when it marks a point that does not deploy."""
    from ecdsim.plotting import level_colors, temperature_colors
    from ecdsim.units_display import Shown

    u = Shown(units)
    temps = sorted({float(r["temperature_C"]) for r in rows})
    if others:
        groups = sorted({tuple(r[v.column] for v in others) for r in rows})
        colors = level_colors(len(groups))
    else:
        groups = [(t,) for t in temps]
        colors = temperature_colors(temps)
    stalls_drawn = False
    for row, (group, color) in enumerate(zip(groups, colors, strict=True)):
        if others:
            mine = [
                r
                for r in rows
                if float(r["temperature_C"]) == panel
                and tuple(r[v.column] for v in others) == group
            ]
            label = _group_label(others, group, units)
        else:
            mine = [r for r in rows if float(r["temperature_C"]) == group[0]]
            label = u.text(group[0], "temperature")
        stalls_drawn |= _draw(ax, mine, x_vary, column, units, color, row, label, "o-")
    ax.set_xlabel(_vary_label(x_vary, units))
    ax.grid(True, alpha=0.3)
    return stalls_drawn


def _scatter_panel(
    ax: Any, rows: list[dict[str, Any]], column: str, units: UnitSystem, vary: Vary
) -> bool:
    """One panel of points: ``column`` against ``vary``, a colour per temperature. True
    when it marks a point that does not deploy."""
    from ecdsim.plotting import temperature_colors
    from ecdsim.units_display import Shown

    u = Shown(units)
    temps = sorted({float(r["temperature_C"]) for r in rows})
    stalls_drawn = False
    for row, (temp, color) in enumerate(zip(temps, temperature_colors(temps), strict=True)):
        mine = [r for r in rows if float(r["temperature_C"]) == temp]
        label = u.text(temp, "temperature")
        stalls_drawn |= _draw(ax, mine, vary, column, units, color, row, label, "o", alpha=0.8)
    ax.set_xlabel(_vary_label(vary, units))
    ax.grid(True, alpha=0.3)
    return stalls_drawn


def _draw(
    ax: Any,
    rows: list[dict[str, Any]],
    vary: Vary,
    column: str,
    units: UnitSystem,
    color: Any,
    row: int,
    label: str,
    style: str,
    **options: Any,
) -> bool:
    """``column`` of ``rows`` against ``vary`` in ``style`` and ``color``, the points that
    do not deploy crossed at the top (the ``row``-th line's height); True if any is."""
    x, y, stalled = _series(rows, vary, column, units)
    ax.plot(x, np.where(stalled, np.nan, y), style, color=color, ms=3.5, label=label, **options)
    if np.any(stalled):
        _mark_stalls(ax, x[stalled], color, row)
        return True
    return False


PARQUET_KEY = b"ecdsim"


def parquet_table(frame: Any, metadata: dict[str, Any]) -> Any:
    """A pyarrow table of ``frame`` whose schema carries ``metadata`` (JSON, key
    ``ecdsim``) and, on each column with a unit, that unit (field metadata ``unit``)."""
    import json

    import pyarrow as pa

    table = pa.Table.from_pandas(frame, preserve_index=False)
    units = metadata.get("units", {})
    fields = [
        field.with_metadata({b"unit": units[field.name].encode()}) if field.name in units else field
        for field in table.schema
    ]
    schema = pa.schema(fields, metadata=table.schema.metadata)
    table = table.cast(schema)
    document = json.dumps(metadata, sort_keys=True, allow_nan=False).encode("utf-8")
    return table.replace_schema_metadata({**(schema.metadata or {}), PARQUET_KEY: document})


# At most this many lines per panel: more combinations of the other keys are drawn as points.
MAX_LINES = 12


def _line_plan(
    varies: Sequence[Vary], rows: list[dict[str, Any]]
) -> tuple[Vary, list[Vary]] | None:
    """For a full factorial sweep: the key along x (the one of most levels, the first on a
    tie) and the keys whose levels make the lines; None for points (a Latin hypercube, or
    more than :data:`MAX_LINES` lines)."""
    levels = [sorted({float(r[v.column]) for r in rows}) for v in varies]
    points = {tuple(float(r[v.column]) for v in varies) for r in rows}
    factorial = len(points) == math.prod(len(found) for found in levels) and all(
        set(found) <= {float(x) for x in v.si} for v, found in zip(varies, levels, strict=True)
    )
    if not factorial:
        return None
    x_index = max(range(len(varies)), key=lambda i: (len(levels[i]), -i))
    others = [v for i, v in enumerate(varies) if i != x_index]
    if math.prod(len(levels[i]) for i in range(len(varies)) if i != x_index) > MAX_LINES:
        return None
    return varies[x_index], others


def _not_deployed(row: Mapping[str, Any]) -> bool:
    """A point that stalls, sticks or cannot start (no deployment time), not an error."""
    return "error" not in row and bool(row.get("stalled") or row.get("stuck"))


def _series(
    rows: list[dict[str, Any]], vary: Vary, column: str, units: UnitSystem
) -> tuple[FloatArray, FloatArray, NDArray[np.bool_]]:
    """x (the varied key in display units), y (``column`` in display units) and which
    points do not deploy, sorted along x."""
    from ecdsim.units_display import convert

    x = np.array([_shown(float(r[vary.column]), vary.unit or "", units) for r in rows])
    kind = kind_of_column(column)
    y = np.array([_number(r.get(column)) for r in rows])
    if kind is not None:
        y = np.array([convert(v, kind, units) if math.isfinite(v) else v for v in y])
    stalled = np.array([_not_deployed(r) for r in rows], dtype=bool)
    order = np.argsort(x, kind="stable")
    return x[order], y[order], stalled[order]


def _mark_stalls(ax: Any, x: FloatArray, color: Any, row: int = 0) -> None:
    """Crosses at the top of the panel over the x values that do not deploy; ``row``
    (the line's index) moves each line's crosses down a little, so none hides another."""
    ax.plot(
        x,
        np.full(x.shape, 0.97 - 0.045 * row),
        "x",
        color=color,
        ms=8,
        mew=2,
        transform=ax.get_xaxis_transform(),
        clip_on=False,
    )


def _legend_entries(ax: Any, others: list[Vary], stalls: bool) -> tuple[list[Any], list[str], str]:
    """The legend of a sweep plot: the lines, then what a cross means; and its title."""
    from matplotlib.lines import Line2D

    handles, labels = ax.get_legend_handles_labels()
    if stalls:
        handles.append(Line2D([], [], marker="x", ls="", color="0.2", ms=8, mew=2))
        labels.append("x at the top: stalls (no deployment)")
    title = ", ".join(v.key for v in others) if others else "temperature"
    return handles, labels, title


def _figure_legend(fig: Any, handles: list[Any], labels: list[str], title: str) -> None:
    """One legend for the figure, below the panels."""
    fig.legend(
        handles,
        labels,
        title=title,
        loc="outside lower center",
        ncols=min(len(labels), 4),
        fontsize="small",
    )


def kind_of_column(column: str) -> str | None:
    """The kind of quantity a table column holds ("time", "torque"), from its unit: a
    bracketed SI unit (``load.start_torque [N*m]``) or a key suffix
    (``deployment_time_s``); None for a plain number."""
    from ecdsim.units_display import KIND_BY_SI_UNIT, kind_of_key

    name, unit = _split_unit(column)
    if unit is not None:
        return KIND_BY_SI_UNIT.get(unit)
    return kind_of_key(name)


def _split_unit(column: str) -> tuple[str, str | None]:
    """``"key [unit]"`` -> ("key", "unit"); anything else -> (column, None)."""
    if column.endswith("]") and " [" in column:
        name, _, unit = column[:-1].rpartition(" [")
        return name, unit
    return column, None


def _label(column: str, units: UnitSystem = "si") -> str:
    """A column as an axis label in ``units``: ``deployment_time_s`` -> ``deployment time
    [s]``, ``load.start_torque_Nm`` -> ``load.start_torque [lbf*in]`` in US units."""
    from ecdsim.units_display import KEY_SUFFIXES, header

    name, unit = _split_unit(column)
    kind = kind_of_column(column)
    if unit is None:
        # A config key (dotted: load.end_torque_Nm) keeps its underscores; a result
        # column reads as words (deployment_time_s -> deployment time).
        for suffix, _ in KEY_SUFFIXES:
            if kind is not None and name.endswith(suffix):
                name = name[: -len(suffix)]
                break
        if "." not in name:
            name = name.replace("_", " ")
    if kind is None:
        return f"{name} [{unit}]" if unit else name
    return header(name, kind, units)


def _vary_label(vary: Vary, units: UnitSystem) -> str:
    return _label(vary.column, units)


def _shown(value: float, si_unit: str, units: UnitSystem) -> float:
    """An SI value of a quantity in ``si_unit`` in the display ``units``."""
    from ecdsim.units_display import KIND_BY_SI_UNIT, convert

    kind = KIND_BY_SI_UNIT.get(si_unit)
    return value if kind is None or not math.isfinite(value) else convert(value, kind, units)


def _group_label(others: Sequence[Vary], group: tuple[Any, ...], units: UnitSystem) -> str:
    """One line's label: the other keys' values with their display units ("3.2 N*m")."""
    from ecdsim.formatting import format_number
    from ecdsim.units_display import KIND_BY_SI_UNIT, format_quantity

    parts = []
    for vary, value in zip(others, group, strict=True):
        kind = KIND_BY_SI_UNIT.get(vary.unit or "")
        text = (
            format_quantity(float(value), kind, units)
            if kind is not None
            else format_number(float(value))
        )
        parts.append(text if len(others) == 1 else f"{vary.key} = {text}")
    return ", ".join(parts)


def _json_row(row: Mapping[str, Any]) -> dict[str, Any]:
    """A row with NaN and infinities as null (JSON has neither)."""
    return {k: None if isinstance(v, float) and not math.isfinite(v) else v for k, v in row.items()}


def _number(value: object) -> float:
    if isinstance(value, bool):
        return float(value)
    return float(value) if isinstance(value, int | float) else math.nan


def _cell(value: object) -> object:
    if isinstance(value, float):
        return "" if math.isnan(value) else repr(value)
    return "" if value is None else value


def run_sweep(
    raw: Mapping[str, Any],
    source: str,
    varies: Sequence[Vary],
    points: Sequence[Mapping[str, tuple[object, float]]],
    temperatures: Sequence[float] | None = None,
    methods: Sequence[str] | None = None,
    config_sha256: str | None = None,
) -> SweepResult:
    """Validate every point's config, then predict at each and gather the rows.

    ``raw`` is the parsed TOML document of the base config; ``config_sha256`` its
    file's hash (default: the hash of ``raw`` as canonical JSON). Every invalid point is
    reported before anything runs (:class:`SweepError`, one line per problem naming
    ``--vary`` and the key); a point the model cannot evaluate (damping <= 0, ...)
    gives rows with the ``error`` column set and NaN results.
    """
    import hashlib
    import json

    from ecdsim.config import ConfigError
    from ecdsim.config.loader import validate
    from ecdsim.config.overrides import apply_overrides
    from ecdsim.config.wing_keys import is_wing_key
    from ecdsim.model import DeploymentSystem

    specs: list[Any] = []
    problems: list[str] = [
        f"--vary {v.key}: a wing file's key path, but {source} is a single hinge's file "
        "(its keys: gearbox.ratio, load.inertia, ...; docs/config.md)"
        for v in varies
        if is_wing_key(v.key)
    ]
    if problems:
        raise SweepError(problems)
    seen: set[str] = set()
    for point in points:
        overrides = {k: value for k, (value, _) in point.items()}
        try:
            spec = validate(apply_overrides(raw, overrides), source)
        except ConfigError as exc:
            shown = ", ".join(f"{k}={v}" for k, v in overrides.items())
            for p in exc.problems:
                if p not in seen:
                    seen.add(p)
                    problems.append(f"--vary: {p} (at {shown})")
            continue
        specs.append(spec)
        if len(problems) >= 20:
            break
    if problems:
        raise SweepError(problems)
    from ecdsim.deployment import ModelDomainError, predict

    rows: list[dict[str, Any]] = []
    errors: list[tuple[int, str]] = []
    title = ""
    chosen_methods: tuple[str, ...] = ()
    for index, (point, spec) in enumerate(zip(points, specs, strict=True)):
        system = DeploymentSystem(ecd=spec.ecd(), load=spec.load.to_model(), name=spec.title)
        title = spec.title
        temps = tuple(temperatures) if temperatures else tuple(spec.analysis.temperatures)
        chosen_methods = tuple(methods) if methods else tuple(spec.analysis.methods)
        head: dict[str, Any] = {"point": index}
        head.update({v.column: point[v.key][1] for v in varies})
        try:
            prediction = predict(system, temps, chosen_methods, dynamics=spec.dynamics())
        except ModelDomainError as exc:
            errors.append((index, str(exc)))
            for temp in temps:
                for method in chosen_methods:
                    rows.append(
                        {**head, "temperature_C": temp, "method": method, "error": str(exc)}
                    )
            continue
        for row in prediction_rows(prediction):
            rows.append({**head, **row})
    if config_sha256 is None:
        text = json.dumps(raw, sort_keys=True, default=str)
        config_sha256 = hashlib.sha256(text.encode("utf-8")).hexdigest()
    return SweepResult(rows, list(varies), title, chosen_methods, errors, config_sha256)


def run_wing_sweep(
    raw: Mapping[str, Any],
    source: str,
    varies: Sequence[Vary],
    points: Sequence[Mapping[str, tuple[object, float]]],
    temperatures: Sequence[float] | None = None,
    config_sha256: str = "",
    *,
    base: Path | None = None,
    read_catalogue: Any = None,
) -> SweepResult:
    """A sweep of a wing file (docs/wing.md, studies): each point's wing solved by
    :func:`ecdsim.wing.solver.deploy_wing` at every temperature, one row per (point,
    temperature) with :meth:`ecdsim.wing.result.WingResult.summary_rows`'s columns and
    ``method = "wing"``.

    The keys are the file's paths (``wing.panels[2].mass``); every point is validated as
    a file (and checked against what the wing's solver models) before anything runs
    (:class:`SweepError`, one line each); a point the solver cannot evaluate gives rows
    with ``error`` set. ``read_catalogue`` reads the file's catalogue entries
    (:func:`ecdsim.sizing.catalogue.load_catalogue`), ``base`` their folder.
    """
    from ecdsim.config import ConfigError
    from ecdsim.config.wing_keys import key_problem, set_values
    from ecdsim.config.wing_schema import wing_config_from_document
    from ecdsim.wing.solver import WingUnsupported, check_supported, deploy_wing

    problems = [f"--vary {problem}" for v in varies if (problem := key_problem(v.key)) is not None]
    if problems:
        raise SweepError(problems)
    configs: list[Any] = []
    seen: set[str] = set()
    folder = base if base is not None else Path(source).parent
    for point in points:
        values = {k: value for k, (value, _) in point.items()}
        shown = ", ".join(f"{k}={v}" for k, v in values.items())
        try:
            config = wing_config_from_document(
                set_values(raw, values), source, folder, read_catalogue, config_sha256
            )
            check_supported(config.wing)
        except (ConfigError, WingUnsupported) as exc:
            lines = exc.problems if isinstance(exc, ConfigError) else [str(exc)]
            for line in lines:
                if line not in seen:
                    seen.add(line)
                    problems.append(f"--vary: {line} (at {shown})")
            if len(problems) >= 20:
                break
            continue
        configs.append(config)
    if problems:
        raise SweepError(problems)
    rows: list[dict[str, Any]] = []
    errors: list[tuple[int, str]] = []
    title = ""
    for index, (point, config) in enumerate(zip(points, configs, strict=True)):
        title = config.spec.title
        temps = tuple(temperatures) if temperatures else config.temperatures
        head: dict[str, Any] = {"point": index}
        head.update({v.column: point[v.key][1] for v in varies})
        try:
            result = deploy_wing(config.wing, temps, rtol=config.rtol, stop_time=config.stop_time)
        except WingUnsupported as exc:  # a law the solver cannot take at a temperature
            errors.append((index, str(exc)))
            rows.extend(
                {**head, "temperature_C": t, "method": "wing", "error": str(exc)} for t in temps
            )
            continue
        for row in result.summary_rows():
            rows.append(
                {**head, "temperature_C": row.pop("temperature_C"), "method": "wing", **row}
            )
    return SweepResult(rows, list(varies), title, ("wing",), errors, config_sha256)
