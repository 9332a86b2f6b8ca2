"""Damper and gearbox catalogues, read from TOML or CSV (format in docs/sizing.md).

A catalogue lists high-speed dampers (paper section 2) and gearboxes (section 3) with
the source of every entry. Each entry is validated on its own; every problem is reported
on one line that names the entry (kind, position, name) and the field.

Entries whose ``source`` says "illustrative" are invented for demonstration, never vendor
data; every output repeats that label next to them.
"""

from __future__ import annotations

import csv
import io
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Any

from pydantic import AfterValidator, BaseModel, Field, ValidationError, model_validator

from ecdsim._types import FloatArray
from ecdsim.config.errors import ConfigError
from ecdsim.config.fields import (
    NonNegativeAngle,
    NonNegativeDamping,
    NonNegativeNumber,
    NonNegativeTorque,
    PositiveNumber,
    PositiveTorque,
)
from ecdsim.config.loader import parse_toml, read_config_text
from ecdsim.config.schema import DamperSpec
from ecdsim.config.sizing_schema import (
    Efficiency,
    KnownMass,
    PositiveLength,
)
from ecdsim.config.units import Kind
from ecdsim.model import Gearbox, HighSpeedDamper

ILLUSTRATIVE = "illustrative, not vendor data"


def _source_text(value: str) -> str:
    text = value.strip()
    if not text:
        raise ValueError("source must say where the data come from (or 'illustrative, ...')")
    return text


SourceText = Annotated[str, AfterValidator(_source_text)]


class DamperEntrySpec(DamperSpec):
    """One ``[[damper]]`` entry: a ``[damper]`` config section plus catalogue data.

    ``rotor_inertia`` comes from ``[damper]`` (0 = not given). Keys of ``[damper]`` that
    only the full dynamics use are accepted and ignored by the quasi-static sizing.
    """

    name: str = Field(min_length=1)
    source: SourceText
    note: str = ""
    max_torque: PositiveTorque | None = None
    mass: KnownMass | None = None
    mass_includes_gearbox: str | None = Field(default=None, min_length=1)
    length: PositiveLength | None = None
    diameter: PositiveLength | None = None

    @model_validator(mode="after")
    def _assembly_mass(self) -> DamperEntrySpec:
        if self.mass_includes_gearbox is not None and self.mass is None:
            raise ValueError(
                "mass_includes_gearbox needs mass (the mass of this damper with that gearbox)"
            )
        return self


class GearboxEntrySpec(BaseModel):
    """One ``[[gearbox]]`` entry: the ratios on offer and the gearbox's data."""

    model_config = DamperSpec.model_config

    name: str = Field(min_length=1)
    source: SourceText
    note: str = ""
    ratios: list[PositiveNumber] = Field(min_length=1)
    damping_fraction: NonNegativeNumber | None = None
    damping_rate: NonNegativeDamping | None = None
    coulomb_friction: NonNegativeTorque
    max_output_torque: PositiveTorque | None = None
    efficiency: Efficiency | None = None
    lost_motion: NonNegativeAngle = 0.0
    mass: KnownMass | None = None

    @model_validator(mode="after")
    def _one_damping(self) -> GearboxEntrySpec:
        if (self.damping_fraction is None) == (self.damping_rate is None):
            raise ValueError(
                "give exactly one of damping_fraction (BG/BD, e.g. 0.26) and damping_rate "
                "(BG in N*m*s/rad)"
            )
        return self


@dataclass(frozen=True)
class DamperEntry:
    """A catalogue high-speed damper, SI units.

    Attributes
    ----------
    name : catalogue name
    source : where the data come from
    note : free remark (e.g. what a mass includes)
    damper : the model object (BD, temperature law, FD, FL_T, linear-range limits)
    rotor_inertia : rotor inertia at the damper shaft [kg*m^2], None if not given
    max_torque : largest allowed torque at the damper shaft [N*m], None if not given
    mass : [kg], None if not given; with ``mass_includes_gearbox``, the assembly's mass
    mass_includes_gearbox : name of the gearbox whose mass ``mass`` includes (an
        assembly mass, e.g. the paper's Cc-16), else None
    length : [m], None if not given
    diameter : [m], None if not given
    """

    name: str
    source: str
    note: str
    damper: HighSpeedDamper
    rotor_inertia: float | None
    max_torque: float | None
    mass: float | None
    mass_includes_gearbox: str | None
    length: float | None
    diameter: float | None

    @property
    def illustrative(self) -> bool:
        """True for invented demonstration data (source says "illustrative")."""
        return "illustrative" in self.source.lower()


