"""Write fitted parameters as a configuration file (TOML) that ``ecdsim deploy`` reads.

The fits give BECD(T) and FECD(T) at the ECD's input shaft, not the high-speed damper
and gearbox separately. The file therefore describes a 1:1 "gearbox" with no losses of
its own and puts everything in the damper (Eq. 1-4 with N = 1, BG = 0, FD = FG = 0)::

    [damper]  damping_rate = B_ref              (BECD at reference_temperature)
              damping_temperature_coefficient = c   (the fitted linear law)
              coulomb_friction = 0
              lubrication_friction = { slope, at_0C }   (the fitted FECD line)
    [gearbox] ratio = 1, damping_fraction = 0, coulomb_friction = 0

so that ``BECD(T) = B_ref * (1 + c (T - T_ref))`` and ``FECD(T) = slope * T + at_0C``
exactly. The configuration format holds only the paper's linear damping law; where the
resistivity law fits better the file says so in a comment. With one temperature no law
can be fitted: c = 0 and the FECD slope is 0 (a warning says so).

With a configuration from the user (``--config``) the file written is that file as the
user wrote it (comments, order, title, units, ``[load]``, ``[analysis]``, every other
section; tomlkit), with only the fitted parts replaced: ``[damper]`` and ``[gearbox]``
for a damper fit (:func:`fitted_config_text`), ``[load] start_torque`` and ``end_torque``
for a spring fit (:func:`spring_config_text`). Without one, a clearly marked placeholder
load is written (constant torque equal to the largest bench torque over a 90 deg travel)
that must be edited before any deployment time means anything. Fitted numbers are
written to the digits their 95 % intervals support (:func:`significant`), with no float
noise. Every file is validated with the configuration reader before it is written, and
written atomically.
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from types import UnionType
from typing import TYPE_CHECKING, Annotated, Any, Union, get_args, get_origin

import numpy as np
from pydantic import BaseModel

from ecdsim._types import ArrayLike
from ecdsim._version import __version__
from ecdsim.atomic import write_text
from ecdsim.characterize.findings import FitWarning
from ecdsim.characterize.stats import Estimate
from ecdsim.characterize.templaws import TemperatureLaws
from ecdsim.config import ConfigError
from ecdsim.config.units import Kind

if TYPE_CHECKING:
    # The schema (pydantic models of every section) is built only when a file is
    # written: a fit that prints its table does not pay for it.
    from ecdsim.config.schema import LoadSpec

PLACEHOLDER_TRAVEL = math.pi / 2.0  # rad


class ExportError(ValueError):
    """The fit cannot be written as a configuration; the message says why."""


def toml_string(text: str) -> str:
    r"""A TOML basic string (double-quoted, escaped).

    >>> toml_string('say "hi"')
    '"say \\"hi\\""'
    """
    out = []
    for char in text:
        code = ord(char)
        if char == '"':
            out.append('\\"')
        elif char == "\\":
            out.append("\\\\")
        elif char == "\t":
            out.append("\\t")
        elif code < 0x20 or code == 0x7F:
            out.append(f"\\u{code:04X}")
        else:
            out.append(char)
    return '"' + "".join(out) + '"'


def quantity(value: float, unit: str) -> str:
    """A quantity as a TOML string, the number written exactly (``repr``) with its unit.

    For a value copied from a validated configuration, which must read back bit for bit;
    a fitted value is written by :func:`fitted_quantity`.
    """
    number = repr(float(value))
    return toml_string(f"{number} {unit}" if unit else number)


def fitted_quantity(value: float, unit: str, half_width: float | None = None) -> str:
    """A fitted quantity as a TOML string, to its :func:`significant` digits, with its unit.

    ``half_width`` is the half-width of the value's 95 % interval (None: none).
    """
    number = significant(float(value), half_width)
    return toml_string(f"{number} {unit}" if unit else number)


MIN_DIGITS = 6  # significant digits of a fitted number at least (the header's precision)


def significant(value: float, half_width: float | None = None) -> str:
    """``value`` to the digits its 95 % interval supports, at least :data:`MIN_DIGITS`.

    Enough digits (15 at most) that the rounding stays below 1 % of the interval's
    half-width, so that the written number is the fit's to well within its uncertainty;
    6 digits at least.
    Without a (positive, finite) half-width: 15 significant digits, trailing zeros
    dropped, which removes float noise (-39.99999999999997 reads -40) and keeps the
    value to 5e-16 relative.

    >>> significant(24.058730239258235, 0.1055)
    '24.0587'
    >>> significant(-0.003998517629040172, 5.27e-05)
    '-0.00399852'
    >>> significant(-39.99999999999997), significant(25.0), significant(1.3e-4)
    ('-40', '25', '0.00013')
    """
    if not math.isfinite(value) or value == 0.0:
        return repr(value) if value != 0.0 else "0"
    if half_width is not None and math.isfinite(half_width) and half_width > 0.0:
        needed = math.floor(math.log10(abs(value))) - math.floor(math.log10(half_width / 100))
        digits = min(max(MIN_DIGITS, needed + 1), 15)  # beyond 15: float noise
        return f"{value:.{digits}g}"
    return f"{value:.15g}"  # 15 digits: the float noise of the 16th and 17th is gone


@dataclass(frozen=True)
class Entry:
    """One ``key = value`` line; ``value`` is TOML text, ``comment`` optional."""

    key: str
    value: str
    comment: str | None = None


def render_toml(header: Sequence[str], sections: Sequence[tuple[str, Sequence[Entry]]]) -> str:
    """TOML text: ``# header`` lines, then each ``[section]`` with its entries."""
    lines = [f"# {line}" if line else "#" for line in header]
    for name, entries in sections:
        if name.startswith("#"):
            lines += ["", name]
            continue
        lines += ["", f"[{name}]"] if name else [""]
        for entry in entries:
            text = f"{entry.key} = {entry.value}"
            lines.append(f"{text}   # {entry.comment}" if entry.comment else text)
    return "\n".join(lines).lstrip("\n") + "\n"


