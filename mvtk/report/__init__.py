"""Self-contained HTML reports: sections, tables (also as CSV), figures, provenance."""

from ._html import Report, Section, render_table
from ._provenance import Provenance, collect_provenance, file_sha256

__all__ = ["Report", "Section", "render_table", "Provenance", "collect_provenance",
           "file_sha256"]
