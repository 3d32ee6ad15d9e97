"""A Nastran bulk-data subset read without pyNastran.

Why not pyNastran: its current release (1.4.1) requires ``numpy < 2`` and fails to import
under numpy 2 (``np.in1d`` was removed), while mvtk's pandas needs numpy >= 2. The
subset below is small enough to read directly.

Formats (:func:`read_bulk_cards`): small field (8 columns), large field (``NAME*``, 16
columns, half lines joined in pairs) and free field (commas), mixed within a card, with
explicit (``+``/``*`` in field 1) and implicit (blank field 1) continuations. Each line
is padded to its full width before the next is appended, so every field lands at the
position the format defines. Field 10 of a line is the continuation marker; on a
free-field line it is taken as a marker only when blank or ``+``/``*``-prefixed, otherwise
it and any fields after it are data (a long free-field line). Nothing beyond column 80
of a fixed-field line is dropped silently (refused). Only the bulk data section is read
(after ``BEGIN BULK`` when present, up to ``ENDDATA``); ``INCLUDE 'file'`` is read in
place; ``SPC = n`` of the case control selects the SPC set.

Cards and their meaning here (every other card is refused, all listed by name and count;
``PARAM``, ``EIGRL``, ``EIGR``, ``MDLPRM`` are ignored and counted in
``meta["nastran"]["ignored"]``):

- ``GRID ID CP X1 X2 X3 CD PS``: ``CP``/``CD`` any ``CORD2R/C/S``; the DOFs of a grid
  with ``CD`` are in that system's axes at the grid (radial, tangential, axial for a
  cylindrical one), and so are its SPCs, springs and ``CBAR`` vectors.
- ``CORD2R / CORD2C / CORD2S CID RID A B C`` (chains through RID allowed).
- ``CQUAD4 / CTRIA3 EID PID G1..G4 THETA|MCID ZOFFS``: MITC4 / MITC3 shells. Ply angles of
  a ``PCOMP`` are measured from the G1-G2 edge rotated by ``THETA`` about the normal, or
  from the projected x axis of ``MCID`` (Nastran uses the G1-G2 edge for triangles and
  a diagonal-bisector axis for quadrilaterals: the two agree for rectangles).
- ``PSHELL PID MID1 T MID2 12I/T^3 MID3 TS/T NSM``: homogeneous shells (MID2, MID3 = MID1
  or blank, 12I/T^3 = 1 or blank, NSM = 0); ``TS/T`` is the shear correction (5/6);
  transverse shear always from MID1 (a blank MID3, Kirchhoff in Nastran, differs only
  by the shear flexibility of thick shells).
- ``PCOMP PID Z0 NSM ... LAM`` + plies ``MID T THETA``; ``LAM = SYM`` mirrors the plies.
- ``MAT1 MID E G NU RHO`` (two of E, G, NU; all three kept when given),
  ``MAT8 MID E1 E2 NU12 G12 G1Z G2Z RHO``; structural damping ``GE`` is kept in
  ``meta["nastran"]["damping"]``, not applied to ``M``, ``K``.
- ``CBAR / CBEAM EID PID GA GB X1 X2 X3|G0 OFFT PA PB WA WB``: Timoshenko beams with the
  orientation vector ``v`` (in the displacement system of GA); offsets ``WA = WB``;
  ``OFFT`` blank or ``GGG``; pin flags must be blank.
- ``PBAR PID MID A I1 I2 J NSM`` (+ K1 K2 on the third line; blank or 0 K = shear-rigid,
  modelled by a shear factor of 1e6), ``PBARL``/``PBEAML PID MID GROUP TYPE`` with
  ``TYPE`` ``BAR``, ``ROD``, ``TUBE``, ``BOX``, ``I`` (Nastran dimension order; PBEAML with
  equal stations), ``PBEAM PID MID A I1 I2 I12 J NSM`` (constant section; K1, K2 default
  1.0). ``I1`` bends in plane 1 (local x-y, about local z): ``Iz``. NSM adds mass per
  length.
- ``CONM2 EID G CID M X1 X2 X3 / I11 I21 I22 I31 I32 I33`` (``CID`` -1, 0 or a system;
  inertia matrix ``[[I11, -I21, -I31], [-I21, I22, -I32], [-I31, -I32, I33]]`` about the
  mass centre, in ``CID``).
- ``CELAS1 EID PID G1 C1 G2 C2`` + ``PELAS PID K``; ``CELAS2 EID K G1 C1 G2 C2``
  (grounded, or between the same component of two nodes).
- ``SPC1 SID C G1 G2 ... | G1 THRU G2`` (grids of a THRU range that do not exist are
  skipped, as in Nastran), ``SPC SID G C 0.0``, ``SPCADD``; with several sets choose one
  (``spc_id`` or ``SPC =`` in the case control).
- ``RBE2 EID GN CM GM1 ... [ALPHA]`` (rigid link), ``RBE3 EID - REFGRID 123456 WT1 123
  G1,1 ...`` (weighted interpolation, translations of the independent grids).
- Static loads, kept as nodal forces in ``meta["load_cases"]`` by set id (``"10"``),
  the case control's ``LOAD =`` in ``meta["nastran"]["load_id"]``: ``FORCE``/``MOMENT
  SID G CID F N1 N2 N3`` (the vector in the CID axes at the grid), ``PLOAD2 SID P EIDs |
  EID1 THRU EID2`` and uniform ``PLOAD4 SID EID P [THRU EID2]`` on CQUAD4/CTRIA3 (along
  the element normal), ``GRAV SID CID A N1 N2 N3`` (from the consistent mass) and
  ``LOAD SID S S1 L1 ...``.

"""

from __future__ import annotations

import re
from collections import defaultdict
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import FormatError, MvtkError, ParameterError
from ._frames import CoordinateSystem
from ._general import BeamSet, PointMass, RigidLink, ShellSet, Spring, assemble_model
from ._laminate import Laminate
from ._materials import IsotropicMaterial, OrthotropicMaterial, Ply
from ._model import DOF_NAMES, FEModel
from ._sections import (
    box_section,
    generic_section,
    i_section,
    rectangle_section,
    tube_section,
)

__all__ = ["read_nastran", "read_bulk_cards"]