@dataclass(frozen=True)
class GearboxEntry:
    """A catalogue gearbox, SI units; BG and FG are referred to the high-speed shaft.

    Attributes
    ----------
    name : catalogue name
    source : where the data come from
    note : free remark
    ratios : available gear ratios N [-]
    damping_fraction : BG / BD [-], or None
    damping_rate : BG [N*m*s/rad], or None
    coulomb_friction : FG [N*m]
    max_output_torque : largest allowed torque at the slow (ECD input) shaft [N*m]
    efficiency : catalogue efficiency [-] (reported; the paper models losses as BG, FG)
    lost_motion : backlash at the slow shaft [rad]
    mass : [kg], None if not given
    """

    name: str
    source: str
    note: str
    ratios: tuple[float, ...]
    damping_fraction: float | None
    damping_rate: float | None
    coulomb_friction: float
    max_output_torque: float | None
    efficiency: float | None
    lost_motion: float
    mass: float | None

    @property
    def illustrative(self) -> bool:
        """True for invented demonstration data (source says "illustrative")."""
        return "illustrative" in self.source.lower()

    def gearbox(self, ratio: float | FloatArray) -> Gearbox:
        """The model gearbox at ratio(s) N (BG and FG as catalogued, whatever the ratio)."""
        return Gearbox(
            ratio=ratio,
            coulomb_friction=self.coulomb_friction,
            damping_rate=self.damping_rate,
            damping_fraction=self.damping_fraction,
            lost_motion=self.lost_motion,
        )


@dataclass(frozen=True)
class Catalogue:
    """Dampers and gearboxes from one file.

    Attributes
    ----------
    dampers : the high-speed dampers
    gearboxes : the gearboxes
    source : the file it was read from
    """

    dampers: tuple[DamperEntry, ...]
    gearboxes: tuple[GearboxEntry, ...]
    source: str

    def damper(self, name: str) -> DamperEntry:
        """The damper called ``name``; KeyError naming the known ones if absent."""
        for entry in self.dampers:
            if entry.name == name:
                return entry
        raise KeyError(f"no damper {name!r}; known: {[d.name for d in self.dampers]}")

    def gearbox(self, name: str) -> GearboxEntry:
        """The gearbox called ``name``; KeyError naming the known ones if absent."""
        for entry in self.gearboxes:
            if entry.name == name:
                return entry
        raise KeyError(f"no gearbox {name!r}; known: {[g.name for g in self.gearboxes]}")


def _damper_entry(spec: DamperEntrySpec) -> DamperEntry:
    return DamperEntry(
        name=spec.name,
        source=spec.source,
        note=spec.note,
        damper=spec.to_model(),
        rotor_inertia=spec.rotor_inertia if spec.rotor_inertia > 0.0 else None,
        max_torque=spec.max_torque,
        mass=spec.mass,
        mass_includes_gearbox=spec.mass_includes_gearbox,
        length=spec.length,
        diameter=spec.diameter,
    )


def _gearbox_entry(spec: GearboxEntrySpec) -> GearboxEntry:
    return GearboxEntry(
        name=spec.name,
        source=spec.source,
        note=spec.note,
        ratios=tuple(float(r) for r in spec.ratios),
        damping_fraction=spec.damping_fraction,
        damping_rate=spec.damping_rate,
        coulomb_friction=spec.coulomb_friction,
        max_output_torque=spec.max_output_torque,
        efficiency=spec.efficiency,
        lost_motion=spec.lost_motion,
        mass=spec.mass,
    )


_SPECS: dict[str, type[BaseModel]] = {"damper": DamperEntrySpec, "gearbox": GearboxEntrySpec}


