"""A self-contained HTML report: sections, pandas tables with pass/fail, figures.

The page has no script and no external resource (figures are embedded as base64 SVG
for line plots or PNG for raster and very dense ones; styles are inline), so it opens
offline and prints to PDF (:func:`mvtk.report.to_pdf`). Table cells are formatted by quantity
(:mod:`mvtk.report._format`) and each table sits in a box that scrolls horizontally when
the window is too narrow. Each table is also written, unformatted, as CSV next to
``index.html`` under ``tables/``.
"""

from __future__ import annotations

import base64
import html
import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from string import Template
from typing import Any

import numpy as np
import pandas as pd

from .._atomic import write_text
from .._format import ColumnFormat, FormatSpec, dict_table
from .._table import TABLE_CSS, html_table, render_table
from ..errors import ParameterError
from ._provenance import Provenance
from ._render import FigureRenderer, render_figure

__all__ = ["Report", "Section", "render_table", "html_table", "tolerance_used", "TABLE_CSS"]

_NAME_RE = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.-]{0,80}$")

_PAGE = Template(
    """<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<title>$title</title>
<style>
body { font-family: system-ui, sans-serif; margin: 2em auto; max-width: 80em;
       padding: 0 1em; color: #222; line-height: 1.4; }
h1 { border-bottom: 2px solid #335; }
h2 { border-bottom: 1px solid #aab; margin-top: 2em; }
$table_css
figure { margin: 1em 0; max-width: 100%; }
figure img { display: block; box-sizing: border-box; width: 100%; max-width: 702px;
             height: auto;
             border: 1px solid #ddd; }
figcaption { font-size: 0.9em; color: #444; }
.verdict { font-size: 1.2em; padding: 0.5em 1em; border-radius: 4px; display: inline-block; }
.verdict.pass { background: #d7f5d7; } .verdict.fail { background: #fbd5d5; }
.executive { border: 2px solid #335; border-radius: 6px; padding: 0.2em 1em 0.6em;
             margin: 1em 0; }
.executive h2 { margin-top: 0.5em; }
.unavailable { background: #fff4d6; border-left: 4px solid #e0a800; padding: 0.5em 1em; }
.synthetic { background: #e8f0ff; border-left: 4px solid #3a6fd8; padding: 0.5em 1em; }
pre { background: #f6f6f8; padding: 0.6em; overflow-x: auto; font-size: 0.85em; }
a.csv { font-size: 0.85em; font-weight: normal; }
@page { size: A4; margin: 14mm 12mm; }
@media print {
  body { margin: 0; max-width: none; padding: 0; font-size: 10pt; }
  nav, a.csv { display: none; }
  h2 { break-after: avoid; }
  .mvtk-table-wrap { overflow: visible; }
  table.mvtk { font-size: 7.5pt; }
  table.mvtk th, table.mvtk td { padding: 0.2em 0.3em; }
  table.mvtk tr, figure, .executive { break-inside: avoid; }
  figure img { max-width: 100%; }
  pre { white-space: pre-wrap; overflow-wrap: anywhere; }
}
</style>
</head>
<body>
<h1>$title</h1>
$summary
$toc
$body
</body>
</html>
"""
)


_TOL_REL = re.compile(r"^\s*±\s*([0-9.eE+-]+)\s*%\s*$")
_TOL_ABS = re.compile(r"^\s*±\s*([0-9.eE+-]+)(\s+\S.*)?$")
_TOL_BOUND = re.compile(r"^\s*(<=|>=)\s*ref\s*[+-]\s*([0-9.eE+-]+)(\s+\S.*)?$")