@dataclass(frozen=True)
class FittedEcd:
    """BECD(T) and FECD(T) in the form the configuration can hold.

    Attributes
    ----------
    damping_rate : B_ref, BECD at the reference temperature [N*m*s/rad]
    reference_temperature : T_ref [degC]
    temperature_coefficient : c of the linear law [1/K]
    friction_slope : FECD change per kelvin [N*m/K]
    friction_at_0c : FECD at 0 degC [N*m]
    temperatures : the test temperatures (the file's analysis temperatures) [degC]
    comments : lines about the fit (intervals, law choice) for the file's header
    warnings : findings to show the user
    half_widths : half-widths of the 95 % intervals of damping_rate,
        temperature_coefficient, friction_slope and friction_at_0c (None: no interval),
        which set the digits written
    """

    damping_rate: float
    reference_temperature: float
    temperature_coefficient: float
    friction_slope: float
    friction_at_0c: float
    temperatures: tuple[float, ...]
    comments: tuple[str, ...]
    warnings: tuple[FitWarning, ...]
    half_widths: tuple[float | None, float | None, float | None, float | None] = (
        None,
        None,
        None,
        None,
    )

    def damping_at(self, temperature: float) -> float:
        """BECD(T) [N*m*s/rad] as the file states it."""
        dt = temperature - self.reference_temperature
        return self.damping_rate * (1.0 + self.temperature_coefficient * dt)

    def friction_at(self, temperature: float) -> float:
        """FECD(T) [N*m] as the file states it."""
        return self.friction_slope * temperature + self.friction_at_0c


def _half_width(estimate: Estimate) -> float | None:
    """Half the width of an estimate's 95 % interval, None without one."""
    if estimate.ci95 is None:
        return None
    low, high = estimate.ci95
    return (high - low) / 2.0


def _ci(estimate: Estimate, unit: str) -> str:
    if estimate.ci95 is None:
        return f"{estimate.value:.6g} {unit} (no interval)"
    low, high = estimate.ci95
    return f"{estimate.value:.6g} {unit}, 95 % CI [{low:.6g}, {high:.6g}]"


