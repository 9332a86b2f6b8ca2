"""The common end of the bench-reduction commands (``fit drive-test``, ``fit fluid-damper``).

Both write an optional parameter file and plots, print a table or JSON, then their warnings
and the files written, in the same order and wording; written once here. Only typer is
imported at start-up.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import typer

from ecdsim.cli.common import fail

if TYPE_CHECKING:
    from ecdsim.units_display import UnitSystem


def finish_bench_fit(
    result: Any,
    *,
    command: str,
    output: Path | None,
    parameter_text: Callable[[list[str]], str],
    plot: Path | None,
    write_plots: Callable[[Any, Path, UnitSystem], Sequence[Path]],
    as_json: bool,
    u_system: UnitSystem,
    print_table: Callable[[Any, Any], None],
    bad: list[str],
    not_done: str,
) -> None:
    """Write ``result``'s parameter file (``-o``) and plots (``--plot``), print it, then
    the bad rows, the temperatures ``not_done`` ("not reduced", "not fitted"), the fit's
    warnings and the files written.

    ``parameter_text`` turns the provenance lines of ``command`` into the file's text.
    """
    import json

    from ecdsim.characterize.export import ExportError, provenance, write_parameter_file

    written: list[str] = []
    if output is not None:
        lines = provenance(command, result.table.source, result.table.sha256)
        try:
            written.append(str(write_parameter_file(output, parameter_text(lines))))
        except ExportError as exc:
            fail([f"-o {output}: {exc}"])
        except OSError as exc:
            fail([f"-o {output}: cannot write ({exc.strerror or exc})"])
    if plot is not None:
        try:
            written += [str(p) for p in write_plots(result, plot, u_system)]
        except OSError as exc:
            fail([f"--plot {plot}: cannot write plots ({exc.strerror or exc})"])
    if as_json:
        document = result.to_dict()
        document["parameter_file"] = written[0] if output is not None else None
        document["display_units"] = u_system
        typer.echo(json.dumps(document, indent=2, sort_keys=True, allow_nan=False))
    else:
        from ecdsim.units_display import Shown

        print_table(result, Shown(u_system))
    for line in bad[:20]:
        typer.echo(f"warning: {line}", err=True)
    for t, _, why in result.failed:
        typer.echo(f"error: {not_done}: {t:g} degC: {why}", err=True)
    for warning in result.warnings:
        typer.echo(f"warning: {warning.message}", err=True)
    for path in written:
        typer.echo(f"wrote {path}", err=as_json)