_IGNORED = {"PARAM", "EIGRL", "EIGR", "MDLPRM"}
_SUPPORTED = {"GRID", "CORD2R", "CORD2C", "CORD2S", "CQUAD4", "CTRIA3", "PSHELL", "PCOMP",
              "MAT1", "MAT8", "CBAR", "CBEAM", "PBAR", "PBARL", "PBEAM", "PBEAML", "CONM2",
              "CELAS1", "CELAS2", "PELAS", "SPC1", "SPC", "SPCADD", "RBE2", "RBE3",
              "FORCE", "MOMENT", "GRAV", "PLOAD2", "PLOAD4", "LOAD"}
_REAL = re.compile(r"^([+-]?(?:\d+\.?\d*|\.\d+))([+-]\d+)$")
_INT = re.compile(r"^[+-]?\d+$")


class _Card(list):
    """Data fields of one card (name and continuation markers excluded).

    Field ``i`` is Nastran field ``i % 8 + 2`` of the card's logical line ``i // 8 + 1``
    (large-field half lines are joined in pairs, as the format defines).
    """

    def __init__(self, name: str, fields: list[str], where: str, lines: list[str]):
        super().__init__(fields)
        self.name = name
        self.where = where
        self.lines = lines  # source position of each field

    def _raw(self, i: int) -> str:
        return self[i].strip() if i < len(self) else ""

    def _at(self, i: int, what: str) -> str:
        where = self.lines[i] if i < len(self.lines) else self.where
        line = f" of continuation {i // 8}" if i >= 8 else ""
        return f"{where}: {self.name} field {i % 8 + 2}{line} ({what})"

    def blank(self, i: int) -> bool:
        return not self._raw(i)

    def is_int(self, i: int) -> bool:
        return bool(_INT.match(self._raw(i)))

    def int(self, i: int, default: int | None = None, what: str = "") -> int:
        s = self._raw(i)
        if not s:
            if default is None:
                raise FormatError(f"{self._at(i, what)} is required")
            return default
        if not _INT.match(s):
            raise FormatError(f"{self._at(i, what)}: expected an integer, got {s!r}")
        return int(s)

    def real(self, i: int, default: float | None = None, what: str = "") -> float:
        s = self._raw(i).upper().replace("D", "E")
        if not s:
            if default is None:
                raise FormatError(f"{self._at(i, what)} is required")
            return default
        m = _REAL.match(s)
        if m:
            s = f"{m.group(1)}E{m.group(2)}"
        try:
            return float(s)
        except ValueError:
            raise FormatError(f"{self._at(i, what)}: expected a real number, got "
                              f"{self._raw(i)!r}") from None

    def text(self, i: int) -> str:
        return self._raw(i).upper()


def _is_marker(field: str) -> bool:
    """A continuation field: blank or a ``+``/``*`` marker."""
    f = field.strip()
    return not f or f[0] in "+*"


def _line_fields(line: str, where: str) -> tuple[str, list[str], int]:
    """(field 1, data fields, data fields per logical half or full line)."""
    if "," in line:  # free field
        parts = [p.strip() for p in line.split(",")]
        first, data = parts[0], parts[1:]
        cap = 4 if first.endswith("*") or first.startswith("*") else 8
        if len(data) > cap:
            # field 10 is the continuation field when it holds a marker (blank or
            # +/*-prefixed): drop it and go on with the next logical line; a value
            # there means the line simply continues (every field is data)
            out: list[str] = []
            rest = data
            while len(rest) > cap and _is_marker(rest[cap]):
                out += rest[:cap]
                rest = rest[cap + 1:]
                if rest:  # the next logical line starts on a field boundary
                    out += [""] * (-len(out) % cap)
            data = out + rest
        return first, data, cap
    if len(line) > 80 and line[80:].strip():
        raise FormatError(f"{where}: characters beyond column 80 in a fixed-field line "
                          f"({line[80:].strip()!r}); fixed-field data ends at column 72 "
                          "(73-80 hold the continuation marker)")
    first = line[:8].strip()
    cap = 4 if first.endswith("*") or first.startswith("*") else 8
    w = 64 // cap
    body = line[8:72].ljust(64)
    return first, [body[k:k + w].strip() for k in range(0, 64, w)], cap


def _read_lines(path: Path, depth: int = 0) -> tuple[list[tuple[str, str]], list[str]]:
    """Bulk-data lines ``(where, text)`` (INCLUDEs expanded) and case-control lines."""
    if depth > 10:
        raise FormatError(f"{path}: INCLUDE nested more than 10 deep")
    try:
        text = path.read_text(errors="replace")
    except OSError as err:
        raise FormatError(f"Nastran file {str(path)!r} cannot be read: {err}") from err
    lines = text.splitlines()
    start, case = 0, []
    if depth == 0:
        for i, line in enumerate(lines):
            if line.strip().upper().startswith("BEGIN BULK"):
                start, case = i + 1, lines[:i]
                break
    out: list[tuple[str, str]] = []
    for no, raw in enumerate(lines[start:], start=start + 1):
        line = raw.split("$")[0].rstrip().expandtabs(8)
        if not line.strip():
            continue
        head = line.strip().upper()
        if head.startswith("ENDDATA"):
            break
        if head.startswith("INCLUDE"):
            m = re.match(r"^\s*INCLUDE\s+'([^']+)'\s*$", line, re.I)
            if not m:
                raise FormatError(f"{path} line {no}: INCLUDE must name one quoted file on "
                                  "one line: INCLUDE 'file'")
            inc = (path.parent / m.group(1)).resolve()
            if not inc.exists():
                raise FormatError(f"{path} line {no}: included file {str(inc)!r} not found")
            out += _read_lines(inc, depth + 1)[0]
            continue
        out.append((f"{path} line {no}", line))
    return out, case


