"""Read a TOML configuration into model objects, gathering every problem at once."""

from __future__ import annotations

import hashlib
import os
import re
import sys
import tomllib
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from pydantic import ValidationError

from ecdsim.config.errors import ConfigError
from ecdsim.config.units import MAX_QUOTED, quoted
from ecdsim.model import DeploymentSystem


@contextmanager
def _without_pydantic_plugins() -> Iterator[None]:
    """pydantic builds each model's validator when its class is defined, and on the first
    build looks for plugins (observability hooks registered as package entry points) by
    reading every installed distribution's metadata: about 10 ms of each command that
    reads a config. ecdsim's config models have no use for them, so the schema is built
    with plugins off, as typer builds its option adapters (PYDANTIC_DISABLE_PLUGINS is
    read at each build; the variable is restored at once, before any user code runs)."""
    previous = os.environ.get("PYDANTIC_DISABLE_PLUGINS")
    os.environ["PYDANTIC_DISABLE_PLUGINS"] = "1"
    try:
        yield
    finally:
        if previous is None:
            del os.environ["PYDANTIC_DISABLE_PLUGINS"]
        else:
            os.environ["PYDANTIC_DISABLE_PLUGINS"] = previous


with _without_pydantic_plugins():
    from ecdsim.config.schema import STUDY_SECTIONS, CoreConfigSpec

if TYPE_CHECKING:
    from ecdsim.config.full_schema import ConfigSpec


@dataclass(frozen=True)
class Config:
    """A validated configuration, in SI units.

    Attributes
    ----------
    system : the deployment system
    temperatures : analysis temperatures [degC]
    methods : solver names to run
    spec : the validated file content (for reports and round trips)
    source : where it came from (a path or "<string>")
    sha256 : hash of the file's bytes, for provenance
    """

    system: DeploymentSystem
    temperatures: tuple[float, ...]
    methods: tuple[str, ...]
    spec: ConfigSpec | CoreConfigSpec
    source: str
    sha256: str


def read_config_text(path: Path, what: str = "config file", encoding: str = "utf-8") -> str:
    """The text of an input file; :class:`ConfigError` if missing, unreadable or not UTF-8.

    ``what`` names the file in the messages ("config file", "catalogue file"); ``encoding``
    is "utf-8" or "utf-8-sig" (the latter drops a leading byte-order mark).
    """
    try:
        data = path.read_bytes()
    except FileNotFoundError:
        raise ConfigError([f"{what} not found: {path}"]) from None
    except OSError as exc:
        raise ConfigError([f"cannot read {what} {path}: {exc.strerror}"]) from None
    try:
        return data.decode(encoding)
    except UnicodeDecodeError:
        raise ConfigError(["the file is not UTF-8 text"], str(path)) from None


def load_config(path: str | Path) -> Config:
    """Read and validate a TOML file; :class:`ConfigError` lists every problem."""
    file = Path(path)
    return parse_config(read_config_text(file), str(file))


# No ecdsim config nests deeper than a few levels (a table of tables of lists of pairs);
# anything much deeper is a mistake or an attack, refused before it is walked.
MAX_NESTING = 32


TOO_DEEP = f"nested too deeply (at most {MAX_NESTING} levels of tables and lists)"

# A digit run (underscores allowed, as TOML writes 1_000) longer than Python converts.
_LONG_DIGITS = re.compile(r"[0-9][0-9_]*")
# A (bare or dotted) key followed by '=': the last one before a value names it.
_KEY_BEFORE_EQUALS = re.compile(r"([A-Za-z0-9_.\-]+)\s*=")


def parse_toml(text: str, source: str = "<string>") -> dict[str, Any]:
    """The TOML document ``text``; :class:`ConfigError` (one line) if it cannot be read.

    Every TOML reader of ecdsim's inputs goes through it, so that each refusal is a line
    naming the problem: invalid TOML (tomllib's message, with line and column), nesting
    beyond :data:`MAX_NESTING` (tomllib recurses and would exhaust the stack), and an
    integer longer than Python converts (``sys.get_int_max_str_digits()``, 4,300 digits
    by default, a guard against quadratic-time conversions; tomllib raises a bare
    ValueError that names no line).
    """
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError([f"not valid TOML: {exc}"], source) from None
    except RecursionError:
        # tomllib parses nested arrays and inline tables recursively.
        raise ConfigError([TOO_DEEP], source) from None
    except ValueError as exc:  # int() refused a digit run over the limit
        raise ConfigError([_long_integer(text, exc)], source) from None


