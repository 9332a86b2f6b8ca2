"""numba's set-up for every compiled kernel: the switch, the cache and the compile notice.

ecdsim's compiled kernels (the exact solution's for large batches, the dynamic method's
integrator, the Monte Carlo sums) import numba through :func:`load`, never at start-up.

* **The switch.** ``ECDSIM_NUMBA=0`` in the environment selects the NumPy paths of every
  kernel (:func:`enabled`); so does a missing numba (numba is a core dependency, but a
  platform without its wheels can install ecdsim without it: the NumPy paths are the
  reference implementations and are tested on their own).
* **The cache.** Every kernel is compiled with ``cache=True``: the machine code is kept on
  disk for this CPU and reused by later processes. numba puts it in ``__pycache__`` beside
  the package's source when that folder is writable (a virtual environment, a user
  install), and otherwise, as in a system-wide install, in the user's cache folder
  (``$XDG_CACHE_HOME/numba``, by default ``~/.cache/numba`` on Linux); ``NUMBA_CACHE_DIR``
  names another folder. Each CPU model keeps its own entries: a cache copied to another
  machine is recompiled, not misused. ``tests/test_numba_setup.py`` checks that a
  read-only package's kernels are compiled once and then loaded.
* **The notice.** The first compilation on a machine takes a minute or more (one
  dynamic run's kernels: 83 s of CPU for the MSL brake's; all of ``ecdsim precompile``'s
  309: 251 s on a loaded 2-core machine; docs/reproducibility.md), which looks
  like a hang. When a kernel is about to be compiled because the cache has none for this
  CPU, one line on stderr says so, once per process. It is printed only when stderr is a
  terminal (``ECDSIM_COMPILE_NOTICE=1`` prints it always, ``=0`` never): what a command
  prints to a pipe or a log must not depend on the state of a cache, or a script that
  compares the output of two runs would see the first differ. ``ecdsim precompile``
  compiles everything ahead (``make demo`` runs it).
* **Plain for a block.** Inside :func:`plain` every kernel runs its NumPy or plain-Python
  path, as with ``ECDSIM_NUMBA=0``, and numba is not imported for it. The deployment FMU
  runs so: numba inside a host's call into pythonfmu's Python aborted the host
  (docs/fmu.md).
"""

from __future__ import annotations

import os
import sys
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from types import ModuleType
from typing import Any, TextIO

__all__ = [
    "available",
    "cache_folder",
    "compilations",
    "enabled",
    "load",
    "note_cache",
    "plain",
    "switched_off",
]

# The switch every compiled kernel obeys.
SWITCH = "ECDSIM_NUMBA"
# The compile notice: "1" always, "0" never, anything else: when stderr is a terminal.
NOTICE = "ECDSIM_COMPILE_NOTICE"
# One line within 80 columns.
NOTICE_TEXT = "ecdsim: compiling its kernels for this CPU, once (a minute or more)"

_lock = threading.Lock()
# "plain": how many plain() blocks are open (process wide: the dynamic solve may run a
# batch's parts in threads of its own).
_state: dict[str, Any] = {"listener": None, "compilations": 0, "noticed": False, "plain": 0}
# Cache folders of compiled kernels that are not module globals (the dynamic kernel's,
# built from its Python source by ecdsim.dynamics.kernel.build).
_caches: set[str] = set()


def switched_off() -> bool:
    """True if ``ECDSIM_NUMBA=0`` (or an open :func:`plain` block) asks for the NumPy
    paths of every compiled kernel."""
    return _state["plain"] > 0 or os.environ.get(SWITCH, "").strip() == "0"


@contextmanager
def plain() -> Iterator[None]:
    """Within the block, every kernel runs its NumPy or plain-Python path, as with
    ``ECDSIM_NUMBA=0`` (for the whole process while the block is open)."""
    with _lock:
        _state["plain"] += 1
    try:
        yield
    finally:
        with _lock:
            _state["plain"] -= 1


def available() -> bool:
    """True if numba imports (it is then imported, with ecdsim's set-up: :func:`load`).

    Asked only where a compiled kernel is about to run (its import costs about 0.3 s,
    which a command that never compiles does not pay). A numba that is missing, or
    present but broken (an llvmlite of another version), is False: the NumPy paths run.
    """
    if sys.modules.get("numba") is not None and _state["listener"] is not None:
        return True
    try:
        load()
    except ImportError:
        return False
    return True


def enabled() -> bool:
    """True if the compiled kernels run: numba imports and is not switched off."""
    return not switched_off() and available()


def load() -> ModuleType:
    """numba, with ecdsim's compile notice installed (once per process).

    Every compiled module imports numba through this function. Raises ImportError where
    numba is not installed (the callers then take the NumPy path).
    """
    import numba

    with _lock:
        if _state["listener"] is None:
            from numba.core import event as events

            event: Any = events  # numba's event API, untyped
            listener = _listener_class(event)()
            event.register("numba:compile", listener)
            _state["listener"] = listener
    return numba


def compilations() -> int:
    """How many compilations (cache misses, nested ones included) this process started."""
    return int(_state["compilations"])


def note_cache(path: str) -> None:
    """Record the cache folder of a kernel compiled outside a module's globals."""
    with _lock:
        _caches.add(path)


def cache_folder() -> str | None:
    """Where the kernels loaded so far are cached (the folder common to their caches, or
    the ``__pycache__`` folders under it); None before any kernel is loaded."""
    folders: set[str] = set(_caches)
    for name, module in list(sys.modules.items()):
        if module is None or not (name == "ecdsim" or name.startswith("ecdsim.")):
            continue
        for value in list(vars(module).values()):
            path = getattr(getattr(value, "_cache", None), "cache_path", None)
            if isinstance(path, str):
                folders.add(path)
    if not folders:
        return None
    common = os.path.commonpath(sorted(folders))
    if all(os.path.basename(folder) == "__pycache__" for folder in folders):
        return f"the __pycache__ folders under {common}"
    return common


def _wants_notice(stream: TextIO) -> bool:
    """The notice's rule (module docstring): the environment's choice, else a terminal."""
    choice = os.environ.get(NOTICE, "").strip()
    if choice in ("0", "1"):
        return choice == "1"
    isatty = getattr(stream, "isatty", None)
    return bool(isatty and isatty())


def notice(stream: TextIO | None = None) -> None:
    """Print the compile notice on ``stream`` (stderr) if the rule asks for it, once."""
    target = sys.stderr if stream is None else stream
    with _lock:
        if _state["noticed"] or not _wants_notice(target):
            return
        _state["noticed"] = True
    print(NOTICE_TEXT, file=target, flush=True)


def _listener_class(event: Any) -> type:
    """A numba event listener that counts compilations and prints the notice at the first.

    numba raises the ``numba:compile`` event only after its disk cache had nothing for
    the signature (``Dispatcher.compile``): a cache hit never reaches it.
    """

    class CompileListener(event.Listener):  # type: ignore[misc]
        def on_start(self, event: Any) -> None:
            with _lock:
                _state["compilations"] += 1
            notice()

        def on_end(self, event: Any) -> None:
            return None

    return CompileListener