def fitted_ecd(
    temperatures: Sequence[float],
    damping: Sequence[Estimate],
    friction: Sequence[Estimate],
    laws: TemperatureLaws | None,
) -> FittedEcd:
    """The configuration's form of the fit: the linear law and the FECD line.

    Parameters
    ----------
    temperatures : the fitted temperatures [degC]
    damping : BECD at each [N*m*s/rad]
    friction : FECD at each [N*m]
    laws : the laws over temperature (None with a single temperature)
    """
    temps = tuple(float(t) for t in temperatures)
    if not temps:
        raise ExportError("no temperature could be fitted: nothing to write")
    if laws is None:
        if len(temps) != 1:
            raise ExportError("several temperatures but no law over temperature")
        b, f = damping[0], friction[0]
        result = FittedEcd(
            damping_rate=b.value,
            reference_temperature=temps[0],
            temperature_coefficient=0.0,
            friction_slope=0.0,
            friction_at_0c=f.value,
            temperatures=temps,
            comments=(
                f"one temperature ({temps[0]:g} degC): BECD {_ci(b, 'N*m*s/rad')}",
                f"FECD {_ci(f, 'N*m')}",
                "no temperature law could be fitted: coefficient and friction slope are 0",
            ),
            half_widths=(_half_width(b), None, None, _half_width(f)),
            warnings=(
                FitWarning(
                    "single_temperature_export",
                    f"one temperature only: the file holds BECD and FECD at {temps[0]:g} degC "
                    "with no temperature dependence; edit "
                    "damper.damping_temperature_coefficient if you know it",
                ),
            ),
        )
    else:
        linear = laws.damping.get("linear")
        if linear is None:
            why = laws.damping_failures.get("linear", "not fitted")
            raise ExportError(f"the linear damping law could not be fitted ({why})")
        if laws.friction is None:
            raise ExportError(f"the friction line could not be fitted ({laws.friction_failure})")
        b_ref, c = linear.parameters
        at_0c, slope = laws.friction.parameters
        comments = [
            f"BECD(T) = B_ref * (1 + c * (T - {laws.reference_temperature:g} degC)), fitted "
            f"over {', '.join(f'{t:g}' for t in temps)} degC:",
            f"  B_ref = {_ci(b_ref, 'N*m*s/rad')}",
            f"  c = {_ci(c, '1/K')}",
            "FECD(T) = slope * T + at_0C:",
            f"  slope = {_ci(slope, 'N*m/K')}",
            f"  at_0C = {_ci(at_0c, 'N*m')}",
            f"law comparison: {laws.comparison.statement}",
        ]
        warnings: list[FitWarning] = []
        if laws.comparison.better == "resistivity":
            comments.append(
                "the resistivity law fits better, but this file format holds the linear law "
                "only: BECD is written with the linear law"
            )
            warnings.append(
                FitWarning(
                    "law_not_exported",
                    "the resistivity law fits better, but the configuration holds only the "
                    "paper's linear law; the parameter file uses the linear law",
                )
            )
        result = FittedEcd(
            damping_rate=b_ref.value,
            reference_temperature=laws.reference_temperature,
            temperature_coefficient=c.value,
            friction_slope=slope.value,
            friction_at_0c=at_0c.value,
            temperatures=temps,
            comments=tuple(comments),
            warnings=tuple(warnings),
            half_widths=(
                _half_width(b_ref),
                _half_width(c),
                _half_width(slope),
                _half_width(at_0c),
            ),
        )
    if not result.damping_rate > 0.0:
        raise ExportError(
            f"the damping rate at the reference temperature is {result.damping_rate:.4g} "
            "N*m*s/rad, not positive"
        )
    for t in temps:
        if not result.damping_at(t) > 0.0:
            raise ExportError(f"the linear law gives BECD <= 0 at {t:g} degC")
    return result