def _expected(model: type[BaseModel], name: str) -> str | None:
    info = model.model_fields.get(name)
    if info is None:
        return None
    kinds = [m for m in info.metadata if isinstance(m, Kind)]
    return kinds[0].expected if kinds else None


def _entry_messages(kind: str, label: str, exc: ValidationError) -> list[str]:
    model = _SPECS[kind]
    lines = []
    for error in exc.errors():
        loc = [str(p) for p in error["loc"]]
        field = ".".join(loc) if loc else "(entry)"
        message = str(error["msg"]).removeprefix("Value error, ")
        if error["type"] == "missing":
            expected = _expected(model, loc[0]) if loc else None
            message = f"missing; {expected}" if expected else "missing"
        elif error["type"] == "extra_forbidden":
            message = f"unknown field (known: {', '.join(model.model_fields)})"
        elif error["type"] not in {"quantity", "value_error"} and "input" in error:
            message = f"{error['input']!r}: {message}"
        lines.append(f"{label}: {field}: {message}")
    return lines


def _label(kind: str, position: str, raw: object) -> str:
    name = raw.get("name") if isinstance(raw, dict) else None
    return f"{kind} {position} {name!r}" if isinstance(name, str) else f"{kind} {position}"


def build_catalogue(entries: list[tuple[str, str, dict[str, Any]]], source: str) -> Catalogue:
    """Validate (kind, position label, raw fields) entries into a :class:`Catalogue`.

    Raises :class:`ConfigError` listing every problem of every entry, each line naming
    the entry and the field.
    """
    problems: list[str] = []
    dampers: list[DamperEntry] = []
    gearboxes: list[GearboxEntry] = []
    seen: dict[tuple[str, str], str] = {}
    for kind, position, raw in entries:
        label = _label(kind, position, raw)
        if kind not in _SPECS:
            problems.append(f"{label}: kind must be 'damper' or 'gearbox', got {kind!r}")
            continue
        try:
            spec = _SPECS[kind].model_validate(raw)
        except ValidationError as exc:
            problems.extend(_entry_messages(kind, label, exc))
            continue
        name = str(getattr(spec, "name", ""))
        if (kind, name) in seen:
            problems.append(f"{label}: name repeats {seen[(kind, name)]}; names must be unique")
            continue
        seen[(kind, name)] = label
        if isinstance(spec, DamperEntrySpec):
            dampers.append(_damper_entry(spec))
        elif isinstance(spec, GearboxEntrySpec):
            gearboxes.append(_gearbox_entry(spec))
    if not problems and not dampers:
        problems.append("the catalogue lists no damper ([[damper]] entries)")
    if not problems and not gearboxes:
        problems.append("the catalogue lists no gearbox ([[gearbox]] entries)")
    names = {g.name for g in gearboxes}
    for damper in dampers:
        if damper.mass_includes_gearbox is not None and damper.mass_includes_gearbox not in names:
            problems.append(
                f"damper {damper.name!r}: mass_includes_gearbox: no gearbox "
                f"{damper.mass_includes_gearbox!r} in the catalogue (known: {sorted(names)})"
            )
    if problems:
        raise ConfigError(problems, source)
    return Catalogue(tuple(dampers), tuple(gearboxes), source)


def parse_toml_catalogue(text: str, source: str = "<string>") -> Catalogue:
    """A catalogue from TOML text: ``[[damper]]`` and ``[[gearbox]]`` arrays of tables."""
    raw = parse_toml(text, source)  # invalid TOML, deep nesting, a 4,300-digit integer
    unknown = sorted(set(raw) - {"title", "damper", "gearbox"})
    if unknown:
        raise ConfigError(
            [f"{key}: unknown key (known: title, damper, gearbox)" for key in unknown], source
        )
    entries: list[tuple[str, str, dict[str, Any]]] = []
    problems: list[str] = []
    for kind in ("damper", "gearbox"):
        tables = raw.get(kind, [])
        if not isinstance(tables, list):
            problems.append(f"{kind}: expected an array of tables ([[{kind}]] entries)")
            continue
        for i, table in enumerate(tables, start=1):
            if not isinstance(table, dict):
                problems.append(f"{kind} #{i}: expected a table")
                continue
            entries.append((kind, f"#{i}", table))
    if problems:
        raise ConfigError(problems, source)
    return build_catalogue(entries, source)


