"""The layers are one-way: no module imports a higher layer, and no modules import in a loop.

Every module under ``src/ecdsim`` is parsed with :mod:`ast` (nothing is imported), and
every import statement counts: module-level ones, those inside functions (the lazy
imports that keep ``ecdsim --help`` fast) and those under ``TYPE_CHECKING``. Importing
``a.b.c`` also runs the ``__init__`` of ``a.b``, so that counts as an import of ``a.b``
too. ``LAYERS`` below is the order, lowest first; docs/architecture.md states the same
order in its layer table, and a test holds the two together.
"""

from __future__ import annotations

import ast
import re
from collections.abc import Iterator
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SOURCE = ROOT / "src"
ARCHITECTURE = ROOT / "docs" / "architecture.md"

# Lowest first. A module may import its own group (package or module) and any group of a
# lower layer. Groups that share a layer are peers: they may not import each other. The
# group "ecdsim" is the package's own __init__ (its face), not everything under it.
LAYERS: list[tuple[str, tuple[str, ...]]] = [
    (
        "foundation",
        (
            "ecdsim._numba",
            "ecdsim._types",
            "ecdsim._version",
            "ecdsim.atomic",
            "ecdsim.formatting",
            "ecdsim.invocation",
            "ecdsim.jsonrows",
            "ecdsim.tidy",
            "ecdsim.units_display",
        ),
    ),
    ("physics", ("ecdsim.physics",)),
    ("model", ("ecdsim.model",)),
    ("solvers", ("ecdsim.solvers",)),
    ("dynamics", ("ecdsim.dynamics",)),
    ("registry", ("ecdsim.methods",)),
    ("system", ("ecdsim.deployment", "ecdsim.wing")),
    ("config", ("ecdsim.config",)),
    ("plots", ("ecdsim.plotting",)),
    ("dynamic plots", ("ecdsim.plotting_dynamic", "ecdsim.plotting_wing")),
    ("studies", ("ecdsim.characterize", "ecdsim.sizing", "ecdsim.sweeps")),
    ("tolerances", ("ecdsim.montecarlo",)),
    ("report", ("ecdsim.report",)),
    ("explorer", ("ecdsim.webapp",)),
    ("notebook", ("ecdsim.api",)),
    ("export", ("ecdsim.fmu",)),
    ("command line", ("ecdsim.cli",)),
    ("entry points", ("ecdsim", "ecdsim.__main__")),
]


def _modules() -> dict[str, tuple[Path, bool]]:
    """Every module's dotted name -> (file, is a package's __init__)."""
    found = {}
    for path in sorted((SOURCE / "ecdsim").rglob("*.py")):
        parts = list(path.relative_to(SOURCE).with_suffix("").parts)
        package = parts[-1] == "__init__"
        if package:
            parts = parts[:-1]
        found[".".join(parts)] = (path, package)
    return found


MODULES = _modules()


def _imports(name: str, path: Path, package: bool) -> Iterator[tuple[str, int]]:
    """(imported ecdsim module, line) for every import statement in one module."""
    here = name.split(".") if package else name.split(".")[:-1]
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), str(path))):
        if isinstance(node, ast.Import):
            for alias in node.names:
                yield alias.name, node.lineno
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = here[: len(here) - node.level + 1]
                target = ".".join([*base, *([node.module] if node.module else [])])
            else:
                target = node.module or ""
            for alias in node.names:
                submodule = f"{target}.{alias.name}"
                yield (submodule if submodule in MODULES else target), node.lineno


def _edges() -> dict[str, dict[str, int]]:
    """importer -> {imported ecdsim module: first line}, including package __init__ runs."""
    edges: dict[str, dict[str, int]] = {}
    for name, (path, package) in MODULES.items():
        own_packages = {".".join(name.split(".")[:i]) for i in range(1, name.count(".") + 2)}
        out: dict[str, int] = {}
        for target, line in _imports(name, path, package):
            if target != "ecdsim" and not target.startswith("ecdsim."):
                continue
            parts = target.split(".")
            # Importing a.b.c runs a.b's __init__ first, unless it is the importer's own.
            for i in range(2, len(parts) + 1):
                module = ".".join(parts[:i])
                if module in MODULES and module not in own_packages:
                    out.setdefault(module, line)
        out.pop(name, None)
        edges[name] = out
    return edges