def read_bulk_cards(path: str | Path) -> list[_Card]:
    """Every bulk-data card of a Nastran deck as its list of data fields.

    Free field (commas), small field (8 columns) and large field (``NAME*``, 16
    columns) lines, mixed within a card, with explicit (``+``/``*`` in field 1) and
    implicit (blank field 1) continuations. Each line is padded to its full width
    before the next one is appended, so a field's position is the one the format
    defines: field ``i`` of the result is field ``i % 8 + 2`` of logical line
    ``i // 8 + 1``. Continuation markers (field 10 of a line, field 1 of a
    continuation) are dropped; on a free-field line the tenth field is a marker only
    when blank or ``+``/``*``-prefixed, otherwise it and the fields after it are data.
    ``INCLUDE 'file'`` is read in place (relative to the including file).

    Parameters
    ----------
    path : path

    Returns
    -------
    list
        Cards with ``name``, ``where`` (file and line), the data fields as stripped
        strings and ``lines`` (the source line of each field).

    Raises
    ------
    FormatError
        A continuation without a card, text beyond column 80 of a fixed-field line, an
        unreadable INCLUDE; the message names the file and line.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> deck = pathlib.Path(tempfile.mkdtemp()) / "spring.bdf"
    >>> _ = deck.write_text("BEGIN BULK\\nGRID,1,,0.,0.,0.\\nCELAS2,20,1.0e5,1,3\\nENDDATA\\n")
    >>> [(card.name, list(card)) for card in read_bulk_cards(deck)]
    [('GRID', ['1', '', '0.', '0.', '0.']), ('CELAS2', ['20', '1.0e5', '1', '3'])]
    """
    path = Path(path)
    if not path.exists():
        raise FormatError(f"Nastran file {str(path)!r} not found")
    return _cards_of(_read_lines(path)[0])


def _cards_of(lines: list[tuple[str, str]]) -> list[_Card]:
    cards: list[_Card] = []
    for where, line in lines:
        first, data, cap = _line_fields(line, where)
        is_cont = not first or first[0] in "+*"
        if is_cont:
            if not cards:
                raise FormatError(f"{where}: continuation line without a card")
            card = cards[-1]
            pad = -len(card) % cap
        else:
            card = _Card(first.rstrip("*").strip().upper(), [], where, [])
            cards.append(card)
            pad = 0
        card.extend([""] * pad + data + [""] * (-len(data) % cap))
        card.lines.extend([where] * (pad + len(data) + (-len(data) % cap)))
    for c in cards:  # trailing blank fields carry nothing
        while c and not c[-1].strip():
            c.pop()
            c.lines.pop()
    return cards


def _frames(cards: dict[str, list[_Card]]) -> dict[int, CoordinateSystem]:
    """The CORD2R/C/S systems (chains through RID resolved)."""
    raw: dict[int, _Card] = {}
    for name in ("CORD2R", "CORD2C", "CORD2S"):
        for c in cards.get(name, []):
            cid = c.int(0, what="CID")
            if cid in raw or cid == 0:
                raise FormatError(f"{c.where}: coordinate system {cid} defined twice (or 0)")
            raw[cid] = c
    out: dict[int, CoordinateSystem] = {0: CoordinateSystem("R", np.zeros(3), np.eye(3))}

    def get(cid: int, depth: int = 0) -> CoordinateSystem:
        if cid in out:
            return out[cid]
        if cid not in raw or depth > 20:
            raise FormatError(f"coordinate system {cid} is not defined by a CORD2R/C/S (or "
                              "the chain of reference systems is circular)")
        c = raw[cid]
        ref = get(c.int(1, 0), depth + 1)
        a, b, cc = (ref.to_global(np.array([c.real(k + j, 0.0) for j in range(3)]))
                    for k in (2, 5, 8))
        try:
            out[cid] = CoordinateSystem.from_points(c.name[-1], a, b, cc)
        except ParameterError as err:
            raise FormatError(f"{c.where}: {c.name} {cid}: {err}") from err
        return out[cid]

    for cid in raw:
        get(cid)
    return out


def _components(code: str, where: str) -> list[str]:
    if not code or any(ch not in "123456" for ch in code):
        raise FormatError(f"{where}: component code {code!r} must be digits 1..6")
    return [DOF_NAMES[int(ch) - 1] for ch in sorted(set(code))]


def _materials(cards, notes: dict) -> dict[int, OrthotropicMaterial]:
    mats: dict[int, OrthotropicMaterial] = {}
    for c in cards.get("MAT1", []):
        mid = c.int(0, what="MID")
        E, G, nu = c.real(1, 0.0), c.real(2, 0.0), c.real(3, 0.0)
        given = [not c.blank(k) for k in (1, 2, 3)]
        if sum(given) < 2 or not (given[0] or given[1]):
            raise FormatError(f"{c.where}: MAT1 {mid} needs two of E, G, NU (E or G among "
                              "them)")
        if not given[2]:
            nu = E / (2 * G) - 1
        elif not given[1]:
            G = E / (2 * (1 + nu))
        elif not given[0]:
            E = 2 * G * (1 + nu)
        rho = c.real(4, 0.0)
        if not c.blank(7):
            notes["damping"][f"MAT1 {mid}"] = c.real(7, what="GE")
        try:
            if abs(G - E / (2 * (1 + nu))) <= 1e-12 * E:
                mats[mid] = IsotropicMaterial(f"MAT1 {mid}", E, nu, rho)
            else:  # E, G and NU all given and independent: keep the given G
                mats[mid] = OrthotropicMaterial(f"MAT1 {mid}", E, E, G, G, G, nu, rho)
        except MvtkError as err:
            raise FormatError(f"{c.where}: MAT1 {mid}: {err}"
                              + (" (RHO is blank: mvtk models carry mass; give the "
                                 "density)" if rho == 0.0 else "")) from err
    for c in cards.get("MAT8", []):
        mid = c.int(0, what="MID")
        vals = [c.real(k, what=w) for k, w in ((1, "E1"), (2, "E2"), (3, "NU12"), (4, "G12"))]
        g1z, g2z = c.real(5, 0.0), c.real(6, 0.0)
        if not (g1z and g2z):
            raise FormatError(f"{c.where}: MAT8 {mid} needs G1Z and G2Z (transverse shear "
                              "moduli) for shear-deformable shells")
        if not c.blank(16):
            notes["damping"][f"MAT8 {mid}"] = c.real(16, what="GE")
        try:
            mats[mid] = OrthotropicMaterial(f"MAT8 {mid}", vals[0], vals[1], vals[3], g1z,
                                            g2z, vals[2], c.real(7, 0.0))
        except MvtkError as err:
            raise FormatError(f"{c.where}: MAT8 {mid}: {err}") from err
    return mats


def _material(mats, mid: int, where: str) -> OrthotropicMaterial:
    if mid not in mats:
        raise FormatError(f"{where}: material {mid} is not defined (MAT1/MAT8)")
    return mats[mid]