def ecd_sections(ecd: FittedEcd) -> list[tuple[str, list[Entry]]]:
    """The ``[damper]`` and ``[gearbox]`` sections of a fitted ECD (N = 1, no losses)."""
    hw_b, hw_c, hw_slope, hw_f = ecd.half_widths
    damper = [
        Entry(
            "damping_rate",
            fitted_quantity(ecd.damping_rate, "N*m*s/rad", hw_b),
            "BECD at reference_temperature, at the input shaft",
        ),
        Entry("reference_temperature", fitted_quantity(ecd.reference_temperature, "degC")),
        Entry(
            "damping_temperature_coefficient",
            fitted_quantity(ecd.temperature_coefficient, "/ K", hw_c),
            "fitted linear law",
        ),
        Entry("coulomb_friction", fitted_quantity(0.0, "N*m"), "all friction is in the line below"),
        Entry(
            "lubrication_friction",
            "{ slope = "
            + fitted_quantity(ecd.friction_slope, "N*m/K", hw_slope)
            + ", at_0C = "
            + fitted_quantity(ecd.friction_at_0c, "N*m", hw_f)
            + " }",
            "FECD(T) = slope * T + at_0C",
        ),
    ]
    gearbox = [
        Entry("ratio", "1", "BECD and FECD are already at the input shaft"),
        Entry("damping_fraction", "0.0"),
        Entry("coulomb_friction", fitted_quantity(0.0, "N*m")),
    ]
    return [("damper", damper), ("gearbox", gearbox)]


def _kind(annotation: Any, metadata: Sequence[Any] = ()) -> Kind | None:
    """The :class:`Kind` a (possibly Optional, Annotated) schema annotation carries."""
    for item in (*metadata, *getattr(annotation, "__metadata__", ())):
        if isinstance(item, Kind):
            return item
    for arg in get_args(annotation):
        if arg is not type(None) and get_origin(annotation) in (Union, UnionType):
            found = _kind(arg)
            if found is not None:
                return found
    return None


def _strip(annotation: Any) -> Any:
    """The annotation without its Annotated and Optional wrappers."""
    while True:
        origin = get_origin(annotation)
        if origin is Annotated:
            annotation = get_args(annotation)[0]
            continue
        if origin in (Union, UnionType):
            rest = [a for a in get_args(annotation) if a is not type(None)]
            if len(rest) == 1:
                annotation = rest[0]
                continue
        return annotation


def _key(name: str) -> str:
    return name if re.fullmatch(r"[A-Za-z0-9_-]+", name) else toml_string(name)


def toml_value(value: Any, annotation: Any = None, metadata: Sequence[Any] = ()) -> str:
    """A validated configuration value as TOML text, quantities with their SI unit.

    The schema's annotation says which :class:`~ecdsim.config.units.Kind` a number is,
    so that it is written back as a quantity string ("3.73 N*m") the reader accepts.
    """
    if isinstance(value, BaseModel):
        return "{ " + ", ".join(f"{e.key} = {e.value}" for e in model_entries(value)) + " }"
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return toml_string(value)
    inner = _strip(annotation)
    args = get_args(inner)
    if isinstance(value, list | tuple):
        if get_origin(inner) is tuple and args and args[-1] is not Ellipsis:
            items = [toml_value(v, a) for v, a in zip(value, args, strict=False)]
        else:
            element = args[0] if args else None
            items = [toml_value(v, element) for v in value]
        return "[" + ", ".join(items) + "]"
    if isinstance(value, dict):
        element = args[1] if len(args) == 2 else None
        pairs = (f"{_key(str(k))} = {toml_value(v, element)}" for k, v in value.items())
        return "{ " + ", ".join(pairs) + " }"
    if isinstance(value, int | float):
        kind = _kind(annotation, metadata)
        if kind is not None and kind.unit:
            return quantity(float(value), kind.unit)
        return repr(float(value))
    raise ExportError(f"cannot write a value of type {type(value).__name__} as TOML")


def model_entries(spec: BaseModel, **replace_values: Any) -> list[Entry]:
    """``key = value`` entries of every field the configuration set (defaults stay out).

    ``replace_values`` overrides values (and writes them even if they were not set).
    """
    entries = []
    fields = type(spec).model_fields
    for name, info in fields.items():
        if name not in spec.model_fields_set and name not in replace_values:
            continue
        value = replace_values.get(name, getattr(spec, name))
        if value is None:
            continue
        entries.append(Entry(name, toml_value(value, info.annotation, info.metadata)))
    return entries