# CSV columns that hold the lubrication law's two numbers (a TOML entry nests them).
_LUBRICATION_COLUMNS = {"lubrication_slope": "slope", "lubrication_at_0C": "at_0C"}


def _header(text: str) -> tuple[str, str]:
    """``"damping_rate [N*m*s/rad]"`` -> ("damping_rate", "N*m*s/rad")."""
    head = text.strip()
    if head.endswith("]") and "[" in head:
        name, _, unit = head[:-1].partition("[")
        return name.strip(), unit.strip()
    return head, ""


def _is_number(cell: str) -> bool:
    try:
        float(cell)
    except ValueError:
        return False
    return True


def _cell(cell: str, unit: str) -> str:
    """A CSV cell as a quantity string: a bare number takes the column's unit."""
    return f"{cell} {unit}" if unit and _is_number(cell) else cell


def parse_csv_catalogue(text: str, source: str = "<string>") -> Catalogue:
    """A catalogue from CSV text: one row per entry, a ``kind`` column (damper|gearbox).

    A header may carry a unit in brackets (``mass [kg]``) that applies to bare numbers in
    its column; a cell may also hold a quantity with its own unit (``185 g``). Empty cells
    are "not given". ``ratios`` holds ratios separated by ``;``. The lubrication law is
    given by ``lubrication_slope`` and ``lubrication_at_0C`` (linear law only).
    """
    reader = csv.reader(io.StringIO(text))
    try:
        rows = [row for row in reader if any(c.strip() for c in row)]
    except csv.Error as exc:  # a cell over the csv module's limit (131,072 characters)
        raise ConfigError([f"row {reader.line_num}: not valid CSV ({exc})"], source) from None
    if not rows:
        raise ConfigError(["the CSV catalogue is empty"], source)
    headers = [_header(h) for h in rows[0]]
    names = [name for name, _ in headers]
    problems = []
    for required in ("kind", "name"):
        if required not in names:
            problems.append(f"header: missing the {required!r} column")
    repeated = sorted({n for n in names if names.count(n) > 1})
    if repeated:
        problems.append(f"header: repeated column(s) {repeated}")
    if problems:
        raise ConfigError(problems, source)
    entries: list[tuple[str, str, dict[str, Any]]] = []
    for line, row in enumerate(rows[1:], start=2):
        if len(row) > len(headers):
            problems.append(f"row {line}: {len(row)} cells but {len(headers)} columns")
            continue
        fields: dict[str, Any] = {}
        kind = ""
        for (name, unit), cell in zip(headers, row, strict=False):
            value = cell.strip()
            if not value:
                continue
            if name == "kind":
                kind = value
            elif name == "ratios":
                fields["ratios"] = [r.strip() for r in value.split(";") if r.strip()]
            elif name in _LUBRICATION_COLUMNS:
                law = fields.setdefault("lubrication_friction", {})
                law[_LUBRICATION_COLUMNS[name]] = _cell(value, unit)
            elif name in {"name", "source", "note", "mass_includes_gearbox"}:
                fields[name] = value
            else:
                fields[name] = _cell(value, unit)
        entries.append((kind, f"(row {line})", fields))
    if problems:
        raise ConfigError(problems, source)
    return build_catalogue(entries, source)


def load_catalogue(path: str | Path) -> Catalogue:
    """Read a catalogue file; the suffix chooses the format (.toml or .csv)."""
    file = Path(path)
    text = read_config_text(file, "catalogue file", encoding="utf-8-sig")
    suffix = file.suffix.lower()
    if suffix == ".toml":
        return parse_toml_catalogue(text, str(file))
    if suffix == ".csv":
        return parse_csv_catalogue(text, str(file))
    raise ConfigError([f"unknown catalogue format {suffix!r}; expected .toml or .csv"], str(file))