def tolerance_used(checks: pd.DataFrame, *, error_column: str = "error_pct") -> np.ndarray:
    """Share of its tolerance each check uses (1.0 = at the limit, > 1 = failed).

    Read from the ``tolerance`` text of :func:`mvtk.validation.check_table`:
    ``"±X %"`` -> ``|error_pct| / X``; ``"±X unit"`` -> ``|error| / X``;
    ``"<= ref + X"`` -> ``value / (reference + X)``; ``">= ref - X"`` ->
    ``(reference - X) / value`` (bounds on positive quantities). ``nan`` where the text
    is not one of these or the ratio is undefined.

    Parameters
    ----------
    checks : DataFrame
        With columns ``tolerance`` and ``error_column`` / ``error`` / ``value`` /
        ``reference`` as needed.
    error_column : str
        Column of the relative error in percent.

    Returns
    -------
    ndarray, shape (len(checks),)
    """
    n = len(checks)
    out = np.full(n, np.nan)
    if "tolerance" not in checks.columns:
        return out

    def num(col):
        if col not in checks.columns:
            return np.full(n, np.nan)
        return pd.to_numeric(checks[col], errors="coerce").to_numpy(dtype=float)

    err_pct, err, value, ref = num(error_column), num("error"), num("value"), num("reference")
    with np.errstate(divide="ignore", invalid="ignore"):
        for i, tol in enumerate(checks["tolerance"].astype(str)):
            try:
                if m := _TOL_REL.match(tol):
                    out[i] = abs(err_pct[i]) / float(m.group(1))
                elif m := _TOL_BOUND.match(tol):
                    limit = ref[i] + float(m.group(2)) * (1 if m.group(1) == "<=" else -1)
                    if limit > 0 and value[i] > 0:
                        out[i] = value[i] / limit if m.group(1) == "<=" else limit / value[i]
                elif m := _TOL_ABS.match(tol):
                    out[i] = abs(err[i]) / float(m.group(1))
            except (ValueError, ZeroDivisionError):
                out[i] = np.nan
    out[~np.isfinite(out)] = np.nan
    return out


#: kept here for compatibility; the rendering lives in :mod:`mvtk.report._render`
_figure_bytes = render_figure


class _FigureBlock:
    """A figure of a section: its HTML once the render job is done."""

    __slots__ = ("job", "number", "alt", "caption")

    def __init__(self, job, number: int, alt: str, caption: str) -> None:
        self.job, self.number, self.alt, self.caption = job, number, alt, caption

    def __str__(self) -> str:
        if not self.job.done:
            raise RuntimeError("figure not rendered yet: call Report.render_figures()")
        b64 = base64.b64encode(self.job.data).decode("ascii")
        return (f'<figure><img class="report-figure" alt="{self.alt}" '
                f'src="data:{self.job.mime};base64,{b64}">'
                f"<figcaption>Figure {self.number}: {html.escape(self.caption)}"
                "</figcaption></figure>")


