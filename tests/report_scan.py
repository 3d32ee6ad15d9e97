"""Read a report page back as an engineer would: table headers and cells per column.

Used by the report tests: no header may be a raw field name (no underscore), and a
column shows its numbers in one notation (scientific or fixed) -- for a column of one
quantity (a unit in its header, a damping ratio, a MAC) every number, for a column of
mixed quantities (a check's value) the small numbers below 0.01.
"""

from __future__ import annotations

import html as _html
import re

_SCI = re.compile(r"^-?\d(\.\d+)?e[+-]?\d+$")
_FIX = re.compile(r"^-?\d+(\.\d+)?$")
#: key/value tables: each row its own quantity (text, hashes, parameters)
KEY_VALUE_TABLES = ("table-provenance_parameters", "table-provenance_versions",
                    "table-provenance_inputs", "table-report_signoff")
_HOMOGENEOUS = re.compile(r"\[[^\]]+\]|zeta|MAC|MPC|CoV|COMAC|fraction")


def tables(page: str) -> dict[str, tuple[list[str], list[list[str]]]]:
    """``{table id: (headers, rows of cell texts)}`` of every report table."""
    out = {}
    for m in re.finditer(r'<table class="mvtk" id="([^"]+)">(.*?)</table>', page, re.S):
        tid, body = m.groups()
        heads = [_html.unescape(re.sub(r"<[^>]+>", "", h))
                 for h in re.findall(r"<th[^>]*>(.*?)</th>", body, re.S)]
        rows = [[_html.unescape(re.sub(r"<[^>]+>", "", c))
                 for c in re.findall(r"<td[^>]*>(.*?)</td>", r, re.S)]
                for r in re.findall(r"<tr>(.*?)</tr>", body.split("<tbody>")[-1], re.S)]
        out[tid] = (heads, rows)
    return out


def problems(page: str) -> list[str]:
    """Headers with underscores and columns with two notations, as readable lines."""
    bad = []
    for tid, (heads, rows) in tables(page).items():
        for j, head in enumerate(heads):
            if "_" in head:
                bad.append(f"{tid}: header {head!r} is a raw field name")
            if tid in KEY_VALUE_TABLES:
                continue
            col = [r[j] for r in rows if j < len(r)]
            if not _HOMOGENEOUS.search(head):
                col = [c for c in col if _SCI.match(c) and abs(float(c)) < 1e-2
                       or _FIX.match(c) and 0 < abs(float(c)) < 1e-2]
            sci = [c for c in col if _SCI.match(c)]
            fix = [c for c in col if _FIX.match(c) and c not in ("0", "-0")]
            if sci and fix:
                bad.append(f"{tid}: column {head!r} mixes {sci[0]} and {fix[0]}")
    return bad