def _shell_props(cards, mats) -> dict[int, Laminate]:
    out: dict[int, Laminate] = {}
    for c in cards.get("PSHELL", []):
        pid, mid = c.int(0, what="PID"), c.int(1, what="MID1")
        t = c.real(2, what="T")
        mid2 = c.int(3, mid, "MID2")
        if mid2 != mid or c.real(4, 1.0, "12I/T**3") != 1.0 or c.real(7, 0.0, "NSM") != 0.0 \
                or not c.blank(10):
            raise FormatError(f"{c.where}: PSHELL {pid}: only homogeneous shells (MID2 = "
                              "MID1, 12I/T^3 = 1, NSM = 0, no MID4) are supported")
        mid3 = c.int(5, mid, "MID3")
        if mid3 != mid:
            raise FormatError(f"{c.where}: PSHELL {pid}: MID3 = {mid3} differs from MID1; "
                              "transverse shear comes from MID1 here")
        out[pid] = Laminate((Ply(_material(mats, mid, c.where), t),),
                            shear_correction=c.real(6, 5.0 / 6.0, "TS/T"))
    for c in cards.get("PCOMP", []):
        pid = c.int(0, what="PID")
        plies = []
        k = 8
        while k < len(c):
            mid = c.int(k, plies[-1][0] if plies else None, "MID")
            t = c.real(k + 1, plies[-1][1] if plies else None, "T")
            plies.append((mid, t, c.real(k + 2, 0.0, "THETA")))
            k += 4
        if not plies:
            raise FormatError(f"{c.where}: PCOMP {pid} has no plies")
        if c.real(2, 0.0, "NSM") != 0.0:
            raise FormatError(f"{c.where}: PCOMP {pid}: NSM must be 0")
        if c.text(7) == "SYM":
            plies = plies + plies[::-1]
        elif c.text(7) not in ("", "BLANK"):
            raise FormatError(f"{c.where}: PCOMP {pid}: LAM = {c.text(7)!r} not supported")
        total = sum(t for _, t, _ in plies)
        z0 = c.real(1, -total / 2)
        out[pid] = Laminate(tuple(Ply(_material(mats, m, c.where), t, th)
                                  for m, t, th in plies), z_bottom=z0)
    return out


#: Number of dimensions of the PBARL/PBEAML shapes read here.
_NDIM = {"BAR": 2, "ROD": 1, "TUBE": 2, "BOX": 4, "I": 6}


def _shape_section(mat, kind: str, d: list[float], where: str, name: str):
    try:
        if kind == "BAR":  # DIM1 width (local y), DIM2 height (local z)
            return rectangle_section(mat, d[0], d[1])
        if kind == "ROD":
            return tube_section(mat, d[0])
        if kind == "TUBE":
            return tube_section(mat, d[0], d[1])
        if kind == "BOX":  # DIM1 width, DIM2 height, DIM3 flange t, DIM4 web t
            return box_section(mat, d[1], d[0], d[3], d[2])
        # I: DIM1 height, DIM2/3 flange widths, DIM4 web, DIM5/6 flanges
        if d[1] != d[2] or d[4] != d[5]:
            raise FormatError(f"{where}: {name} I: only doubly symmetric sections (DIM2 = "
                              "DIM3, DIM5 = DIM6)")
        return i_section(mat, d[0], d[1], d[4], d[3])
    except FormatError:
        raise
    except Exception as err:
        raise FormatError(f"{where}: {name}: {err}") from err


def _with_nsm(sec, nsm: float):
    return sec if nsm == 0.0 else replace(sec, rhoA=sec.rhoA + nsm)


def _pbeam(c: _Card, mats):
    """A constant-section PBEAM (end B and intermediate stations equal to end A)."""
    pid, mid = c.int(0, what="PID"), c.int(1, what="MID")
    mat = _material(mats, mid, c.where)
    A, I1, I2 = c.real(2, what="A"), c.real(3, what="I1"), c.real(4, what="I2")
    I12, J, nsm = c.real(5, 0.0, "I12"), c.real(6, 0.0, "J"), c.real(7, 0.0, "NSM")
    if I12 != 0.0:
        raise FormatError(f"{c.where}: PBEAM {pid}: I12 = {I12} (unsymmetric section) is "
                          "not supported")
    rows = [c[k:k + 8] + [""] * (8 - len(c[k:k + 8])) for k in range(8, len(c), 8)]
    r = 0
    if rows and rows[0][0].strip().upper() not in ("YES", "YESA", "NO"):
        r = 1  # stress recovery points of end A
    last = None
    while r < len(rows) and rows[r][0].strip().upper() in ("YES", "YESA", "NO"):
        so = rows[r][0].strip().upper()
        last = rows[r]
        for k, ref in zip(range(2, 8), (A, I1, I2, I12, J, nsm)):
            v = rows[r][k].strip()
            if v and c.real(8 + 8 * r + k, what="station") != ref:
                raise FormatError(f"{c.where}: PBEAM {pid}: tapered beams (a station with "
                                  "properties different from end A) are not supported")
        r += 2 if so == "YES" else 1
    k1 = k2 = 1.0  # Nastran default shear factors of PBEAM
    if r < len(rows):
        if last is None:
            raise FormatError(f"{c.where}: PBEAM {pid}: shear factors K1, K2 need the end B "
                              "station line before them")
        base = 8 + 8 * r
        k1, k2 = c.real(base, 1.0, "K1"), c.real(base + 1, 1.0, "K2")
        for k in range(base + 2, len(c)):
            if not c.blank(k) and c.real(k, 0.0) != 0.0:
                raise FormatError(f"{c.where}: PBEAM {pid}: shear relief, warping, "
                                  "non-structural inertia and offsets (fields after K2) are "
                                  "not supported")
    return _with_nsm(generic_section(mat, A=A, Iy=I2, Iz=I1, J=J,
                                     shear_factor_y=k1 or 1e6, shear_factor_z=k2 or 1e6), nsm)