@dataclass
class Section:
    """A titled part of a :class:`Report` holding paragraphs, tables and figures.

    Made by :meth:`Report.section`; the methods return ``self`` so calls chain.
    """

    title: str
    report: Report = field(repr=False)
    blocks: list[Any] = field(default_factory=list)
    anchor: str = ""

    def text(self, paragraph: str) -> Section:
        """Add a paragraph of plain text (escaped)."""
        self.blocks.append(f"<p>{html.escape(paragraph)}</p>")
        return self

    def note(self, paragraph: str, kind: str = "synthetic") -> Section:
        """Add a highlighted note; ``kind`` is ``"synthetic"`` or ``"unavailable"``."""
        if kind not in ("synthetic", "unavailable"):
            raise ParameterError(f"note kind must be 'synthetic' or 'unavailable', got {kind!r}")
        self.blocks.append(f'<div class="{kind}">{html.escape(paragraph)}</div>')
        return self

    def unavailable(self, reason: str) -> Section:
        """Mark this stage as not available, with the reason (no numbers are faked)."""
        self.report.unavailable.append((self.title, reason))
        return self.note(f"Not available: {reason}", kind="unavailable")

    def table(
        self,
        df: pd.DataFrame,
        name: str,
        caption: str = "",
        passed_column: str | None = "passed",
        formats: Mapping[Any, FormatSpec] | None = None,
    ) -> Section:
        """Add a table; it is also written (unformatted) as ``tables/<name>.csv``.

        Parameters
        ----------
        df : DataFrame
        name : str
            File stem of the CSV; letters, digits, ``_.-``; unique within the report.
        caption : str
        passed_column : str or None
            Boolean column shown as PASS/FAIL and counted in the report's verdict.
        formats : mapping of column to ColumnFormat, int or callable, optional
            Per-column overrides of the formatting inferred from the column names
            (an int is a number of significant digits); see :func:`render_table`.
        """
        if not isinstance(df, pd.DataFrame):
            raise ParameterError(f"table {name!r}: expected a pandas DataFrame, got "
                                 f"{type(df).__name__}")
        if not _NAME_RE.match(name):
            raise ParameterError(
                f"table name {name!r} is not a safe file stem "
                "(letters, digits, '_', '.', '-'; at most 81 characters)"
            )
        if name in self.report.tables:
            raise ParameterError(f"table name {name!r} is used twice in the report")
        try:
            block = render_table(df, caption=caption, passed_column=passed_column,
                                 csv_href=f"tables/{name}.csv", table_id=f"table-{name}",
                                 formats=formats)
        except ParameterError as err:
            raise ParameterError(f"table {name!r}: {err}") from None
        self.report.tables[name] = df
        if passed_column is not None and passed_column in df.columns:
            self.report.verdicts.extend(bool(v) for v in df[passed_column])
        self.blocks.append(block)
        return self

    def figure(self, figure: Any, caption: str = "", alt: str | None = None,
               image_format: str = "auto") -> Section:
        """Add a figure, embedded in the page (base64 data URI).

        A matplotlib figure is rendered when the page is written, in one of the
        report's render processes (see :class:`Report`'s ``workers``): do not change it
        after adding it. A function returning a figure (``functools.partial(plot_frf,
        f, H)``) is called there too, so that building the figure is shared out as well.

        Parameters
        ----------
        figure : matplotlib Figure, bytes or callable
            A figure, PNG / SVG bytes, or a function without arguments returning a
            figure.
        caption, alt : str
        image_format : {"auto", "svg", "png"}
            For a matplotlib figure: ``"auto"`` gives PNG for figures with raster images,
            SVG for line plots up to :data:`SVG_KEEP_BYTES`, and the smaller of the two
            for larger ones.
        """
        job = self.report._renderer().submit(figure, image_format)
        alt_text = html.escape(alt if alt is not None else caption or self.title)
        self.report.n_figures += 1
        self.blocks.append(_FigureBlock(job, self.report.n_figures, alt_text, caption))
        return self

    def preformatted(self, text: str) -> Section:
        """Add preformatted text (escaped)."""
        self.blocks.append(f"<pre>{html.escape(text)}</pre>")
        return self

    def render(self) -> str:
        """HTML of the section (renders the report's pending figures first)."""
        self.report.render_figures()
        return f'<section id="{self.anchor}"><h2>{html.escape(self.title)}</h2>\n' + "\n".join(
            map(str, self.blocks)
        ) + "</section>"


