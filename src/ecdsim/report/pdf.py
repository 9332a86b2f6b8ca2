"""Print an HTML report to PDF with headless Chromium (Debian ``chromium`` or Google Chrome).

No Python dependency: the browser is run as a subprocess with networking irrelevant (the
report is self-contained). When no browser is found, :class:`PdfUnavailable` names what
is missing so that the CLI can say so and exit with code 2.
"""

from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path

from ecdsim.atomic import atomic_path

BROWSERS = ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable")
ENV_BROWSER = "ECDSIM_CHROMIUM"
TIMEOUT_S = 120.0


class PdfUnavailable(RuntimeError):
    """No headless browser could print the PDF; the message says what is missing."""


def find_browser() -> str | None:
    """Path of a Chromium-family browser: ``$ECDSIM_CHROMIUM`` first, then the PATH."""
    override = os.environ.get(ENV_BROWSER)
    if override:
        return override if Path(override).is_file() else shutil.which(override)
    for name in BROWSERS:
        found = shutil.which(name)
        if found:
            return found
    return None


def html_to_pdf(html_path: Path, pdf_path: Path) -> Path:
    """Print ``html_path`` to ``pdf_path`` (written atomically) with headless Chromium."""
    browser = find_browser()
    if browser is None:
        raise PdfUnavailable(
            f"--pdf needs a Chromium browser and none was found (looked for {', '.join(BROWSERS)} "
            f"on PATH and ${ENV_BROWSER}); install it (Debian: apt-get install chromium) "
            "or open the HTML report and print it"
        )
    with atomic_path(pdf_path) as temporary:
        command = [
            browser,
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--no-first-run",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--no-pdf-header-footer",
            f"--print-to-pdf={temporary}",
            html_path.resolve().as_uri(),
        ]
        try:
            done = subprocess.run(  # noqa: S603 - fixed argument list, no shell
                command, capture_output=True, text=True, timeout=TIMEOUT_S, check=False
            )
        except (OSError, subprocess.TimeoutExpired) as exc:
            raise PdfUnavailable(f"--pdf: running {browser} failed ({exc})") from None
        if done.returncode != 0 or temporary.stat().st_size == 0:
            tail = (done.stderr or "").strip().splitlines()[-1:] or ["no output"]
            raise PdfUnavailable(
                f"--pdf: {browser} did not print the PDF (exit {done.returncode}: {tail[0]})"
            )
    return pdf_path