def _beam_props(cards, mats) -> dict[int, Any]:
    out: dict[int, Any] = {}
    for c in cards.get("PBAR", []):
        pid, mid = c.int(0, what="PID"), c.int(1, what="MID")
        mat = _material(mats, mid, c.where)
        A, I1, I2 = c.real(2, what="A"), c.real(3, what="I1"), c.real(4, what="I2")
        J, nsm = c.real(5, what="J"), c.real(6, 0.0, "NSM")
        k1, k2 = c.real(16, 0.0, "K1"), c.real(17, 0.0, "K2")
        if c.real(18, 0.0, "I12") != 0.0:
            raise FormatError(f"{c.where}: PBAR {pid}: I12 (unsymmetric section) is not "
                              "supported")
        out[pid] = _with_nsm(generic_section(mat, A=A, Iy=I2, Iz=I1, J=J,
                                             shear_factor_y=k1 or 1e6,
                                             shear_factor_z=k2 or 1e6), nsm)
    for c in cards.get("PBEAM", []):
        out[c.int(0, what="PID")] = _pbeam(c, mats)
    for c in cards.get("PBARL", []) + cards.get("PBEAML", []):
        pid, mid = c.int(0, what="PID"), c.int(1, what="MID")
        mat = _material(mats, mid, c.where)
        kind = c.text(3)
        if kind not in _NDIM:
            raise FormatError(f"{c.where}: {c.name} {pid}: TYPE {kind!r} not supported; "
                              f"use one of {', '.join(_NDIM)}")
        n = _NDIM[kind]
        d = [c.real(8 + k, what=f"DIM{k + 1}") for k in range(n)]
        nsm = c.real(8 + n, 0.0, "NSM")
        if c.name == "PBARL" and len(c) > 9 + n:
            raise FormatError(f"{c.where}: PBARL {pid}: {len(c) - 9 - n} fields after NSM "
                              f"(TYPE {kind} has {n} dimensions)")
        if c.name == "PBEAML":  # further stations: SO, X/XB, DIM1..DIMn, NSM each
            k = 9 + n
            while k < len(c):
                dims = [c.real(k + 2 + j, d[j], f"DIM{j + 1}") for j in range(n)]
                if dims != d or c.real(k + 2 + n, nsm, "NSM") != nsm:
                    raise FormatError(f"{c.where}: PBEAML {pid}: tapered beams (stations "
                                      "with dimensions different from end A) are not "
                                      "supported")
                k += n + 3
        out[pid] = _with_nsm(_shape_section(mat, kind, d, c.where, f"{c.name} {pid}"), nsm)
    return out


def _spc_sets(cards, ids, where_of) -> dict[int, list]:
    """SPC1/SPC sets: sid -> [(node index, components)] (SPCADD resolved later)."""
    sets: dict[int, list[tuple[int, list[str]]]] = defaultdict(list)
    for c in cards.get("SPC1", []):
        sid, comps = c.int(0, what="SID"), _components(c.text(1), c.where)
        rest = [c._raw(k) for k in range(2, len(c)) if c._raw(k)]
        if len(rest) == 3 and rest[1].upper() == "THRU":
            lo, hi = c.int(2, what="G1"), c.int(len(c) - 1, what="G2")
            if hi < lo:
                raise FormatError(f"{c.where}: SPC1 {sid}: G1 THRU G2 with G2 < G1")
            # Nastran: grids of the range that do not exist are skipped
            gids = [g for g in ids if lo <= g <= hi]
        else:
            gids = [c.int(k, what="G") for k in range(2, len(c)) if c._raw(k)]
        sets[sid].extend((where_of(g, c.where), comps) for g in gids)
    for c in cards.get("SPC", []):
        sid = c.int(0, what="SID")
        for k in (1, 4):
            if c.blank(k):
                continue
            if c.real(k + 2, 0.0, "D") != 0.0:
                raise FormatError(f"{c.where}: SPC {sid}: enforced displacement D = "
                                  f"{c.real(k + 2)} is not supported (only D = 0)")
            sets[sid].append((where_of(c.int(k, what="G"), c.where),
                              _components(c.text(k + 1), c.where)))
    return sets


def _case_spc(case: list[str]) -> int | None:
    """The SPC set of the case control when it names exactly one."""
    found = {int(m.group(1)) for line in case
             if (m := re.match(r"^\s*SPC\s*=\s*(\d+)\s*$", line.split("$")[0], re.I))}
    return found.pop() if len(found) == 1 else None