EDGES = _edges()


def _group(module: str) -> tuple[int, str]:
    """(layer index, group) of a module: the longest declared prefix that holds it."""
    best: tuple[int, str] | None = None
    for index, (_, groups) in enumerate(LAYERS):
        for group in groups:
            holds = module == group or (group != "ecdsim" and module.startswith(group + "."))
            if holds and (best is None or len(group) > len(best[1])):
                best = (index, group)
    if best is None:
        raise LookupError(module)
    return best


def test_every_module_belongs_to_a_declared_layer() -> None:
    unplaced = []
    for module in MODULES:
        try:
            _group(module)
        except LookupError:
            unplaced.append(module)
    assert unplaced == [], f"add these to LAYERS and docs/architecture.md: {unplaced}"


def test_no_module_imports_a_higher_layer_or_a_peer() -> None:
    wrong = []
    for importer, targets in EDGES.items():
        own_layer, own_group = _group(importer)
        for target, line in targets.items():
            layer, group = _group(target)
            if layer > own_layer or (layer == own_layer and group != own_group):
                wrong.append(
                    f"{importer} (layer {LAYERS[own_layer][0]!r}) line {line} imports {target} "
                    f"(layer {LAYERS[layer][0]!r})"
                )
    assert wrong == [], "\n".join(wrong)


def _cycles(edges: dict[str, dict[str, int]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []

    def visit(node: str) -> None:
        index[node] = low[node] = len(index)
        stack.append(node)
        on_stack.add(node)
        for nxt in edges.get(node, {}):
            if nxt not in index:
                visit(nxt)
                low[node] = min(low[node], low[nxt])
            elif nxt in on_stack:
                low[node] = min(low[node], index[nxt])
        if low[node] == index[node]:
            component = []
            while True:
                member = stack.pop()
                on_stack.discard(member)
                component.append(member)
                if member == node:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for node in sorted(edges):
        if node not in index:
            visit(node)
    return found


def test_no_modules_import_each_other_in_a_loop() -> None:
    assert _cycles(EDGES) == []


def test_the_checks_see_lazy_and_relative_imports_and_loops(tmp_path: Path) -> None:
    # The checks must see what they are for: an import inside a function, one under
    # TYPE_CHECKING, a relative one, and a loop of three modules.
    source = tmp_path / "probe.py"
    source.write_text(
        "from typing import TYPE_CHECKING\n"
        "if TYPE_CHECKING:\n"
        "    from ecdsim.deployment import Prediction\n"
        "def f():\n"
        "    from ecdsim.cli.app import app\n"
        "    from .fit import fit_app\n",
        encoding="utf-8",
    )
    seen = {target for target, _ in _imports("ecdsim.cli.probe", source, package=False)}
    assert {"ecdsim.deployment", "ecdsim.cli.app", "ecdsim.cli.fit"} <= seen
    assert _cycles({"a": {"b": 1}, "b": {"c": 1}, "c": {"a": 1}, "d": {"a": 1}}) == [
        ["a", "b", "c"]
    ]
    # In the real graph: lazy imports counted, and importing ecdsim.solvers.base counts
    # as importing ecdsim.solvers (its __init__ runs first).
    assert "ecdsim.characterize.droptest" in EDGES["ecdsim.cli.fit"]
    assert "ecdsim.solvers" in EDGES["ecdsim.dynamics.problem"]


def test_architecture_doc_states_the_same_layers_in_the_same_order() -> None:
    # The doc's layer table: one row per layer, lowest first: "| 1 foundation | `group`, ...".
    text = ARCHITECTURE.read_text(encoding="utf-8")
    rows = re.findall(r"^\| *(\d+) +([a-z ]+?) *\| *([^|]*)\|", text, flags=re.MULTILINE)
    documented = [(name, tuple(re.findall(r"`([\w.]+)`", groups))) for _, name, groups in rows]
    assert documented == LAYERS, "docs/architecture.md's layer table differs from LAYERS"
    assert [int(number) for number, _, _ in rows] == list(range(1, len(LAYERS) + 1))