def placeholder_load(torque: float) -> list[Entry]:
    """A marked placeholder ``[load]``: constant ``torque`` [N*m] over a 90 deg travel.

    ``placeholder = true`` makes every command flag its results (docs/config.md); the
    torque is written to 6 significant digits and the travel as "90 deg", without float
    noise (``"1.5707963267948966 rad"``): a stand-in needs no more digits.
    """
    note = "PLACEHOLDER: edit"
    return [
        Entry("placeholder", "true", "delete this line once the load below is your mechanism's"),
        Entry("start_torque", toml_string(f"{torque:.6g} N*m"), note),
        Entry("end_torque", toml_string(f"{torque:.6g} N*m"), note),
        Entry("travel", toml_string(f"{math.degrees(PLACEHOLDER_TRAVEL):g} deg"), note),
    ]


PLACEHOLDER_NOTICE = (
    "# PLACEHOLDER LOAD: no --config was given, so this [load] is a constant torque equal\n"
    "# to the largest bench torque over a 90 deg travel. Replace it with your mechanism's\n"
    "# spring and travel, then delete `placeholder = true`: until then every command flags\n"
    "# its results as those of a placeholder load."
)


def _analysis(temperatures: Sequence[float]) -> list[Entry]:
    temps = ", ".join(fitted_quantity(t, "degC") for t in temperatures)
    return [Entry("temperatures", f"[{temps}]", "the test temperatures")]


def fitted_parameter_text(
    ecd: FittedEcd,
    load: LoadSpec | None,
    placeholder_torque: float,
    title: str,
    provenance: Sequence[str],
) -> str:
    """The parameter file of a damper fit (drop test or trace).

    Parameters
    ----------
    ecd : the fitted BECD(T), FECD(T)
    load : the load to copy; None for the placeholder load
    placeholder_torque : torque of the placeholder load [N*m]
    title : the file's title
    provenance : header comment lines (tool, version, source file and hash)
    """
    header = [*provenance, "", *ecd.comments]
    sections: list[tuple[str, Sequence[Entry]]] = [("", [Entry("title", toml_string(title))])]
    sections += ecd_sections(ecd)
    if load is None:
        sections.append((PLACEHOLDER_NOTICE, []))
        sections.append(("load", placeholder_load(placeholder_torque)))
    else:
        sections.append(("load", model_entries(load)))
    sections.append(("analysis", _analysis(ecd.temperatures)))
    return render_toml(header, sections)


def _table(entries: Sequence[Entry]) -> Any:
    """A tomlkit table of ``entries`` (values are TOML text), with their comments."""
    import tomlkit

    table = tomlkit.table()
    for entry in entries:
        table.add(entry.key, tomlkit.parse(f"v = {entry.value}\n")["v"])
        if entry.comment:
            table[entry.key].comment(entry.comment)
    return table


def _replace_table(document: Any, name: str, entries: Sequence[Entry]) -> None:
    """Put ``entries`` in the place of the table ``name`` (its keys, subtables, comments).

    The table keeps its place and the blank line after it; a new one goes at the end.
    """
    from tomlkit.items import Comment, Table

    old = document.get(name)
    if not isinstance(old, Table):
        document[name] = _table(entries)
        return
    for key in list(old.keys()):
        del old[key]
    body = old.value.body  # only unkeyed items (comments, blank lines) are left
    body[:] = [(key, item) for key, item in body if not isinstance(item, Comment)]
    new = _table(entries)
    for key in new:
        old.add(key, new[key])


def _with_header(header: Sequence[str], body: str) -> str:
    lines = [f"# {line}" if line else "#" for line in header]
    return "\n".join(lines) + "\n\n" + body.lstrip("\n")


def _parse_user(text: str) -> Any:
    """The user's configuration as a tomlkit document; ExportError if tomlkit cannot."""
    import tomlkit
    from tomlkit.exceptions import TOMLKitError

    try:
        return tomlkit.parse(text)
    except TOMLKitError as exc:
        raise ExportError(f"cannot keep the --config file's text ({exc})") from None


def keys_not_carried(user_text: str, ecd: FittedEcd) -> list[str]:
    """The user's ``[damper]`` and ``[gearbox]`` keys that the fitted file does not hold.

    :func:`fitted_config_text` replaces both tables with the fitted ECD at its input shaft
    (N = 1); keys of the high-speed damper or the gearbox that the fit does not give (a
    roll-off or heating law, inertias, backlash, an efficiency, ...) have no meaning at
    that 1:1 shaft and are not carried over. They are named, dotted (``damper.rolloff``),
    in file order, so that the user is told rather than finding them gone. A file tomlkit
    cannot read names none (``fitted_config_text`` reports it).
    """
    try:
        document = _parse_user(user_text)
    except ExportError:
        return []
    out: list[str] = []
    for name, entries in ecd_sections(ecd):
        kept = {entry.key for entry in entries}
        table = document.get(name)
        if isinstance(table, dict):  # tomlkit's Table is a dict
            out.extend(f"{name}.{key}" for key in table if key not in kept)
    return out