def read_nastran(path: str | Path, spc_id: int | None = None, name: str = "") -> FEModel:
    """Read a Nastran bulk-data deck (the cards in the module notes) into an FEModel.

    Parameters
    ----------
    path : path
        ``.bdf`` / ``.dat`` / ``.nas`` file.
    spc_id : int, optional
        SPC set (SPC1, SPC or SPCADD id) to apply. Default: the one named by ``SPC =``
        in the case control, else the only set of the deck.
    name : str

    Returns
    -------
    FEModel
        ``node_ids`` are the GRID ids; node sets ``spc:<sid>`` (also ``spc1:<sid>``) and
        one per property ``pid:<pid>`` (its elements' nodes); element sets named
        ``<CARD>:<pid>``. Grids with ``CD`` other than 0 have their DOFs in that
        system's axes at the grid (``meta["node_frames"]``); ``meta["nastran"]`` holds
        the card counts, the ignored cards and their counts, the structural damping
        coefficients ``GE`` read (not applied to ``M``, ``K``) and the SPC set used.

    Raises
    ------
    FormatError
        Unsupported cards (all listed with their counts), missing references,
        unsupported options; the message names the file and line.

    Examples
    --------
    The 2-mass chain as a Nastran deck (GRID 1 grounded, CONM2 1 kg, CELAS2 1e5 N/m);
    closed form ``f1 = sqrt(k (3 - sqrt(5)) / 2) / (2 pi)`` = 31.105 Hz:

    >>> import pathlib, tempfile
    >>> from mvtk.fe import modal_analysis
    >>> deck = pathlib.Path(tempfile.mkdtemp()) / "chain.bdf"
    >>> _ = deck.write_text("BEGIN BULK\\n"
    ...                     "GRID,1,,0.,0.,0.\\nGRID,2,,0.1,0.,0.\\nGRID,3,,0.2,0.,0.\\n"
    ...                     "CONM2,10,2,,1.0\\nCONM2,11,3,,1.0\\n"
    ...                     "CELAS2,20,1.0e5,1,3,2,3\\nCELAS2,21,1.0e5,2,3,3,3\\n"
    ...                     "SPC1,1,123456,1\\nSPC1,1,12456,2,3\\nENDDATA\\n")
    >>> model = read_nastran(deck)
    >>> model.n_dof, np.round(modal_analysis(model, 1).fn_hz, 3)
    (2, array([31.105]))
    """
    path = Path(path)
    if not path.exists():
        raise FormatError(f"Nastran file {str(path)!r} not found")
    lines, case = _read_lines(path)
    all_cards = _cards_of(lines)
    cards: dict[str, list[_Card]] = defaultdict(list)
    unsupported: dict[str, int] = defaultdict(int)
    ignored: dict[str, int] = defaultdict(int)
    for c in all_cards:
        if c.name in _SUPPORTED:
            cards[c.name].append(c)
        elif c.name in _IGNORED:
            ignored[c.name] += 1
        else:
            unsupported[c.name] += 1
    if unsupported:
        raise FormatError(f"{path}: unsupported bulk-data cards "
                          f"{dict(sorted(unsupported.items()))}; supported: "
                          f"{', '.join(sorted(_SUPPORTED))} (ignored: "
                          f"{', '.join(sorted(_IGNORED))})")
    if not cards.get("GRID"):
        raise FormatError(f"{path}: no GRID cards")
    notes: dict[str, Any] = {"cards": {k: len(v) for k, v in sorted(cards.items())},
                             "ignored": dict(sorted(ignored.items())), "damping": {}}
    systems = _frames(cards)

    def system(cid: int, where: str) -> CoordinateSystem:
        if cid not in systems:
            raise FormatError(f"{where}: coordinate system {cid} is not defined "
                              "(CORD2R/C/S)")
        return systems[cid]

    ids, xyz, fixed_ps, cds = [], [], [], []
    for c in cards["GRID"]:
        gid, cp = c.int(0, what="ID"), c.int(1, 0, "CP")
        if c.int(7, 0, "SEID") != 0:
            raise FormatError(f"{c.where}: GRID {gid}: superelement SEID is not supported")
        xyz.append(system(cp, c.where).to_global(np.array([c.real(k, 0.0, f"X{k - 1}")
                                                          for k in (2, 3, 4)])))
        ids.append(gid)
        cds.append((c.int(5, 0, "CD"), c.where))
        if c.text(6):
            fixed_ps.append((gid, _components(c.text(6), c.where)))
    ids_a = np.array(ids)
    if np.unique(ids_a).size != ids_a.size:
        u, n = np.unique(ids_a, return_counts=True)
        raise FormatError(f"{path}: duplicated GRID ids {u[n > 1][:10].tolist()}")
    index = {g: i for i, g in enumerate(ids)}
    nodes = np.array(xyz)
    node_frames = {i: system(cd, w).axes_at(nodes[i]) for i, (cd, w) in enumerate(cds)
                   if cd != 0}

    def axes(i: int) -> np.ndarray:
        return node_frames.get(i, np.eye(3))

    def node(gid: int, where: str) -> int:
        if gid not in index:
            raise FormatError(f"{where}: grid {gid} is not defined")
        return index[gid]

    mats = _materials(cards, notes)
    shells, beams = _shell_props(cards, mats), _beam_props(cards, mats)
    members: list[Any] = []
    node_sets: dict[str, np.ndarray] = {}
    groups: dict[tuple[str, int, float], list[tuple[list[int], np.ndarray]]] = defaultdict(list)
    shell_nodes: dict[int, list[int]] = {}
    for kind, n in (("CQUAD4", 4), ("CTRIA3", 3)):
        for c in cards.get(kind, []):
            pid = c.int(1, what="PID")
            if pid not in shells:
                raise FormatError(f"{c.where}: {kind} {c.int(0)}: property {pid} is not a "
                                  "PSHELL/PCOMP")
            g = [node(c.int(2 + k, what=f"G{k + 1}"), c.where) for k in range(n)]
            shell_nodes[c.int(0, what="EID")] = g
            if any(not c.blank(k) and c.real(k, 0.0) != 0.0 for k in range(9, len(c))):
                raise FormatError(f"{c.where}: {kind} {c.int(0)}: TFLAG and corner "
                                  "thicknesses T1..T4 are not supported")
            x = nodes[g]
            nrm = np.cross(x[2] - x[0], x[-1] - x[1]) if n == 4 else np.cross(
                x[1] - x[0], x[2] - x[0])
            nrm /= np.linalg.norm(nrm)
            if c.is_int(2 + n):  # MCID
                mc = system(c.int(2 + n), c.where)
                if mc.kind != "R":
                    raise FormatError(f"{c.where}: {kind} {c.int(0)}: MCID must be a "
                                      "CORD2R")
                a = mc.axes[0]
            else:
                theta = np.radians(c.real(2 + n, 0.0, "THETA"))
                e = x[1] - x[0]
                e /= np.linalg.norm(e)
                a = np.cos(theta) * e + np.sin(theta) * np.cross(nrm, e)
            groups[(kind, pid, c.real(3 + n, 0.0, "ZOFFS"))].append((g, a))
    for (kind, pid, zoff), items in groups.items():
        el = np.array([g for g, _ in items])
        axes_ = np.array([a for _, a in items])
        members.append(ShellSet(el, shells[pid], material_axis=axes_, offset=zoff,
                                name=f"{kind}:{pid}:{zoff}"))
        node_sets[f"pid:{pid}"] = np.unique(np.concatenate(
            [node_sets.get(f"pid:{pid}", np.zeros(0, int)), el.ravel()]))
    bgroups: dict[tuple, list[list[int]]] = defaultdict(list)
    for c in cards.get("CBAR", []) + cards.get("CBEAM", []):
        pid = c.int(1, what="PID")
        if pid not in beams:
            raise FormatError(f"{c.where}: {c.name} {c.int(0)}: property {pid} is not a "
                              "PBAR/PBARL/PBEAM/PBEAML")
        ga, gb = node(c.int(2, what="GA"), c.where), node(c.int(3, what="GB"), c.where)
        if c.is_int(4) and c.blank(5) and c.blank(6):  # G0
            v = nodes[node(c.int(4), c.where)] - nodes[ga]
        else:  # v in the displacement system of GA
            v = axes(ga).T @ np.array([c.real(k, 0.0, f"X{k - 3}") for k in (4, 5, 6)])
        if c.text(7) not in ("", "GGG"):
            raise FormatError(f"{c.where}: {c.name} {c.int(0)}: OFFT = {c.text(7)!r}; only "
                              "GGG (vectors in the grids' displacement systems)")
        if c.text(8) or c.text(9):
            raise FormatError(f"{c.where}: {c.name} {c.int(0)}: pin flags PA/PB are not "
                              "supported")
        if c.name == "CBEAM" and (c.text(16) or c.text(17)):
            raise FormatError(f"{c.where}: CBEAM {c.int(0)}: warping scalar points SA/SB "
                              "are not supported")
        wa = axes(ga).T @ np.array([c.real(k, 0.0, "W") for k in (10, 11, 12)])
        wb = axes(gb).T @ np.array([c.real(k, 0.0, "W") for k in (13, 14, 15)])
        if not np.allclose(wa, wb, rtol=1e-12, atol=1e-15):
            raise FormatError(f"{c.where}: {c.name} {c.int(0)}: offsets WA and WB must be "
                              "equal")
        if np.linalg.norm(v) == 0:
            raise FormatError(f"{c.where}: {c.name} {c.int(0)}: orientation vector is zero")
        bgroups[(pid, tuple(np.round(v / np.linalg.norm(v), 12)), tuple(wa))].append([ga, gb])
    for (pid, v, w), els in bgroups.items():
        members.append(BeamSet(np.array(els), beams[pid], orientation=v, offset=w,
                               name=f"beam:{pid}:{v}:{w}"))
    for c in cards.get("CONM2", []):
        g = node(c.int(1, what="G"), c.where)
        cid = c.int(2, 0, "CID")
        x = np.array([c.real(k, 0.0, f"X{k - 3}") for k in (4, 5, 6)])
        i11, i21, i22, i31, i32, i33 = (c.real(k, 0.0, "I") for k in range(8, 14))
        J = np.array([[i11, -i21, -i31], [-i21, i22, -i32], [-i31, -i32, i33]])
        if cid == -1:  # X is the centre of gravity in basic; inertia in basic
            off = x - nodes[g]
        else:
            R = system(cid, c.where).axes_at(nodes[g])
            off, J = R.T @ x, R.T @ J @ R
        members.append(PointMass(g, c.real(3, what="M"), J, tuple(off)))
    pelas = {}
    for c in cards.get("PELAS", []):
        for k in (0, 4):
            if not c.blank(k):
                pelas[c.int(k)] = c.real(k + 1, what="K")
                if c.real(k + 2, 0.0, "GE"):
                    notes["damping"][f"PELAS {c.int(k)}"] = c.real(k + 2)
    for c in cards.get("CELAS1", []) + cards.get("CELAS2", []):
        if c.name == "CELAS1":
            pid = c.int(1, what="PID")
            if pid not in pelas:
                raise FormatError(f"{c.where}: CELAS1 {c.int(0)}: PELAS {pid} not defined")
            k = pelas[pid]
        else:
            k = c.real(1, what="K")
            if c.real(6, 0.0, "GE"):
                notes["damping"][f"CELAS2 {c.int(0)}"] = c.real(6)
        g1, c1 = c.int(2, what="G1"), c.text(3)
        g2, c2 = c.int(4, 0, "G2"), c.text(5)
        dof = _components(c1, c.where)
        if len(dof) != 1:
            raise FormatError(f"{c.where}: {c.name}: C1 must be one component")
        if g2 and c2 != c1:
            raise FormatError(f"{c.where}: {c.name} {c.int(0)}: springs between different "
                              "components are not supported")
        members.append(Spring(node(g1, c.where), {dof[0]: k},
                              node(g2, c.where) if g2 else None))
    for c in cards.get("RBE2", []):
        gn = node(c.int(1, what="GN"), c.where)
        deps, k = [], 3
        while k < len(c):
            if c.text(k) == "THRU":
                lo, hi = c.int(k - 1, what="GM"), c.int(k + 1, what="GM")
                deps += [node(g, c.where) for g in range(lo + 1, hi + 1)]
                k += 2
                continue
            if not c.blank(k):
                if not c.is_int(k):  # ALPHA (thermal expansion): kept, not used
                    notes.setdefault("rbe2_alpha", {})[c.int(0)] = c.real(k, what="ALPHA")
                    if k != len(c) - 1:
                        raise FormatError(f"{c.where}: RBE2 {c.int(0)}: a real number "
                                          "(ALPHA) must be the last field")
                else:
                    deps.append(node(c.int(k), c.where))
            k += 1
        members.append(RigidLink(gn, deps, "rbe2", tuple(_components(c.text(2), c.where))))
    for c in cards.get("RBE3", []):
        members.append(_rbe3(c, node))
    spc = _spc_sets(cards, ids, node)
    adds: dict[int, list[int]] = {}
    for c in cards.get("SPCADD", []):
        sid = c.int(0, what="SID")
        adds[sid] = [c.int(k, what="S") for k in range(1, len(c)) if not c.blank(k)]
    for sid, parts in adds.items():
        for s_ in parts:
            if s_ not in spc:
                raise FormatError(f"{path}: SPCADD {sid} names SPC set {s_}, which is not "
                                  "defined by SPC/SPC1 cards")
    choices = sorted(set(adds) | (set(spc) - {s_ for p in adds.values() for s_ in p}))
    chosen_id = spc_id if spc_id is not None else _case_spc(case)
    if chosen_id is None:
        if len(choices) > 1:
            raise FormatError(f"{path}: several SPC sets {choices}; choose one with spc_id "
                              "(or SPC = n in the case control)")
        chosen_id = choices[0] if choices else None
    if chosen_id is not None and chosen_id not in spc and chosen_id not in adds:
        raise FormatError(f"{path}: no SPC set {chosen_id}; sets: {choices}")
    chosen = [] if chosen_id is None else (
        [x for s_ in adds[chosen_id] for x in spc[s_]] if chosen_id in adds
        else spc[chosen_id])
    notes["spc_id"] = chosen_id
    supports: dict[str, list[str]] = {}
    for i, (n, comps) in enumerate(list(chosen) + [(index[g], c) for g, c in fixed_ps]):
        node_sets[f"_spc{i}"] = np.array([n])
        supports[f"_spc{i}"] = comps
    for sid, items in spc.items():
        node_sets[f"spc:{sid}"] = np.unique([n for n, _ in items])
        node_sets[f"spc1:{sid}"] = node_sets[f"spc:{sid}"]
    model = assemble_model(nodes, members, supports=supports, node_sets=node_sets,
                           node_ids=ids_a, name=name or path.stem,
                           meta={"source": str(path), "nastran": notes},
                           node_frames=node_frames or None)
    sets = {k: v for k, v in model.node_sets.items() if not k.startswith("_spc")}
    model = FEModel(nodes=model.nodes, M=model.M, K=model.K, dof_node=model.dof_node,
                    dof_component=model.dof_component, node_sets=sets,
                    elements=model.elements, name=model.name, meta=model.meta,
                    node_ids=model.node_ids)
    cases = _load_cases(cards, model, node, system, shell_nodes)
    if cases:
        notes["load_id"] = _case_load(case)
        model = replace(model, meta=dict(model.meta, load_cases=cases))
    return model


