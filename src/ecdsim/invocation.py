"""How to run ecdsim and pip in this installation, for the lines that tell a user what to type.

``make demo`` installs ecdsim into the checkout's ``.venv`` without putting it on the
PATH, and a checkout is installed in development mode (``pip install -e``): a hint that
says ``ecdsim deploy ...`` or ``pip install 'ecdsim[fmu]'`` would run another program, or
install from the package index instead of the checkout. These functions name the command
that works here. A foundation module (it imports nothing of ecdsim), so that every layer
that reports a missing optional package (Monte Carlo, sweeps, the notebook API, the FMU,
the command line) says it with :func:`install_hint`.
"""

from __future__ import annotations

import os
import shutil
import sys
from pathlib import Path

__all__ = ["ecdsim_command", "install_hint", "pip_install"]


def _shown(path: Path) -> str:
    """``path`` relative to the working folder when it is inside it, else absolute."""
    try:
        relative = path.relative_to(Path.cwd())
    except ValueError:
        return str(path)
    return str(relative)


def ecdsim_command(argv0: str | None = None) -> str:
    """The command that runs this ecdsim: ``ecdsim`` when that name on the PATH is this
    program (or ecdsim was not started by its script: ``python -m ecdsim``, a notebook),
    else the path of the script it was started by (``.venv/bin/ecdsim`` after
    ``make demo``, where the venv's bin folder is not on the PATH)."""
    started = Path(argv0 if argv0 is not None else sys.argv[0])
    if started.name != "ecdsim" or not started.is_file():
        return "ecdsim"
    found = shutil.which("ecdsim")
    if found is not None and Path(found).resolve() == started.resolve():
        return "ecdsim"
    return _shown(started.absolute())


def _python() -> str:
    """This interpreter as a user would type it (``.venv/bin/python`` in a checkout)."""
    found = shutil.which("python3") or shutil.which("python")
    if found is not None and Path(found).resolve() == Path(sys.executable).resolve():
        return Path(found).name
    return _shown(Path(sys.executable).absolute())


def checkout() -> Path | None:
    """The source checkout this ecdsim is installed from in development mode, or None.

    A checkout has ``pyproject.toml`` two folders above the package (``src/ecdsim``);
    an installed wheel's package sits in ``site-packages``, which has none.
    """
    root = Path(__file__).resolve().parents[2]
    project = root / "pyproject.toml"
    if (root / "src" / "ecdsim").is_dir() and project.is_file():
        return root
    return None


def pip_install(extra: str) -> str:
    """The command that installs ``ecdsim[extra]`` into this interpreter's environment:
    from the checkout (``.venv/bin/python -m pip install -e '.[fmu]'``) when ecdsim runs
    from one, else from the package index."""
    root = checkout()
    pip = f"{_python()} -m pip install"
    if root is None:
        return f"{pip} 'ecdsim[{extra}]'"
    here = Path.cwd().resolve()
    target = "." if root == here else os.path.relpath(root, here)
    if target.startswith(".." + os.sep + ".." + os.sep + ".."):
        target = str(root)
    return f"{pip} -e '{target}[{extra}]'"


def install_hint(extra: str) -> str:
    """``"install it with: <command>"``, the end of every message about a missing
    optional package, with :func:`pip_install`'s command for ``extra``."""
    return f"install it with: {pip_install(extra)}"
