"""A self-contained HTML report: sections, pandas tables with pass/fail, PNG figures.

The page has no script and no external resource (figures are embedded as base64 PNG,
styles are inline), so it opens offline. Each table is also written as CSV next to
``index.html`` under ``tables/``.
"""

from __future__ import annotations

import base64
import html
import io
import json
import math
import re
from dataclasses import dataclass, field
from pathlib import Path
from string import Template
from typing import Any

import numpy as np
import pandas as pd

from ..errors import ParameterError
from ._provenance import Provenance

__all__ = ["Report", "Section", "render_table"]

_NAME_RE = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.-]{0,80}$")
_PNG_MAGIC = b"\x89PNG\r\n\x1a\n"

_PAGE = Template(
    """<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<title>$title</title>
<style>
body { font-family: system-ui, sans-serif; margin: 2em auto; max-width: 70em;
       padding: 0 1em; color: #222; line-height: 1.4; }
h1 { border-bottom: 2px solid #335; }
h2 { border-bottom: 1px solid #aab; margin-top: 2em; }
table { border-collapse: collapse; margin: 0.8em 0; font-size: 0.92em; }
th, td { border: 1px solid #bbc; padding: 0.25em 0.6em; text-align: right; }
th { background: #eef; }
td.text { text-align: left; }
td.pass { background: #d7f5d7; color: #0a5a0a; font-weight: bold; text-align: center; }
td.fail { background: #fbd5d5; color: #8a0b0b; font-weight: bold; text-align: center; }
caption { caption-side: top; text-align: left; font-weight: bold; padding: 0.3em 0; }
figure { margin: 1em 0; }
figure img { max-width: 100%; border: 1px solid #ddd; }
figcaption { font-size: 0.9em; color: #444; }
.verdict { font-size: 1.2em; padding: 0.5em 1em; border-radius: 4px; display: inline-block; }
.verdict.pass { background: #d7f5d7; } .verdict.fail { background: #fbd5d5; }
.unavailable { background: #fff4d6; border-left: 4px solid #e0a800; padding: 0.5em 1em; }
.synthetic { background: #e8f0ff; border-left: 4px solid #3a6fd8; padding: 0.5em 1em; }
pre { background: #f6f6f8; padding: 0.6em; overflow-x: auto; font-size: 0.85em; }
a.csv { font-size: 0.85em; }
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


def _fmt(value: Any) -> str:
    if isinstance(value, bool | np.bool_):
        return "yes" if value else "no"
    if isinstance(value, float | np.floating):
        v = float(value)
        if math.isnan(v):
            return "–"
        return f"{v:.6g}"
    return str(value)


def render_table(
    df: pd.DataFrame,
    *,
    caption: str = "",
    passed_column: str | None = "passed",
    csv_href: str | None = None,
    table_id: str | None = None,
) -> str:
    """HTML of ``df`` (escaped), with the ``passed_column`` shown as styled PASS/FAIL.

    The index is shown as the first column when it is named or not a default
    RangeIndex.
    """
    show_index = df.index.name is not None or not isinstance(df.index, pd.RangeIndex)
    headers = ([df.index.name or ""] if show_index else []) + [str(c) for c in df.columns]
    parts = [f'<table id="{html.escape(table_id)}">' if table_id else "<table>"]
    if caption or csv_href:
        link = f' <a class="csv" href="{html.escape(csv_href)}">[CSV]</a>' if csv_href else ""
        parts.append(f"<caption>{html.escape(caption)}{link}</caption>")
    parts.append("<thead><tr>" + "".join(f"<th>{html.escape(h)}</th>" for h in headers))
    parts.append("</tr></thead><tbody>")
    for idx, row in zip(df.index, df.itertuples(index=False)):
        cells = []
        if show_index:
            cells.append(f'<td class="text">{html.escape(_fmt(idx))}</td>')
        for col, val in zip(df.columns, row):
            if passed_column is not None and col == passed_column:
                ok = bool(val)
                cls, label = ("pass", "PASS") if ok else ("fail", "FAIL")
                cells.append(f'<td class="{cls}">{label}</td>')
            else:
                cls = ' class="text"' if isinstance(val, str) else ""
                cells.append(f"<td{cls}>{html.escape(_fmt(val))}</td>")
        parts.append("<tr>" + "".join(cells) + "</tr>")
    parts.append("</tbody></table>")
    return "\n".join(parts)


def _png_bytes(figure: Any) -> bytes:
    if isinstance(figure, bytes | bytearray):
        data = bytes(figure)
    elif hasattr(figure, "savefig"):
        buf = io.BytesIO()
        figure.savefig(buf, format="png", dpi=100)
        data = buf.getvalue()
    else:
        raise ParameterError(
            "a report figure must be PNG bytes or a matplotlib Figure, "
            f"got {type(figure).__name__}"
        )
    if not data.startswith(_PNG_MAGIC):
        raise ParameterError("figure bytes are not a PNG image (missing PNG signature)")
    return data


@dataclass
class Section:
    """A titled part of a :class:`Report` holding paragraphs, tables and figures.

    Made by :meth:`Report.section`; the methods return ``self`` so calls chain.
    """

    title: str
    report: Report = field(repr=False)
    blocks: list[str] = field(default_factory=list)
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
    ) -> Section:
        """Add a table; it is also written as ``tables/<name>.csv``.

        Parameters
        ----------
        df : DataFrame
        name : str
            File stem of the CSV; letters, digits, ``_.-``; unique within the report.
        caption : str
        passed_column : str or None
            Boolean column shown as PASS/FAIL and counted in the report's verdict.
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
        self.report.tables[name] = df
        if passed_column is not None and passed_column in df.columns:
            self.report.verdicts.extend(bool(v) for v in df[passed_column])
        else:
            passed_column = None
        self.blocks.append(
            render_table(df, caption=caption, passed_column=passed_column,
                         csv_href=f"tables/{name}.csv", table_id=f"table-{name}")
        )
        return self

    def figure(self, figure: Any, caption: str = "", alt: str | None = None) -> Section:
        """Add a figure (PNG bytes or a matplotlib Figure), embedded as base64."""
        data = _png_bytes(figure)
        b64 = base64.b64encode(data).decode("ascii")
        alt_text = html.escape(alt if alt is not None else caption or self.title)
        self.report.n_figures += 1
        self.blocks.append(
            f'<figure><img class="report-figure" alt="{alt_text}" '
            f'src="data:image/png;base64,{b64}">'
            f"<figcaption>Figure {self.report.n_figures}: {html.escape(caption)}"
            "</figcaption></figure>"
        )
        return self

    def preformatted(self, text: str) -> Section:
        """Add preformatted text (escaped)."""
        self.blocks.append(f"<pre>{html.escape(text)}</pre>")
        return self

    def render(self) -> str:
        return f'<section id="{self.anchor}"><h2>{html.escape(self.title)}</h2>\n' + "\n".join(
            self.blocks
        ) + "</section>"


@dataclass
class Report:
    """Builder of a self-contained HTML report.

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

    def section(self, title: str) -> Section:
        """Append and return a new section."""
        sec = Section(title=title, report=self, anchor=f"s{len(self.sections) + 1}")
        self.sections.append(sec)
        return sec

    def add_provenance(self, provenance: Provenance) -> Section:
        """Append the provenance section (versions, date, input hashes, parameters)."""
        self.provenance = provenance
        sec = self.section("Provenance")
        sec.table(provenance.to_dataframe(), "provenance_versions", "Software and date",
                  passed_column=None)
        if len(provenance.inputs):
            sec.table(provenance.inputs, "provenance_inputs", "Input files (SHA-256)",
                      passed_column=None)
        else:
            sec.text("No input files.")
        if provenance.parameters:
            sec.text("Parameters:")
            sec.preformatted(json.dumps(provenance.parameters, indent=2, sort_keys=True,
                                        default=str))
        return sec

    @property
    def n_passed(self) -> int:
        return sum(self.verdicts)

    @property
    def n_checks(self) -> int:
        return len(self.verdicts)

    def to_html(self) -> str:
        """The whole page as a string."""
        if self.n_checks:
            ok = self.n_passed == self.n_checks
            summary = (
                f'<p class="verdict {"pass" if ok else "fail"}" id="verdict">'
                f"{self.n_passed} of {self.n_checks} checks passed</p>"
            )
        else:
            summary = '<p class="verdict" id="verdict">No pass/fail checks in this report</p>'
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
                                body=body)

    def write(self, out_dir: str | Path) -> Path:
        """Write ``out_dir/index.html`` and ``out_dir/tables/<name>.csv``; return the page path."""
        out = Path(out_dir)
        (out / "tables").mkdir(parents=True, exist_ok=True)
        for name, df in self.tables.items():
            show_index = df.index.name is not None or not isinstance(df.index, pd.RangeIndex)
            df.to_csv(out / "tables" / f"{name}.csv", index=show_index)
        page = out / "index.html"
        page.write_text(self.to_html(), encoding="utf-8")
        return page
