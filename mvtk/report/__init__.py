"""Self-contained HTML reports: sections, tables (also as CSV), figures, provenance, PDF.

Numbers in tables are formatted by quantity (:func:`infer_format`); :func:`html_table`
gives result objects a notebook ``_repr_html_`` with the same formatting.
"""

from .._format import (
    ColumnFormat,
    dict_table,
    format_number,
    format_table,
    infer_format,
    parameter_unit,
)
from .._table import TABLE_CSS, html_table, render_table
from ._html import Report, Section, classify_checks, display_checks, tolerance_used
from ._pdf import PdfExportError, find_chromium, to_pdf
from ._provenance import Provenance, collect_provenance, file_sha256

__all__ = ["Report", "Section", "render_table", "html_table", "tolerance_used",
           "classify_checks", "display_checks", "TABLE_CSS",
           "ColumnFormat", "format_number", "parameter_unit", "format_table", "infer_format",
           "dict_table",
           "to_pdf", "find_chromium", "PdfExportError", "Provenance", "collect_provenance",
           "file_sha256"]