def _long_integer(text: str, error: ValueError) -> str:
    """The line naming the first integer of ``text`` longer than Python converts."""
    limit = sys.get_int_max_str_digits()
    for number, line in enumerate(text.splitlines(), start=1):
        for match in _LONG_DIGITS.finditer(line):
            digits = len(match.group().replace("_", ""))
            if digits > limit:
                keys = _KEY_BEFORE_EQUALS.findall(line[: match.start()])
                key = keys[-1] if keys else "value"
                return (
                    f"line {number}: {key[:MAX_QUOTED]} = an integer of {digits:,} digits; "
                    f"expected a number of at most {limit:,} digits (ecdsim accepts "
                    "magnitudes up to 1e30)"
                )
    return f"not valid TOML: {quoted(str(error))}"


def parse_config(text: str, source: str = "<string>") -> Config:
    """Validate TOML text; :class:`ConfigError` lists every problem."""
    raw = parse_toml(text, source)
    spec = validate(raw, source)
    system = DeploymentSystem(ecd=spec.ecd(), load=spec.load.to_model(), name=spec.title)
    return Config(
        system=system,
        temperatures=tuple(spec.analysis.temperatures),
        methods=tuple(spec.analysis.methods),
        spec=spec,
        source=source,
        sha256=hashlib.sha256(text.encode("utf-8")).hexdigest(),
    )


def nesting_depth(document: object, limit: int = MAX_NESTING) -> int:
    """Depth of nested dicts and lists in ``document``, counted up to ``limit + 1``.

    Iterative (no recursion) and stops as soon as the limit is passed, so any document,
    however deep, is measured safely.

    >>> nesting_depth({"a": [1, [2]]})
    3
    """
    deepest = 0
    stack: list[tuple[object, int]] = [(document, 1)]
    while stack:
        item, depth = stack.pop()
        if isinstance(item, dict):
            children: list[object] = list(item.values())
        elif isinstance(item, list | tuple):
            children = list(item)
        else:
            continue
        deepest = max(deepest, depth)
        if deepest > limit:
            return deepest
        stack.extend((child, depth + 1) for child in children)
    return deepest


def validate(raw: dict[str, Any], source: str = "<string>") -> ConfigSpec | CoreConfigSpec:
    """Validate a parsed TOML document against the schema.

    A file with a study section (``[requirements]``, ``[fluid_damper]``, ``[tolerances]``)
    is validated by the whole :class:`~ecdsim.config.full_schema.ConfigSpec`; any other
    by :class:`~ecdsim.config.schema.CoreConfigSpec`, the same fields without those
    three, so that their schemas are not imported at start-up. Both give the same
    messages (their keys are described by the whole schema).
    """
    if nesting_depth(raw) > MAX_NESTING:
        raise ConfigError([TOO_DEEP], source)
    if "wing" in raw:  # a wing file (ecdsim.config.wing_schema), not a single hinge's
        raise ConfigError([WING_FILE], source)
    try:
        if any(section in raw for section in STUDY_SECTIONS):
            with _without_pydantic_plugins():
                from ecdsim.config.full_schema import ConfigSpec

            return ConfigSpec.model_validate(raw)
        return CoreConfigSpec.model_validate(raw)
    except ValidationError as exc:
        raise ConfigError(error_lines(exc), source) from None


# A wing file read where a single hinge's config is expected (docs/wing.md).
WING_FILE = (
    "wing: this is a wing file (docs/wing.md); `ecdsim deploy`, `report`, `sweep` and "
    "`montecarlo` take it, this command takes a single hinge's file"
)

Describe = Callable[[tuple[Any, ...]], tuple[str | None, list[str]]]


def error_lines(exc: ValidationError, describe: Describe | None = None) -> list[str]:
    """One line per validation error; ``describe`` gives a key path's expected unit and
    its section's keys (default: the deployment config's; the wing file passes its own)."""
    return [_message(error, describe) for error in exc.errors()]


def _path(loc: tuple[Any, ...]) -> str:
    text = ""
    for part in loc:
        text += f"[{part}]" if isinstance(part, int) else (f".{part}" if text else str(part))
    return text or "(top level)"


def _message(error: Any, describe: Describe | None = None) -> str:
    loc = tuple(error["loc"])
    path = _path(loc)
    kind = error["type"]
    if describe is None:
        # Errors only: the whole schema describes every key (and knows the study sections).
        from ecdsim.config.full_schema import describe_field

        describe = describe_field
    expected, known = describe(loc)
    if kind == "missing":
        return f"{path}: missing; {expected}" if expected else f"{path}: missing"
    if kind == "extra_forbidden":
        return f"{path}: unknown key (known keys here: {', '.join(known)})"
    if kind in {"quantity", "method"}:
        return f"{path}: {error['msg']}"
    message = str(error["msg"]).removeprefix("Value error, ")
    if kind in {"model_type", "model_attributes_type", "dict_type"}:
        message = f"expected a TOML table ([{path}] section or {{ key = value, ... }})"
    elif kind in {"list_type", "tuple_type"}:
        message = "expected a list [ ... ]"
    elif kind == "too_short":
        message = "expected at least one entry"
    if kind == "value_error":
        return f"{path}: {message}"
    return f"{path} = {quoted(error.get('input'))}: {message}"