@dataclass
class Report:
    """Builder of a self-contained HTML report.

    Parameters
    ----------
    title : str
    workers : int, optional
        Processes rendering figures at the same time, forked as each figure is added
        (default: ``MVTK_REPORT_WORKERS`` or the usable CPUs; ``0``: render in process,
        as each figure is added). Without ``fork`` (Windows) figures render in process.

    Examples
    --------
    >>> rep = Report("Smart beam")
    >>> _ = rep.section("Eigenfrequencies").table(df, "table2", "FE vs test")  # doctest: +SKIP
    >>> rep.write("out")  # writes out/index.html and out/tables/table2.csv  # doctest: +SKIP
    """

    title: str
    sections: list[Section] = field(default_factory=list)
    tables: dict[str, pd.DataFrame] = field(default_factory=dict)
    verdicts: list[bool] = field(default_factory=list)
    unavailable: list[tuple[str, str]] = field(default_factory=list)
    n_figures: int = 0
    provenance: Provenance | None = None
    summary_html: str = ""
    summary_verdict: str = ""
    workers: int | None = None
    _figure_renderer: FigureRenderer | None = field(default=None, init=False,
                                                    repr=False, compare=False)

    def _renderer(self) -> FigureRenderer:
        if self._figure_renderer is None:
            self._figure_renderer = FigureRenderer(self.workers)
        return self._figure_renderer

    def render_figures(self) -> None:
        """Wait until every figure added so far is rendered (done by :meth:`to_html`)."""
        if self._figure_renderer is not None:
            self._figure_renderer.wait()

    def section(self, title: str) -> Section:
        """Append and return a new section."""
        sec = Section(title=title, report=self, anchor=f"s{len(self.sections) + 1}")
        self.sections.append(sec)
        return sec

    def add_provenance(self, provenance: Provenance) -> Section:
        """Append the provenance section (versions, date, input hashes, parameters).

        The parameters (e.g. the parsed study TOML) are shown as a key/value table
        (:func:`mvtk.report.dict_table`) and written as ``tables/provenance_parameters.csv``.
        """
        self.provenance = provenance
        sec = self.section("Provenance")
        sec.table(provenance.to_dataframe(), "provenance_versions", "Software and date",
                  passed_column=None)
        if len(provenance.inputs):
            sec.table(provenance.inputs, "provenance_inputs", "Input files (SHA-256)",
                      passed_column=None, formats={"bytes": str})
        else:
            sec.text("No input files.")
        if provenance.parameters:
            sec.table(dict_table(provenance.parameters), "provenance_parameters",
                      "Parameters", passed_column=None)
        return sec

    def executive_summary(
        self,
        checks: pd.DataFrame,
        *,
        validated: str,
        against: str,
        n_worst: int = 5,
        passed_column: str = "passed",
        error_column: str = "error_pct",
        name_column: str = "check",
        columns: list[str] | None = None,
    ) -> Report:
        """Put an executive summary at the top of the page.

        The summary says what was validated and against what, gives the verdict of
        ``checks`` (PASS only when every check passed; a report without checks has no
        PASS) and lists the ``n_worst`` checks: failed ones first, then the passing
        ones closest to their limit (largest share of the tolerance used, see
        :func:`tolerance_used`), then by decreasing ``|error_column|``. Calling it again
        replaces the summary. The checks are not added to the report's count; add the
        full table with :meth:`Section.table`.

        Parameters
        ----------
        checks : DataFrame
            One row per check with a boolean ``passed_column`` (e.g.
            :func:`mvtk.validation.check_table`).
        validated : str
            What was validated (e.g. ``"FE model of the smart beam, damping, SE and
            controllers"``).
        against : str
            The references (e.g. ``"synthetic measurements and the paper's Tables 2-5"``).
        n_worst : int
            Number of worst checks listed (>= 1).
        passed_column, error_column, name_column : str
            Columns of ``checks``; ``error_column`` may be absent (then failed checks
            are listed in table order).
        columns : list of str, optional
            Columns of the worst-checks table (default: name, value, reference, unit,
            error_pct, tolerance, passed when present).
        """
        if not isinstance(checks, pd.DataFrame):
            raise ParameterError(f"executive_summary expects the checks as a DataFrame, got "
                                 f"{type(checks).__name__}")
        if passed_column not in checks.columns:
            raise ParameterError(
                f"executive_summary: the checks table has no {passed_column!r} column; "
                f"columns are {[str(c) for c in checks.columns]}")
        if not isinstance(n_worst, int) or n_worst < 1:
            raise ParameterError(f"executive_summary: n_worst must be an integer >= 1, got "
                                 f"{n_worst!r}")
        passed = checks[passed_column].astype(bool).to_numpy()
        n, n_ok = len(checks), int(passed.sum())
        used = tolerance_used(checks, error_column=error_column)
        err = (pd.to_numeric(checks[error_column], errors="coerce").abs().to_numpy()
               if error_column in checks.columns else np.full(n, np.nan))
        order = pd.DataFrame({"failed": ~passed, "used": used, "err": err,
                              "pos": np.arange(n)})
        order = order.sort_values(["failed", "used", "err", "pos"],
                                  ascending=[False, False, False, True], na_position="last")
        worst = checks.iloc[order["pos"].to_numpy()[:n_worst]].reset_index(drop=True)
        if np.isfinite(used).any():
            worst.insert(len(worst.columns), "tolerance_used_pct",
                         100.0 * used[order["pos"].to_numpy()[:n_worst]])
        default = [name_column, "value", "reference", "unit", error_column, "tolerance",
                   "tolerance_used_pct", passed_column]
        cols = [c for c in (columns or default) if c in worst.columns]
        missing = [c for c in (columns or []) if c not in checks.columns]
        if missing:
            raise ParameterError(f"executive_summary: columns {missing} are not in the "
                                 "checks table")
        ok = n > 0 and n_ok == n
        if n == 0:
            verdict = "NO VERDICT: no check could be evaluated"
        elif ok:
            verdict = f"PASS: all {n} checks passed"
        else:
            verdict = f"FAIL: {n - n_ok} of {n} checks failed"
        parts = [
            '<section class="executive" id="executive-summary"><h2>Executive summary</h2>',
            f"<p><b>Validated:</b> {html.escape(validated)}<br>"
            f"<b>Against:</b> {html.escape(against)}</p>",
            f'<p class="verdict {"pass" if ok else "fail"}" id="summary-verdict">'
            f"{html.escape(verdict)}</p>",
        ]
        if n:
            title = (f"The {min(n_worst, n)} worst checks" if n > 1 else "The check")
            parts.append(render_table(
                worst[cols], caption=title, passed_column=passed_column,
                table_id="table-summary-worst",
                formats={"tolerance_used_pct": ColumnFormat(
                    "percent", 3, "%", label="share of tolerance used")}
                if "tolerance_used_pct" in cols else None))
        if self.unavailable:
            parts.append("<p>Some stages were not available (listed below); their checks "
                         "are missing from this verdict.</p>")
        parts.append("</section>")
        self.summary_html = "\n".join(parts)
        self.summary_verdict = verdict
        return self

    @property
    def n_passed(self) -> int:
        return sum(self.verdicts)

    @property
    def n_checks(self) -> int:
        return len(self.verdicts)

    def to_html(self) -> str:
        """The whole page as a string."""
        if self.n_checks and self.summary_html:
            # the executive summary carries the verdict; this line counts every table
            summary = (f'<p id="verdict">Pass/fail cells in all tables of this report: '
                       f"{self.n_passed} of {self.n_checks} checks passed</p>")
        elif self.n_checks:
            ok = self.n_passed == self.n_checks
            summary = (
                f'<p class="verdict {"pass" if ok else "fail"}" id="verdict">'
                f"{self.n_passed} of {self.n_checks} checks passed</p>"
            )
        else:
            summary = '<p class="verdict" id="verdict">No pass/fail checks in this report</p>'
        summary = self.summary_html + summary
        if self.unavailable:
            items = "".join(
                f"<li>{html.escape(t)}: {html.escape(r)}</li>" for t, r in self.unavailable
            )
            summary += f'<div class="unavailable">Stages not available:<ul>{items}</ul></div>'
        toc = "<nav><ol>" + "".join(
            f'<li><a href="#{s.anchor}">{html.escape(s.title)}</a></li>' for s in self.sections
        ) + "</ol></nav>"
        body = "\n".join(s.render() for s in self.sections)
        return _PAGE.substitute(title=html.escape(self.title), summary=summary, toc=toc,
                                body=body, table_css=TABLE_CSS)

    def write(self, out_dir: str | Path) -> Path:
        """Write ``out_dir/index.html`` and ``out_dir/tables/<name>.csv``; return the page path."""
        out = Path(out_dir)
        (out / "tables").mkdir(parents=True, exist_ok=True)
        for name, df in self.tables.items():
            show_index = df.index.name is not None or not isinstance(df.index, pd.RangeIndex)
            write_text(out / "tables" / f"{name}.csv", df.to_csv(index=show_index))
        page = out / "index.html"
        write_text(page, self.to_html())
        return page

    def to_pdf(self, out_dir: str | Path, *, chromium: str | None = None,
               timeout: float = 180.0) -> Path:
        """Write the HTML report (:meth:`write`) and print it to ``out_dir/report.pdf``.

        Uses headless Chromium (see :func:`mvtk.report.to_pdf`); raises
        :class:`~mvtk.errors.MissingDependencyError` when it is not installed.
        """
        from ._pdf import to_pdf

        page = self.write(out_dir)
        return to_pdf(page, chromium=chromium, timeout=timeout)
