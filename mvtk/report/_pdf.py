"""PDF export of an HTML report through headless Chromium (Debian package ``chromium``)."""

from __future__ import annotations

import os
import shutil
import subprocess
import tempfile
from pathlib import Path

from .._atomic import atomic_path
from ..errors import MissingDependencyError, MvtkError, ParameterError

__all__ = ["to_pdf", "find_chromium"]

#: Flags of a headless, sandbox-free, offline Chromium (as in the browser tests).
CHROMIUM_FLAGS = (
    "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
    "--disable-background-networking", "--disable-component-update", "--disable-sync",
    "--disable-dev-shm-usage",
)

_INSTALL = ("install the Debian package 'chromium' (apt-get install chromium), or set "
            "MVTK_CHROMIUM to a Chromium/Chrome executable")


class PdfExportError(MvtkError, RuntimeError):
    """Chromium ran but did not produce the PDF."""


def find_chromium() -> str | None:
    """Path of the Chromium executable: ``$MVTK_CHROMIUM``, else ``chromium`` /
    ``chromium-browser`` / ``google-chrome`` on ``PATH``; ``None`` when absent."""
    env = os.environ.get("MVTK_CHROMIUM")
    if env:
        return env if Path(env).is_file() else shutil.which(env)
    for name in ("chromium", "chromium-browser", "google-chrome"):
        exe = shutil.which(name)
        if exe:
            return exe
    return None


def to_pdf(
    html_path: str | Path,
    pdf_path: str | Path | None = None,
    *,
    chromium: str | None = None,
    timeout: float = 180.0,
) -> Path:
    """Print an HTML report to PDF with headless Chromium (A4, the page's print CSS).

    Parameters
    ----------
    html_path : path
        The report page (``index.html``) or the folder holding it.
    pdf_path : path, optional
        Output file (default: ``report.pdf`` next to the page).
    chromium : str, optional
        Chromium executable (default: :func:`find_chromium`).
    timeout : float
        Seconds before Chromium is stopped.

    Returns
    -------
    Path
        The PDF file.

    Raises
    ------
    MissingDependencyError
        Chromium is not installed (names the Debian package).
    ParameterError
        ``html_path`` is not an HTML file or a folder with ``index.html``.
    PdfExportError
        Chromium failed, timed out or wrote no PDF.
    """
    page = Path(html_path)
    if page.is_dir():
        page = page / "index.html"
    if not page.is_file():
        raise ParameterError(f"cannot export {str(page)!r} to PDF: no such HTML file "
                             "(give a report folder with index.html or the page itself)")
    exe = chromium or find_chromium()
    if exe is None or shutil.which(exe) is None and not Path(exe).is_file():
        raise MissingDependencyError(f"PDF export needs headless Chromium, which was not "
                                     f"found; {_INSTALL}")
    out = Path(pdf_path) if pdf_path is not None else page.with_name("report.pdf")
    out = out.resolve()
    out.parent.mkdir(parents=True, exist_ok=True)
    # printed to a temporary file next to the target and renamed when complete: a
    # failed print leaves the previous PDF as it was
    with atomic_path(out) as tmp, \
            tempfile.TemporaryDirectory(prefix="mvtk-chromium-") as profile:
        cmd = [exe, *CHROMIUM_FLAGS, f"--user-data-dir={profile}", "--no-pdf-header-footer",
               "--run-all-compositor-stages-before-draw", f"--print-to-pdf={tmp}",
               page.resolve().as_uri()]
        try:
            res = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout,
                                 check=False)
        except subprocess.TimeoutExpired:
            raise PdfExportError(f"Chromium did not finish printing {page} within "
                                 f"{timeout:g} s") from None
        if res.returncode != 0 or not tmp.is_file() or tmp.stat().st_size == 0:
            tail = " | ".join((res.stderr or "").strip().splitlines()[-5:])
            raise PdfExportError(f"Chromium ({exe}) failed to print {page} to {out} (exit "
                                 f"code {res.returncode})" + (f": {tail}" if tail else ""))
        with open(tmp, "rb") as fh:
            if fh.read(5) != b"%PDF-":
                raise PdfExportError(f"Chromium wrote {out} but it is not a PDF file")
    return out