def _case_load(case: list[str]) -> int | None:
    """The LOAD set of the case control when it names exactly one."""
    found = {int(m.group(1)) for line in case
             if (m := re.match(r"^\s*LOAD\s*=\s*(\d+)\s*$", line.split("$")[0], re.I))}
    return found.pop() if len(found) == 1 else None


def _load_cases(cards, model: FEModel, node, system, shell_nodes) -> dict[str, np.ndarray]:
    """Static load sets ``{"<sid>": nodal forces (n_nodes, 6)}`` of FORCE, MOMENT,
    PLOAD2, PLOAD4 (uniform), GRAV and their LOAD combinations."""
    from ._loads import element_pressure, gravity_nodal

    n = model.n_nodes
    sets: dict[int, np.ndarray] = {}

    def get(sid: int) -> np.ndarray:
        return sets.setdefault(sid, np.zeros((n, 6)))

    for c in cards.get("FORCE", []) + cards.get("MOMENT", []):
        sid, g = c.int(0, what="SID"), node(c.int(1, what="G"), c.where)
        v = c.real(3, what="F") * np.array([c.real(k, 0.0, "N") for k in (4, 5, 6)])
        R = system(c.int(2, 0, "CID"), c.where).axes_at(model.nodes[g])
        col = slice(0, 3) if c.name == "FORCE" else slice(3, 6)
        get(sid)[g, col] += R.T @ v

    def elements(c: _Card, first: int, where_thru: int) -> list[int]:
        if c.text(where_thru) == "THRU":
            lo, hi = c.int(first, what="EID1"), c.int(where_thru + 1, what="EID2")
            ids = [e for e in shell_nodes if lo <= e <= hi]
        else:
            ids = [c.int(k, what="EID") for k in range(first, len(c)) if not c.blank(k)]
        missing = [e for e in ids if e not in shell_nodes]
        if missing or not ids:
            raise FormatError(f"{c.where}: {c.name}: elements {missing or ids} are not "
                              "CQUAD4/CTRIA3 elements of the deck")
        return ids

    def press(sid: int, p: float, ids: list[int]) -> None:
        for k in (3, 4):
            els = [shell_nodes[e] for e in ids if len(shell_nodes[e]) == k]
            if els:
                get(sid)[:, :3] += element_pressure(model.nodes, np.array(els), p)

    for c in cards.get("PLOAD2", []):
        sid, p = c.int(0, what="SID"), c.real(1, what="P")
        press(sid, p, elements(c, 2, 3))
    for c in cards.get("PLOAD4", []):
        sid, p = c.int(0, what="SID"), c.real(2, what="P1")
        if any(not c.blank(k) and c.real(k) != p for k in (3, 4, 5)):
            raise FormatError(f"{c.where}: PLOAD4: only uniform pressure (P2..P4 blank or "
                              "= P1) is supported")
        if any(not c.blank(k) and c.real(k, 0.0) != 0.0 for k in range(9, len(c))):
            raise FormatError(f"{c.where}: PLOAD4: a load direction (CID, N1..N3) is not "
                              "supported (pressure along the element normal only)")
        if c.text(6) == "THRU":
            ids = elements(c, 1, 6)
        elif not (c.blank(6) and c.blank(7)):
            raise FormatError(f"{c.where}: PLOAD4: G1/G3 (solid faces) are not supported")
        else:
            ids = [c.int(1, what="EID")]
            if ids[0] not in shell_nodes:
                raise FormatError(f"{c.where}: PLOAD4: element {ids[0]} is not a "
                                  "CQUAD4/CTRIA3 element of the deck")
        press(sid, p, ids)
    for c in cards.get("GRAV", []):
        sid = c.int(0, what="SID")
        if c.int(6, 0, "MB") != 0:
            raise FormatError(f"{c.where}: GRAV: MB must be 0")
        a = c.real(2, what="A") * np.array([c.real(k, 0.0, "N") for k in (3, 4, 5)])
        R = system(c.int(1, 0, "CID"), c.where).axes
        get(sid)[:] += gravity_nodal(model, R.T @ a)
    out = {str(k): v for k, v in sets.items()}
    for c in cards.get("LOAD", []):
        sid, scale = c.int(0, what="SID"), c.real(1, what="S")
        total = np.zeros((n, 6))
        for k in range(2, len(c), 2):
            if c.blank(k) and c.blank(k + 1):
                continue
            li = c.int(k + 1, what="L")
            if li not in sets:
                raise FormatError(f"{c.where}: LOAD {sid}: load set {li} is not defined by "
                                  "FORCE, MOMENT, PLOAD2, PLOAD4 or GRAV cards")
            total += c.real(k, what="S") * sets[li]
        out[str(sid)] = scale * total
    return out


