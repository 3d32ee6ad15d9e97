"""HTML tables formatted by quantity: the report's tables and the notebook reprs.

A floor-1 leaf (see ``docs/architecture.md``): stage packages use :func:`html_table` for
their ``_repr_html_`` without importing :mod:`mvtk.report`.
"""

from __future__ import annotations

import html
from collections.abc import Mapping
from typing import Any

import pandas as pd

from ._format import FormatSpec, format_number, format_table
from .errors import ParameterError

__all__ = ["TABLE_CSS", "html_table", "render_table", "table_html"]

#: Table styles shared by the report page and the notebook reprs (:func:`html_table`).
TABLE_CSS = """
.mvtk-table-wrap { max-width: 100%; overflow-x: auto; margin: 0.8em 0; }
table.mvtk { border-collapse: collapse; font-size: 0.88em;
             font-variant-numeric: tabular-nums; }
table.mvtk th, table.mvtk td { border: 1px solid #bbc; padding: 0.25em 0.45em;
             text-align: right; vertical-align: top; }
table.mvtk th { background: #eef; vertical-align: bottom; }
table.mvtk th.text { text-align: left; }
table.mvtk td { white-space: nowrap; }
table.mvtk td.text { text-align: left; white-space: normal; overflow-wrap: break-word;
             hyphens: auto; min-width: 3em; max-width: 32em; }
table.mvtk td.pass { background: #d7f5d7; color: #0a5a0a; font-weight: bold;
             text-align: center; }
table.mvtk td.fail { background: #fbd5d5; color: #8a0b0b; font-weight: bold;
             text-align: center; }
table.mvtk caption { caption-side: top; text-align: left; font-weight: bold;
             padding: 0.3em 0; }
"""


def _fmt(value: Any) -> str:
    return format_number(value, digits=6)


def table_html(
    df: pd.DataFrame,
    *,
    caption: str,
    passed_column: str | None,
    csv_href: str | None,
    table_id: str | None,
    formats: Mapping[Any, FormatSpec] | None,
    show_index: bool | None = None,
) -> str:
    if passed_column is not None and passed_column not in df.columns:
        passed_column = None
    if show_index is None:
        show_index = df.index.name is not None or not isinstance(df.index, pd.RangeIndex)
    fmt_df = df.drop(columns=[passed_column]) if passed_column is not None else df
    headers, cells = format_table(fmt_df, formats)
    by_col = dict(zip(fmt_df.columns, zip(*cells))) if len(df) else {}
    idx_hdr = [html.escape(str(df.index.name or ""))] if show_index else []
    parts = ['<div class="mvtk-table-wrap">']
    parts.append(f'<table class="mvtk" id="{html.escape(table_id)}">' if table_id
                 else '<table class="mvtk">')
    if caption or csv_href:
        link = f' <a class="csv" href="{html.escape(csv_href)}">[CSV]</a>' if csv_href else ""
        parts.append(f"<caption>{html.escape(caption)}{link}</caption>")
    hdr_by_col = dict(zip(fmt_df.columns, headers))
    # headers may break after "_" (zeta Rayleigh (least_squares)) to keep columns narrow
    ths = [(h, True) for h in idx_hdr] + [
        (html.escape(hdr_by_col.get(c, str(c))).replace("_", "_<wbr>"),
         len(df) > 0 and all(isinstance(v, str) for v in df[c].tolist()))
        for c in df.columns]
    parts.append("<thead><tr>" + "".join(
        f'<th class="text">{h}</th>' if is_text else f"<th>{h}</th>" for h, is_text in ths)
        + "</tr></thead>")
    parts.append("<tbody>")
    for i, (idx, row) in enumerate(zip(df.index, df.itertuples(index=False))):
        tds = []
        if show_index:
            tds.append(f'<td class="text">{html.escape(_fmt(idx))}</td>')
        for col, val in zip(df.columns, row):
            if col == passed_column:
                ok = bool(val)
                cls, label = ("pass", "PASS") if ok else ("fail", "FAIL")
                tds.append(f'<td class="{cls}">{label}</td>')
            else:
                cls = ' class="text"' if isinstance(val, str) else ""
                tds.append(f"<td{cls}>{html.escape(by_col[col][i])}</td>")
        parts.append("<tr>" + "".join(tds) + "</tr>")
    parts.append("</tbody></table></div>")
    return "\n".join(parts)


def render_table(
    df: pd.DataFrame,
    *,
    caption: str = "",
    passed_column: str | None = "passed",
    csv_href: str | None = None,
    table_id: str | None = None,
    formats: Mapping[Any, FormatSpec] | None = None,
) -> str:
    """HTML of ``df`` (escaped, numbers formatted by quantity) in a horizontal scroll box.

    Parameters
    ----------
    df : DataFrame
        The index is shown as the first column when it is named or not a default
        RangeIndex.
    caption : str
    passed_column : str or None
        Boolean column shown as styled PASS/FAIL (ignored when absent).
    csv_href : str, optional
        Link to the CSV of the table, shown in the caption.
    table_id : str, optional
        ``id`` of the ``<table>`` element.
    formats : mapping of column to ColumnFormat, int or callable, optional
        Per-column overrides of the formatting inferred from the column names (see
        :func:`mvtk.report.infer_format`); an int is a number of significant digits.
    """
    if not isinstance(df, pd.DataFrame):
        raise ParameterError(f"render_table expects a pandas DataFrame, got {type(df).__name__}")
    return table_html(df, caption=caption, passed_column=passed_column, csv_href=csv_href,
                       table_id=table_id, formats=formats)


def html_table(
    df: pd.DataFrame,
    *,
    caption: str = "",
    passed_column: str | None = "passed",
    formats: Mapping[Any, FormatSpec] | None = None,
    max_rows: int = 60,
) -> str:
    """A table for a notebook ``_repr_html_``, formatted exactly as in the report.

    Self-contained (carries its own ``<style>``), long tables are cut to the first and
    last ``max_rows // 2`` rows with a note of how many were left out.

    Examples
    --------
    >>> class DampingResult:                      # doctest: +SKIP
    ...     def _repr_html_(self):
    ...         return html_table(self.to_dataframe(), caption="Damping per mode")
    """
    if not isinstance(df, pd.DataFrame):
        raise ParameterError(f"html_table expects a pandas DataFrame, got {type(df).__name__}")
    if max_rows < 2:
        raise ParameterError(f"max_rows must be >= 2, got {max_rows}")
    note = ""
    show_index = df.index.name is not None or not isinstance(df.index, pd.RangeIndex)
    if len(df) > max_rows:
        half = max_rows // 2
        note = (f'<p style="font-size:0.85em;color:#555">{len(df) - 2 * half} of '
                f"{len(df)} rows not shown</p>")
        df = pd.concat([df.iloc[:half], df.iloc[-half:]])
    body = table_html(df, caption=caption, passed_column=passed_column, csv_href=None,
                       table_id=None, formats=formats, show_index=show_index)
    return f"<div><style>{TABLE_CSS}</style>{body}{note}</div>"
