"""A self-contained HTML report: sections, pandas tables with pass/fail, figures.

The page loads nothing from elsewhere: figures are embedded as base64 SVG for line plots
or PNG for raster and very dense ones, styles are inline, and animated mode shapes are a
canvas with inline data and script. It opens offline and prints to PDF
(:func:`mvtk.report.to_pdf`). Table cells are formatted by quantity
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

__all__ = ["Report", "Section", "render_table", "html_table", "tolerance_used", "classify_checks",
           "display_checks",
           "TABLE_CSS"]

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
figure img { display: block; box-sizing: border-box; width: 100%; height: auto;
             border: 1px solid #ddd; }
figcaption { font-size: 0.9em; color: #444; }
.mode-animation .controls { font-size: 0.9em; margin: 0.3em 0; }
.mode-animation .hint { color: #777; }
.animation { margin: 1em 0; break-inside: avoid; }
.animation .caption { font-size: 0.9em; color: #444; margin-top: 0.2em; }
@media print { .mode-animation .controls { display: none; } }
.verdict { font-size: 1.2em; padding: 0.5em 1em; border-radius: 4px; display: inline-block; }
.verdict.pass { background: #d7f5d7; } .verdict.fail { background: #fbd5d5; }
.verdict.reserved { background: #fff0c2; }
.executive { border: 2px solid #335; border-radius: 6px; padding: 0.2em 1em 0.6em;
             margin: 1em 0; }
.executive h2 { margin-top: 0.5em; }
.unavailable { background: #fff4d6; border-left: 4px solid #e0a800; padding: 0.5em 1em; }
.synthetic { background: #e8f0ff; border-left: 4px solid #3a6fd8; padding: 0.5em 1em; }
pre { background: #f6f6f8; padding: 0.6em; overflow-x: auto; font-size: 0.85em; }
a.csv { font-size: 0.85em; font-weight: normal; }
table.signoff { border-collapse: collapse; margin: 0.5em 0 1em; font-size: 0.92em; }
table.signoff th, table.signoff td { border: 1px solid #889; padding: 0.3em 0.7em;
             text-align: left; vertical-align: top; }
table.signoff th { background: #eef; }
table.signoff td.sign { min-width: 12em; height: 2.2em; }
nav.toc ol { padding-left: 1.4em; margin: 0.3em 0; }
nav.toc a { text-decoration: none; color: #224; }
nav.toc a:hover { text-decoration: underline; }
nav.toc .toc-title { font-weight: bold; }
@media screen and (min-width: 1180px) {
  body { margin-left: 17em; max-width: 82em; }
  nav.toc { position: fixed; left: 0; top: 0; bottom: 0; width: 15em; overflow-y: auto;
            padding: 1em 0.8em; background: #f4f5fa; border-right: 1px solid #ccd;
            font-size: 0.9em; box-sizing: border-box; }
}
$page_css
@media print {
  body { margin: 0; max-width: none; padding: 0; font-size: 10pt; }
  nav, a.csv { display: none; }
  h2 { break-after: avoid; }
  .mvtk-table-wrap { overflow: visible; }
  table.mvtk { font-size: 7.5pt; }
  table.mvtk th, table.mvtk td { padding: 0.2em 0.3em; }
  table.mvtk tr, figure, table.signoff { break-inside: avoid; }
  figure img { max-width: 100%; }
  pre { white-space: pre-wrap; overflow-wrap: anywhere; }
}
</style>
</head>
<body>
$toc
<main>
<h1>$title</h1>
$signoff
$summary
$body
</main>
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


def _plural(n: int, word: str, plural: str | None = None) -> str:
    return f"{n} {word if n == 1 else (plural or word + 's')}"


#: a one-sided bound whose tolerance is below this share of its reference is an exact
#: inequality with a round-off allowance (e.g. a Rayleigh-Ritz bound), not a margin
_ROUNDOFF_TOL = 1e-6


def classify_checks(checks: pd.DataFrame, *, error_column: str = "error_pct") -> pd.DataFrame:
    """How each check can be ranked: its category, margin and share of tolerance used.

    Categories:

    * ``graded``: a two-sided tolerance (``±X %``, ``±X unit``) or a one-sided bound
      with slack (``<= ref + X``, ``>= ref - X``, the value away from the limit);
    * ``at limit``: a one-sided bound met exactly at its limit (a saturated actuator);
    * ``yes/no``: a boolean check (value and reference 0 or 1) or a sign check (limit 0);
    * ``exact bound``: an inequality with only a round-off allowance (tolerance below
      1e-6 of the reference).

    ``margin_pct`` is the distance from the value to its nearest limit in percent of
    that limit (negative when failed): comparable between relative, absolute and
    one-sided checks. ``used`` is :func:`tolerance_used` for two-sided checks (``nan``
    for one-sided ones, which have no tolerance band).

    Parameters
    ----------
    checks : DataFrame
        Columns ``tolerance``, ``value``, ``reference`` (as from
        :func:`mvtk.validation.check_table`).
    error_column : str
        Column of the relative error in percent.

    Returns
    -------
    DataFrame
        Columns ``category``, ``margin_pct``, ``used``; one row per check.

    Examples
    --------
    >>> from mvtk.validation import Check, check_table
    >>> t = check_table([Check("f1", 0.9743, 1.0, 0.03, "Hz"),
    ...                  Check("peak voltage", 100.0, 100.0, 0.0, "V", kind="upper")])
    >>> c = classify_checks(t)
    >>> list(c["category"]), round(float(c["margin_pct"][0]), 2)
    (['graded', 'at limit'], 0.44)
    """
    n = len(checks)
    used = tolerance_used(checks, error_column=error_column)

    def num(col):
        if col not in checks.columns:
            return np.full(n, np.nan)
        return pd.to_numeric(checks[col], errors="coerce").to_numpy(dtype=float)

    value, ref = num("value"), num("reference")
    cat = np.array(["graded"] * n, dtype=object)
    margin = np.full(n, np.nan)
    tols = (checks["tolerance"].astype(str).tolist() if "tolerance" in checks.columns
            else [""] * n)
    with np.errstate(divide="ignore", invalid="ignore"):
        for i, tol in enumerate(tols):
            v, r = value[i], ref[i]
            if m := _TOL_BOUND.match(tol):
                t = float(m.group(2))
                upper = m.group(1) == "<="
                limit = r + t if upper else r - t
                if {v, r} <= {0.0, 1.0} or limit == 0.0:
                    cat[i] = "yes/no"
                elif 0 < t < _ROUNDOFF_TOL * abs(r):
                    cat[i] = "exact bound"
                elif abs(v - limit) <= 1e-9 * abs(limit):
                    cat[i] = "at limit"
                margin[i] = 100 * ((limit - v) if upper else (v - limit)) / abs(limit)
                used[i] = np.nan
            elif m := _TOL_REL.match(tol):
                t = float(m.group(1)) / 100
                lo, hi = sorted((r * (1 - t), r * (1 + t)))
                near = lo if abs(v - lo) < abs(v - hi) else hi
                inside = lo <= v <= hi
                margin[i] = (1 if inside else -1) * 100 * abs(v - near) / abs(near)
            elif m := _TOL_ABS.match(tol):
                t = float(m.group(1))
                lo, hi = r - t, r + t
                near = lo if abs(v - lo) < abs(v - hi) else hi
                inside = lo <= v <= hi
                scale = abs(near) if near != 0 else t
                margin[i] = (1 if inside else -1) * 100 * abs(v - near) / scale
    margin[~np.isfinite(margin)] = np.nan
    return pd.DataFrame({"category": cat, "margin_pct": margin, "used": used})


def display_checks(checks: pd.DataFrame, *, error_column: str = "error_pct") -> pd.DataFrame:
    """The checks as an engineer reads them: the criterion written out, a deviation only
    where a relative error means something, and the margin to the limit.

    ``<= ref + 0 V`` becomes ``≤ 100 V``; a relative check keeps ``±3 %`` and its
    ``deviation`` (the relative error in percent); the deviation of a one-sided bound (a
    MAC, a damping floor, a stability sign) is left empty: the margin says how far the
    value is from failing (:func:`classify_checks`).

    Parameters
    ----------
    checks : DataFrame
        As from :func:`mvtk.validation.check_table`.
    error_column : str
        Column of the relative error in percent.

    Returns
    -------
    DataFrame
        Columns ``check, value, reference, unit, criterion, deviation_pct, margin_pct``
        and the remaining ones of ``checks`` (``source``, ``passed``) when present.

    Examples
    --------
    >>> from mvtk.validation import Check, check_table
    >>> t = check_table([Check("peak voltage", 93.5, 100.0, 0.0, "V", kind="upper")])
    >>> display_checks(t)["criterion"][0]
    '≤ 100 V'
    """
    from .._format import format_number

    cls = classify_checks(checks, error_column=error_column)
    out = pd.DataFrame(index=range(len(checks)))
    src = checks.reset_index(drop=True)
    for c in ("check", "value", "reference", "unit"):
        if c in src.columns:
            out[c] = src[c]
    crit, dev = [], []
    err = (pd.to_numeric(src[error_column], errors="coerce") if error_column in src.columns
           else pd.Series(np.nan, index=src.index))
    for i, tol in enumerate(src.get("tolerance", pd.Series([""] * len(src))).astype(str)):
        unit = str(src["unit"][i]) if "unit" in src.columns and pd.notna(src["unit"][i]) else ""
        if m := _TOL_BOUND.match(tol):
            r = float(pd.to_numeric(src["reference"][i], errors="coerce"))
            t = float(m.group(2))
            limit = r + t if m.group(1) == "<=" else r - t
            if cls["category"][i] == "exact bound":
                limit = r
            op = "≤" if m.group(1) == "<=" else "≥"
            crit.append(f"{op} {format_number(limit, 6)} {unit}".rstrip())
            dev.append(np.nan)
        elif _TOL_REL.match(tol):
            crit.append(tol.strip())
            dev.append(float(err[i]))
        else:
            crit.append(tol.strip())
            dev.append(np.nan)
    out["criterion"] = crit
    out["deviation_pct"] = dev
    out["margin_pct"] = cls["margin_pct"].to_numpy()
    for c in ("source", "passed"):
        if c in src.columns:
            out[c] = src[c]
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
        # a column with no value in any row says nothing on the page (the CSV keeps it)
        empty = [c for c in df.columns if c != passed_column and len(df) and all(
            v is None or (isinstance(v, str) and not v.strip())
            or (isinstance(v, float) and v != v) for v in df[c].tolist())]
        shown = df.drop(columns=empty) if empty else df
        if formats is not None:
            formats = {k: v for k, v in formats.items() if k not in empty}
        try:
            block = render_table(shown, caption=caption, passed_column=passed_column,
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

    def mode_animation(self, xyz: Any, shapes: Any, labels: list[str], caption: str = "",
                       **kwargs: Any) -> Section:
        """Add animated 3-D mode shapes (a canvas with inline data and script: plays
        offline, no library); arguments as :func:`mvtk.plot.mode_animation_html`.

        A printed page shows the first frame.
        """
        from ..plot import mode_animation_html

        self.report.n_animations += 1
        block = mode_animation_html(xyz, shapes, labels,
                                    element_id=f"mode-animation-{self.report.n_animations}",
                                    **kwargs)
        self.blocks.append(f'<div class="animation">{block}<p class="caption">Animation '
                           f"{self.report.n_animations}: {html.escape(caption)}</p></div>")
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
    n_animations: int = 0
    provenance: Provenance | None = None
    summary_html: str = ""
    summary_verdict: str = ""
    document: dict[str, str] = field(default_factory=dict)
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
        warnings: list[str] | tuple[str, ...] = (),
        inconsistencies: list[str] | tuple[str, ...] = (),
    ) -> Report:
        """Put an executive summary at the top of the page.

        The summary says what was validated and against what, gives the verdict and
        lists the ``n_worst`` graded checks closest to failing (failed ones first, then
        by the smallest margin to their limit, see :func:`classify_checks`); yes/no
        checks, exact bounds and one-sided bounds met at their limit (a saturated
        actuator) are listed apart, as are the stage ``warnings`` and the
        ``inconsistencies`` between sections. Calling it again replaces the summary.
        The checks are not added to the report's count; add the full table with
        :meth:`Section.table`.

        Verdict: ``FAIL`` when a check failed; ``PASS WITH RESERVATIONS`` when every
        check passed but there are warnings, inconsistencies, unavailable stages or
        checks met only at their limit; ``PASS`` otherwise; ``NO VERDICT`` without
        checks.

        Parameters
        ----------
        checks : DataFrame
            One row per check with a boolean ``passed_column`` (e.g.
            :func:`mvtk.validation.check_table`).
        validated : str
            What was validated (e.g. ``"FE model of the plate, damping, SE"``).
        against : str
            The references (e.g. ``"impact test, study tolerances"``).
        n_worst : int
            Number of graded checks listed (>= 1).
        passed_column, error_column, name_column : str
            Columns of ``checks``; ``error_column`` may be absent.
        columns : list of str, optional
            Columns of the closest-checks table (default: name, value, reference, unit,
            tolerance, margin, share of tolerance used, passed when present).
        warnings : list of str
            Warnings raised by the stages (resolution, identification, ...).
        inconsistencies : list of str
            Disagreements between sections (e.g. one mode's frequency from two tests).

        Examples
        --------
        >>> from mvtk.validation import Check, check_table
        >>> rep = Report("Plate")
        >>> checks = check_table([Check("f1", 28.9, 28.2, 0.03, "Hz"),
        ...                       Check("f2", 69.0, 69.1, 0.03, "Hz")])
        >>> rep.executive_summary(checks, validated="FE model", against="impact test",
        ...                       warnings=["mode 2: 4 lines in the half-power band"]
        ...                       ).summary_verdict
        'PASS WITH RESERVATIONS: all 2 checks passed, 1 warning'
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
        missing = [c for c in (columns or []) if c not in checks.columns]
        if missing:
            raise ParameterError(f"executive_summary: columns {missing} are not in the "
                                 "checks table")
        passed = checks[passed_column].astype(bool).to_numpy()
        n, n_ok = len(checks), int(passed.sum())
        cls = classify_checks(checks, error_column=error_column)
        table = checks.reset_index(drop=True).copy()
        if "tolerance" in table.columns and "value" in table.columns:
            table["tolerance"] = display_checks(checks, error_column=error_column)[
                "criterion"].to_numpy()
        table["margin_pct"] = cls["margin_pct"].to_numpy()
        table["tolerance_used_pct"] = 100.0 * cls["used"].to_numpy()
        graded = (cls["category"] == "graded").to_numpy()
        order = pd.DataFrame({"failed": ~passed, "margin": cls["margin_pct"].to_numpy(),
                              "pos": np.arange(n)})
        order = order[graded | ~passed].sort_values(
            ["failed", "margin", "pos"], ascending=[False, True, True], na_position="last")
        worst = table.iloc[order["pos"].to_numpy()[:n_worst]].reset_index(drop=True)
        default = [name_column, "value", "reference", "unit", "tolerance", "margin_pct",
                   "tolerance_used_pct", passed_column]
        cols = [c for c in (columns or default) if c in worst.columns]
        if "tolerance_used_pct" in cols and not worst["tolerance_used_pct"].notna().any():
            cols.remove("tolerance_used_pct")
        apart = table[(~graded) & passed]
        at_limit = apart[(cls["category"] == "at limit").to_numpy()[(~graded) & passed]]
        n_res = len(at_limit) + len(warnings) + len(inconsistencies) + len(self.unavailable)
        ok = n > 0 and n_ok == n
        if n == 0:
            verdict = "NO VERDICT: no check could be evaluated"
        elif not ok:
            verdict = f"FAIL: {n - n_ok} of {n} checks failed"
        elif n_res:
            why = []
            if len(at_limit):
                why.append(f"{len(at_limit)} met only at the limit")
            if warnings:
                why.append(_plural(len(warnings), "warning"))
            if inconsistencies:
                why.append(_plural(len(inconsistencies), "inconsistency", "inconsistencies"))
            if self.unavailable:
                why.append(_plural(len(self.unavailable), "stage") + " not available")
            verdict = f"PASS WITH RESERVATIONS: all {n} checks passed, " + ", ".join(why)
        else:
            verdict = f"PASS: all {n} checks passed"
        css = "fail" if not ok else ("reserved" if n_res else "pass")
        parts = [
            '<section class="executive" id="executive-summary"><h2>Executive summary</h2>',
            f"<p><b>Validated:</b> {html.escape(validated)}<br>"
            f"<b>Against:</b> {html.escape(against)}</p>",
            f'<p class="verdict {css}" id="summary-verdict">{html.escape(verdict)}</p>',
        ]
        fmt = {"tolerance_used_pct": ColumnFormat("percent", 3, "%",
                                                  label="share of tolerance used"),
               "margin_pct": ColumnFormat("percent", 3, "%", label="margin to the limit"),
               "tolerance": ColumnFormat("text", label="criterion")}
        if len(worst):
            title = (f"The {len(worst)} graded checks closest to failing (margin: distance "
                     "of the value to its nearest limit, in % of that limit)"
                     if len(worst) > 1 else "The graded check closest to failing")
            parts.append(render_table(
                worst[cols], caption=title, passed_column=passed_column,
                table_id="table-summary-worst",
                formats={k: v for k, v in fmt.items() if k in cols}))
        if len(apart):
            acols = [c for c in (name_column, "value", "reference", "unit", "tolerance",
                                 passed_column) if c in apart.columns]
            kinds = cls["category"].to_numpy()[(~graded) & passed]
            shown = apart[acols].reset_index(drop=True)
            shown.insert(1, "kind", kinds)
            parts.append(render_table(
                shown, caption="Yes/no checks, exact bounds and bounds met at their limit "
                "(no margin to rank)", passed_column=passed_column,
                table_id="table-summary-apart",
                formats={"tolerance": fmt["tolerance"]} if "tolerance" in acols else None))
        if warnings:
            items = "".join(f"<li>{html.escape(str(w))}</li>" for w in warnings)
            parts.append(f'<div class="unavailable" id="summary-warnings"><b>Warnings '
                         f"({len(warnings)})</b><ul>{items}</ul></div>")
        if inconsistencies:
            items = "".join(f"<li>{html.escape(str(w))}</li>" for w in inconsistencies)
            parts.append(f'<div class="unavailable" id="summary-inconsistencies"><b>'
                         f"Inconsistencies between sections ({len(inconsistencies)})</b>"
                         f"<ul>{items}</ul></div>")
        if self.unavailable:
            parts.append("<p>Some stages were not available (listed below); their checks "
                         "are missing from this verdict.</p>")
        parts.append("</section>")
        self.summary_html = "\n".join(parts)
        self.summary_verdict = verdict
        return self

    def set_document(self, **fields: str | None) -> Report:
        """Make the report a controlled document: a title block with sign-off lines and,
        in the PDF, a running header and footer with page numbers.

        Parameters
        ----------
        **fields : str
            Any of ``document_number, revision, date, author, reviewer, approver,
            organisation`` (``None`` or empty: left out; an empty sign-off line is still
            printed for the author, reviewer and approver to sign).

        Examples
        --------
        >>> rep = Report("Validation report: plate").set_document(
        ...     document_number="VR-7", revision="B", author="A. Engineer")
        >>> "VR-7" in rep.to_html() and "Page" in rep.to_html()
        True
        """
        known = ("document_number", "revision", "date", "author", "reviewer", "approver",
                 "organisation")
        unknown = [k for k in fields if k not in known]
        if unknown:
            raise ParameterError(f"set_document: unknown fields {unknown}; accepted: "
                                 f"{list(known)}")
        self.document = {k: str(v) for k, v in fields.items() if v not in (None, "")}
        return self

    def _signoff_html(self) -> str:
        d = self.document
        if not d:
            return ""
        e = html.escape
        ident = [("Document number", d.get("document_number", "–")),
                 ("Revision", d.get("revision", "–")), ("Date", d.get("date", "–"))]
        if "organisation" in d:
            ident.append(("Organisation", d["organisation"]))
        head = "".join(f"<th>{e(k)}</th>" for k, _ in ident)
        vals = "".join(f"<td>{e(v)}</td>" for _, v in ident)
        rows = "".join(
            f"<tr><th>{e(role)}</th><td>{e(d.get(key, ''))}</td>"
            '<td class="sign"></td><td class="sign"></td></tr>'
            for role, key in (("Prepared by", "author"), ("Reviewed by", "reviewer"),
                              ("Approved by", "approver")))
        return ('<section class="signoff" id="report-signoff">'
                f'<table class="signoff"><tr>{head}</tr><tr>{vals}</tr></table>'
                '<table class="signoff"><tr><th>Role</th><th>Name</th><th>Signature</th>'
                f"<th>Date</th></tr>{rows}</table></section>")

    def _page_css(self) -> str:
        """Print header and footer (CSS page margin boxes; Chromium >= 131)."""
        def css_str(text: str) -> str:
            return '"' + text.replace("\\", "\\\\").replace('"', '\\"').replace(
                "\n", " ").replace("<", "\\3C ") + '"'

        d = self.document
        ident = " ".join(x for x in (d.get("document_number", ""),
                                     f"rev. {d['revision']}" if "revision" in d else "")
                         if x)
        right = ident or (self.provenance.created_utc[:10] if self.provenance else "")
        left = self.title if len(self.title) <= 90 else self.title[:87] + "..."
        return ("@page { size: A4; margin: 18mm 12mm 16mm 12mm;\n"
                f"  @top-left {{ content: {css_str(left)}; font-size: 8pt; color: #555; }}\n"
                f"  @top-right {{ content: {css_str(right)}; font-size: 8pt; color: #555; }}\n"
                f"  @bottom-left {{ content: {css_str(self.summary_verdict.split(':')[0])};"
                " font-size: 8pt; color: #555; }\n"
                '  @bottom-right { content: "Page " counter(page) " of " counter(pages); '
                "font-size: 8pt; color: #555; }\n}")

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
        first = ('<li><a href="#executive-summary">Executive summary</a></li>'
                 if self.summary_html else "")
        toc = ('<nav class="toc"><div class="toc-title">Contents</div><ol>' + first + "".join(
            f'<li><a href="#{s.anchor}">{html.escape(s.title)}</a></li>' for s in self.sections
        ) + "</ol></nav>")
        body = "\n".join(s.render() for s in self.sections)
        return _PAGE.substitute(title=html.escape(self.title), summary=summary, toc=toc,
                                body=body, table_css=TABLE_CSS, signoff=self._signoff_html(),
                                page_css=self._page_css())

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