def _rbe3(c: _Card, node) -> RigidLink:
    """RBE3 with translational (123) components at the independent grids."""
    eid = c.int(0, what="EID")
    ref = node(c.int(2, what="REFGRID"), c.where)
    if set(c.text(3)) != set("123456"):
        raise FormatError(f"{c.where}: RBE3 {eid}: REFC = {c.text(3)!r}; only 123456 (the "
                          "reference grid's six DOFs) is supported")
    nodes_, weights = [], []
    k, wt, comps = 4, None, None
    while k < len(c):
        f = c.text(k)
        if f in ("UM", "ALPHA", "TREF"):
            raise FormatError(f"{c.where}: RBE3 {eid}: {f} is not supported")
        if not f:
            k += 1
            continue
        if not c.is_int(k):  # a weight starts a group: WTi Ci Gi,j ...
            wt = c.real(k, what="WT")
            comps = c.text(k + 1)
            if set(comps) != set("123"):
                raise FormatError(f"{c.where}: RBE3 {eid}: C = {comps!r}; only 123 "
                                  "(translations of the independent grids) is supported")
            k += 2
            continue
        if wt is None:
            raise FormatError(f"{c.where}: RBE3 {eid}: grid {f} before a weight WT1")
        nodes_.append(node(c.int(k), c.where))
        weights.append(wt)
        k += 1
    if not nodes_:
        raise FormatError(f"{c.where}: RBE3 {eid}: no independent grids")
    return RigidLink(ref, nodes_, "rbe3", weights=tuple(weights))