def fitted_config_text(
    user_text: str, ecd: FittedEcd, provenance: Sequence[str], config_name: str
) -> str:
    """The user's configuration file with the fitted ECD in place of its own.

    The file the user gave (``--config``) is kept as written, its comments, order, title,
    units, ``[load]``, ``[analysis]`` and every other section (tomlkit); only ``[damper]``
    and ``[gearbox]`` are replaced by the fitted ECD at the input shaft (N = 1, see the
    module docstring). A file with no ``[analysis]`` gets the test temperatures. The
    header names the tool, the data and the fit.
    """
    import tomlkit

    document = _parse_user(user_text)
    dropped = keys_not_carried(user_text, ecd)
    sections = dict(ecd_sections(ecd))
    for name in ("damper", "gearbox"):
        _replace_table(document, name, sections[name])
    if "analysis" not in document:
        document["analysis"] = _table(_analysis(ecd.temperatures))
    header = [
        *provenance,
        f"from {config_name}: every section as written there, except [damper] and [gearbox],",
        "which hold the fitted ECD at its input shaft (1:1, docs/characterize.md)",
        *(
            [
                "not carried over from [damper] and [gearbox] (the fitted 1:1 ECD does not",
                "separate the damper's shaft from the gearbox; enter them again referred to",
                f"the input shaft where they apply): {', '.join(dropped)}",
            ]
            if dropped
            else []
        ),
        "",
        *ecd.comments,
    ]
    return _with_header(header, tomlkit.dumps(document))


def spring_config_text(
    user_text: str,
    start_torque: Estimate,
    end_torque: Estimate,
    provenance: Sequence[str],
    config_name: str,
) -> str:
    """The user's configuration file with the fitted spring torques (tomlkit).

    Only ``[load] start_torque`` and ``end_torque`` change, written to their significant
    digits in N*m; comments, order, units and every other key stay as the user wrote them.
    """
    import tomlkit

    document = _parse_user(user_text)
    load = document.get("load")
    if load is None:
        raise ExportError("the --config file has no [load] to write the spring torques into")
    for key, estimate in (("start_torque", start_torque), ("end_torque", end_torque)):
        text = fitted_quantity(estimate.value, "N*m", _half_width(estimate))
        item = tomlkit.parse(f"v = {text}\n")["v"]
        if key in load:
            old = load[key]
            comment = getattr(getattr(old, "trivia", None), "comment", "")
            load[key] = item
            if comment:
                load[key].comment(comment.lstrip("# "))
        else:
            load[key] = item
    header = [
        *provenance,
        "",
        "spring torques fitted to the traces (at the spring's reference temperature):",
        f"  start_torque = {_ci(start_torque, 'N*m')}",
        f"  end_torque = {_ci(end_torque, 'N*m')}",
        f"everything else as written in {config_name}",
    ]
    return _with_header(header, tomlkit.dumps(document))


def provenance(command: str, source: str, sha256: str) -> list[str]:
    """Header lines naming the tool, its version and the data file."""
    return [
        f"Written by ecdsim {__version__}: {command}",
        f"data: {Path(source).name} (sha256 {sha256})",
    ]


def write_parameter_file(path: str | Path, text: str) -> Path:
    """Validate ``text`` with the configuration reader, then write it atomically.

    Raises :class:`ExportError` if the configuration reader rejects it (which would be
    a bug: the text is built from validated values).
    """
    from ecdsim.config import parse_config

    try:
        parse_config(text, str(path))
    except ConfigError as exc:
        raise ExportError(f"the parameter file would not be valid: {exc}") from None
    return write_text(path, text)


def largest_torque(torques: ArrayLike) -> float:
    """The placeholder load's torque: the largest bench torque [N*m]."""
    return float(np.max(np.asarray(torques, dtype=float)))
