"""A Nastran bulk-data subset read without pyNastran.

Why not pyNastran: its current release (1.4.1) requires ``numpy < 2`` and fails to import
under numpy 2 (``np.in1d`` was removed), while mvtk's pandas needs numpy >= 2. The
subset below is small enough to read directly.

Formats: small field (8 characters), large field (``GRID*``, 16 characters) and free
field (commas), with continuation lines (``+``/``*``/blank first field or a line starting
with a comma). Only the bulk data section is read (after ``BEGIN BULK`` when present, up
to ``ENDDATA``); ``INCLUDE`` is refused.

Cards and their meaning here:

- ``GRID ID CP X1 X2 X3 CD PS``: ``CP`` may be a ``CORD2R``; ``CD`` must be 0 (displacement
  in global axes); ``PS`` = permanent single-point constraints.
- ``CORD2R CID RID A B C`` (rectangular systems, chains through RID allowed).
- ``CQUAD4 / CTRIA3 EID PID G1..G4 THETA|MCID ZOFFS``: MITC4 / MITC3 shells. Ply angles of
  a ``PCOMP`` are measured from the G1-G2 edge rotated by ``THETA`` about the normal, or
  from the projected x axis of ``MCID`` (Nastran uses the G1-G2 edge for triangles and
  a diagonal-bisector axis for quadrilaterals: the two agree for rectangles).
- ``PSHELL PID MID1 T MID2 12I/T^3 MID3 TS/T NSM``: homogeneous shells (MID2 = MID1 or
  blank, 12I/T^3 = 1 or blank, NSM = 0).
- ``PCOMP PID Z0 NSM ... LAM`` + plies ``MID T THETA``; ``LAM = SYM`` mirrors the plies.
- ``MAT1 MID E G NU RHO`` (two of E, G, NU), ``MAT8 MID E1 E2 NU12 G12 G1Z G2Z RHO``.
- ``CBAR / CBEAM EID PID GA GB X1 X2 X3|G0 OFFT PA PB WA WB``: Timoshenko beams with the
  orientation vector ``v``; offsets ``WA = WB`` (global); pin flags must be blank.
- ``PBAR PID MID A I1 I2 J`` (+ K1 K2 on the third line; blank K = shear-rigid, modelled
  by a shear factor of 1e6), ``PBARL PID MID GROUP TYPE`` with ``TYPE`` ``BAR``, ``ROD``,
  ``TUBE``, ``BOX``, ``I`` (Nastran dimension order), ``PBEAM PID MID A I1 I2 I12 J`` (a
  constant section). ``I1`` bends in plane 1 (local x-y, about local z): ``Iz``.
- ``CONM2 EID G CID M X1 X2 X3 / I11 I21 I22 I31 I32 I33`` (``CID`` 0; inertia matrix
  ``[[I11, -I21, -I31], [-I21, I22, -I32], [-I31, -I32, I33]]`` about the mass centre).
- ``CELAS1 EID PID G1 C1 G2 C2`` + ``PELAS PID K``; ``CELAS2 EID K G1 C1 G2 C2``
  (grounded, or between the same component of two nodes).
- ``SPC1 SID C G1 G2 ... | G1 THRU G2``; with several SIDs choose one (``spc_id``).
- ``RBE2 EID GN CM GM1 ...`` (RBE2-like rigid link).

``PARAM``, ``EIGRL`` and ``EIGR`` are ignored; any other card raises
:class:`~mvtk.errors.FormatError` listing the unsupported card names.
"""

from __future__ import annotations

import re
from collections import defaultdict
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import FormatError
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

__all__ = ["read_nastran"]

_IGNORED = {"PARAM", "EIGRL", "EIGR", "ENDDATA"}
_SUPPORTED = {"GRID", "CORD2R", "CQUAD4", "CTRIA3", "PSHELL", "PCOMP", "MAT1", "MAT8",
              "CBAR", "CBEAM", "PBAR", "PBARL", "PBEAM", "CONM2", "CELAS1", "CELAS2",
              "PELAS", "SPC1", "RBE2"}
_REAL = re.compile(r"^([+-]?(?:\d+\.?\d*|\.\d+))([+-]\d+)$")


class _Card(list):
    """Fields of one card (name excluded) with its file position."""

    def __init__(self, name: str, fields: list[str], where: str):
        super().__init__(fields)
        self.name = name
        self.where = where

    def _raw(self, i: int) -> str:
        return self[i].strip() if i < len(self) else ""

    def int(self, i: int, default: int | None = None, what: str = "") -> int:
        s = self._raw(i)
        if not s:
            if default is None:
                raise FormatError(f"{self.where}: {self.name} field {i + 2} ({what}) is "
                                  "required")
            return default
        try:
            return int(s)
        except ValueError:
            raise FormatError(f"{self.where}: {self.name} field {i + 2} ({what}): expected "
                              f"an integer, got {s!r}") from None

    def real(self, i: int, default: float | None = None, what: str = "") -> float:
        s = self._raw(i).upper().replace("D", "E")
        if not s:
            if default is None:
                raise FormatError(f"{self.where}: {self.name} field {i + 2} ({what}) is "
                                  "required")
            return default
        m = _REAL.match(s)
        if m:
            s = f"{m.group(1)}E{m.group(2)}"
        try:
            return float(s)
        except ValueError:
            raise FormatError(f"{self.where}: {self.name} field {i + 2} ({what}): expected "
                              f"a real number, got {self._raw(i)!r}") from None

    def text(self, i: int) -> str:
        return self._raw(i).upper()


def _split_fixed(line: str, large: bool) -> list[str]:
    body = line[8:72].ljust(64)
    w = 16 if large else 8
    return [body[k:k + w] for k in range(0, 64, w)]


def _cards(text: str, source: str) -> list[_Card]:
    lines = text.splitlines()
    start = 0
    for i, line in enumerate(lines):
        if line.strip().upper().startswith("BEGIN BULK"):
            start = i + 1
            break
    cards: list[_Card] = []
    for no, raw in enumerate(lines[start:], start=start + 1):
        line = raw.split("$")[0].rstrip().expandtabs(8)
        if not line.strip():
            continue
        head = line.strip().upper()
        if head.startswith("ENDDATA"):
            break
        if head.startswith("INCLUDE"):
            raise FormatError(f"{source} line {no}: INCLUDE is not supported; merge the "
                              "included file into the deck")
        where = f"{source} line {no}"
        first = line[:8] if "," not in line else line.split(",")[0]
        is_cont = (not first.strip()) or first.strip()[:1] in "+*" or line.startswith(",")
        if "," in line:
            parts = line.split(",")
            fields = parts[1:]
            if not is_cont:
                name = parts[0].strip().upper()
                large = name.endswith("*")
                fields = fields[:8] + fields[9:] if len(fields) > 8 else fields
        else:
            name = line[:8].strip().upper()
            large = name.endswith("*") or (is_cont and first.strip().startswith("*"))
            fields = _split_fixed(line, large)
        if is_cont:
            if not cards:
                raise FormatError(f"{where}: continuation line without a card")
            cards[-1].extend(fields)
            continue
        cards.append(_Card(name.rstrip("*"), list(fields), where))
    for c in cards:  # trailing blank fields carry nothing
        while c and not c[-1].strip():
            c.pop()
    return cards


def _frames(cards: dict[str, list[_Card]]) -> dict[int, tuple[np.ndarray, np.ndarray]]:
    """Origin and rotation (rows = local axes in global) of each CORD2R."""
    raw = {c.int(0, what="CID"): c for c in cards.get("CORD2R", [])}
    out: dict[int, tuple[np.ndarray, np.ndarray]] = {0: (np.zeros(3), np.eye(3))}

    def get(cid: int, depth: int = 0) -> tuple[np.ndarray, np.ndarray]:
        if cid in out:
            return out[cid]
        if cid not in raw or depth > 20:
            raise FormatError(f"coordinate system {cid} is not defined by a CORD2R (or the "
                              "chain of reference systems is circular)")
        c = raw[cid]
        o, R = get(c.int(1, 0), depth + 1)
        a, b, cc = (np.array([c.real(k + j, 0.0) for j in range(3)]) for k in (2, 5, 8))
        a, b, cc = (o + R.T @ p for p in (a, b, cc))
        ez = (b - a) / np.linalg.norm(b - a)
        ey = np.cross(ez, cc - a)
        ey /= np.linalg.norm(ey)
        out[cid] = (a, np.stack([np.cross(ey, ez), ey, ez]))
        return out[cid]

    for cid in raw:
        get(cid)
    return out


def _components(code: str, where: str) -> list[str]:
    if not code or any(ch not in "123456" for ch in code):
        raise FormatError(f"{where}: component code {code!r} must be digits 1..6")
    return [DOF_NAMES[int(ch) - 1] for ch in sorted(set(code))]


def _materials(cards) -> dict[int, OrthotropicMaterial]:
    mats: dict[int, OrthotropicMaterial] = {}
    for c in cards.get("MAT1", []):
        mid = c.int(0, what="MID")
        E, G, nu = c.real(1, 0.0), c.real(2, 0.0), c.real(3, 0.0)
        if E and G and not nu:
            nu = E / (2 * G) - 1
        elif G and nu and not E:
            E = 2 * G * (1 + nu)
        elif not E:
            raise FormatError(f"{c.where}: MAT1 {mid} needs E (and G or NU)")
        mats[mid] = IsotropicMaterial(f"MAT1 {mid}", E, nu, c.real(4, 0.0))
    for c in cards.get("MAT8", []):
        mid = c.int(0, what="MID")
        vals = [c.real(k, what=w) for k, w in ((1, "E1"), (2, "E2"), (3, "NU12"), (4, "G12"))]
        g1z, g2z = c.real(5, 0.0), c.real(6, 0.0)
        if not (g1z and g2z):
            raise FormatError(f"{c.where}: MAT8 {mid} needs G1Z and G2Z (transverse shear "
                              "moduli) for shear-deformable shells")
        mats[mid] = OrthotropicMaterial(f"MAT8 {mid}", vals[0], vals[1], vals[3], g1z, g2z,
                                        vals[2], c.real(7, 0.0))
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
        mid2 = c.int(3, mid)
        if mid2 != mid or c.real(4, 1.0) != 1.0 or c.real(7, 0.0) != 0.0:
            raise FormatError(f"{c.where}: PSHELL {pid}: only homogeneous shells (MID2 = "
                              "MID1, 12I/T^3 = 1, NSM = 0) are supported")
        out[pid] = Laminate((Ply(_material(mats, mid, c.where), t),))
    for c in cards.get("PCOMP", []):
        pid = c.int(0, what="PID")
        plies = []
        k = 8
        while k < len(c):
            mid = c.int(k, plies[-1][0] if plies else None, "MID")
            t = c.real(k + 1, plies[-1][1] if plies else None, "T")
            plies.append((mid, t, c.real(k + 2, 0.0)))
            k += 4
        if not plies:
            raise FormatError(f"{c.where}: PCOMP {pid} has no plies")
        if c.text(7) == "SYM":
            plies = plies + plies[::-1]
        elif c.text(7) not in ("", "BLANK"):
            raise FormatError(f"{c.where}: PCOMP {pid}: LAM = {c.text(7)!r} not supported")
        total = sum(t for _, t, _ in plies)
        z0 = c.real(1, -total / 2)
        out[pid] = Laminate(tuple(Ply(_material(mats, m, c.where), t, th)
                                  for m, t, th in plies), z_bottom=z0)
    return out


def _beam_props(cards, mats) -> dict[int, Any]:
    out: dict[int, Any] = {}
    for c in cards.get("PBAR", []) + cards.get("PBEAM", []):
        pid, mid = c.int(0, what="PID"), c.int(1, what="MID")
        mat = _material(mats, mid, c.where)
        A, I1, I2 = c.real(2, what="A"), c.real(3, what="I1"), c.real(4, what="I2")
        J = c.real(5 if c.name == "PBAR" else 6, what="J")
        if c.name == "PBAR":
            k1, k2 = c.real(16, 0.0), c.real(17, 0.0)
        else:
            k1 = k2 = 0.0
        out[pid] = generic_section(mat, A=A, Iy=I2, Iz=I1, J=J,
                                   shear_factor_y=k1 or 1e6, shear_factor_z=k2 or 1e6)
    for c in cards.get("PBARL", []):
        pid, mid = c.int(0, what="PID"), c.int(1, what="MID")
        mat = _material(mats, mid, c.where)
        kind = c.text(3)
        d = [c.real(k, 0.0) for k in range(8, 14)]
        try:
            if kind == "BAR":
                sec = rectangle_section(mat, d[0], d[1])
            elif kind == "ROD":
                sec = tube_section(mat, d[0])
            elif kind == "TUBE":
                sec = tube_section(mat, d[0], d[1])
            elif kind == "BOX":  # DIM1 width, DIM2 height, DIM3 flange t, DIM4 web t
                sec = box_section(mat, d[1], d[0], d[3], d[2])
            elif kind == "I":  # DIM1 height, DIM2/3 flange widths, DIM4 web, DIM5/6 flanges
                if d[1] != d[2] or d[4] != d[5]:
                    raise FormatError(f"{c.where}: PBARL {pid} I: only doubly symmetric "
                                      "sections (DIM2 = DIM3, DIM5 = DIM6)")
                sec = i_section(mat, d[0], d[1], d[4], d[3])
            else:
                raise FormatError(f"{c.where}: PBARL {pid}: TYPE {kind!r} not supported; "
                                  "use BAR, ROD, TUBE, BOX or I")
        except FormatError:
            raise
        except Exception as err:
            raise FormatError(f"{c.where}: PBARL {pid}: {err}") from err
        out[pid] = sec
    return out


def read_nastran(path: str | Path, spc_id: int | None = None, name: str = "") -> FEModel:
    """Read a Nastran bulk-data deck (the subset in the module notes) into an FEModel.

    Parameters
    ----------
    path : path
        ``.bdf`` / ``.dat`` / ``.nas`` file.
    spc_id : int, optional
        SPC1 set to apply when the deck holds several.
    name : str

    Returns
    -------
    FEModel
        ``node_ids`` are the GRID ids; node sets ``spc1:<sid>`` and one per property
        ``pid:<pid>`` (its elements' nodes); element sets named ``<CARD>:<pid>``.

    Raises
    ------
    FormatError
        Unsupported cards (all listed), missing references, unsupported options; the
        message names the file and line.
    """
    path = Path(path)
    if not path.exists():
        raise FormatError(f"Nastran file {str(path)!r} not found")
    all_cards = _cards(path.read_text(errors="replace"), str(path))
    cards: dict[str, list[_Card]] = defaultdict(list)
    unsupported: dict[str, int] = defaultdict(int)
    for c in all_cards:
        if c.name in _SUPPORTED:
            cards[c.name].append(c)
        elif c.name not in _IGNORED:
            unsupported[c.name] += 1
    if unsupported:
        raise FormatError(f"{path}: unsupported bulk-data cards "
                          f"{dict(sorted(unsupported.items()))}; supported: "
                          f"{', '.join(sorted(_SUPPORTED))}")
    if not cards.get("GRID"):
        raise FormatError(f"{path}: no GRID cards")
    frames = _frames(cards)
    ids, xyz, fixed_ps = [], [], []
    for c in cards["GRID"]:
        gid, cp = c.int(0, what="ID"), c.int(1, 0)
        if c.int(5, 0) != 0:
            raise FormatError(f"{c.where}: GRID {gid}: displacement system CD = {c.int(5)} "
                              "is not supported (only global displacement axes)")
        if cp not in frames:
            raise FormatError(f"{c.where}: GRID {gid}: coordinate system {cp} not defined")
        o, R = frames[cp]
        xyz.append(o + R.T @ np.array([c.real(k, 0.0) for k in (2, 3, 4)]))
        ids.append(gid)
        if c.text(6):
            fixed_ps.append((gid, _components(c.text(6), c.where)))
    ids_a = np.array(ids)
    if np.unique(ids_a).size != ids_a.size:
        raise FormatError(f"{path}: duplicated GRID ids")
    index = {g: i for i, g in enumerate(ids)}
    nodes = np.array(xyz)

    def node(gid: int, where: str) -> int:
        if gid not in index:
            raise FormatError(f"{where}: grid {gid} is not defined")
        return index[gid]

    mats = _materials(cards)
    shells, beams = _shell_props(cards, mats), _beam_props(cards, mats)
    members: list[Any] = []
    node_sets: dict[str, np.ndarray] = {}
    groups: dict[tuple[str, int, float], list[tuple[list[int], np.ndarray]]] = defaultdict(list)
    for kind, n in (("CQUAD4", 4), ("CTRIA3", 3)):
        for c in cards.get(kind, []):
            pid = c.int(1, what="PID")
            if pid not in shells:
                raise FormatError(f"{c.where}: {kind} {c.int(0)}: property {pid} is not a "
                                  "PSHELL/PCOMP")
            g = [node(c.int(2 + k, what=f"G{k + 1}"), c.where) for k in range(n)]
            x = nodes[g]
            nrm = np.cross(x[2] - x[0], x[-1] - x[1]) if n == 4 else np.cross(
                x[1] - x[0], x[2] - x[0])
            nrm /= np.linalg.norm(nrm)
            t = c._raw(2 + n)
            if t and "." not in t and "E" not in t.upper():  # MCID
                axis = frames.get(int(t))
                if axis is None:
                    raise FormatError(f"{c.where}: MCID {t} is not a CORD2R")
                a = axis[1][0]
            else:
                theta = np.radians(c.real(2 + n, 0.0))
                e = x[1] - x[0]
                e /= np.linalg.norm(e)
                a = np.cos(theta) * e + np.sin(theta) * np.cross(nrm, e)
            groups[(kind, pid, c.real(3 + n, 0.0))].append((g, a))
    for (kind, pid, zoff), items in groups.items():
        el = np.array([g for g, _ in items])
        axes = np.array([a for _, a in items])
        members.append(ShellSet(el, shells[pid], material_axis=axes, offset=zoff,
                                name=f"{kind}:{pid}:{zoff}"))
        node_sets[f"pid:{pid}"] = np.unique(np.concatenate(
            [node_sets.get(f"pid:{pid}", np.zeros(0, int)), el.ravel()]))
    bgroups: dict[tuple, list[list[int]]] = defaultdict(list)
    for c in cards.get("CBAR", []) + cards.get("CBEAM", []):
        pid = c.int(1, what="PID")
        if pid not in beams:
            raise FormatError(f"{c.where}: {c.name} {c.int(0)}: property {pid} is not a "
                              "PBAR/PBARL/PBEAM")
        ga, gb = node(c.int(2, what="GA"), c.where), node(c.int(3, what="GB"), c.where)
        f = c._raw(4)
        if f and "." not in f and not c._raw(5) and not c._raw(6):
            v = nodes[node(int(f), c.where)] - nodes[ga]
        else:
            v = np.array([c.real(4, 0.0), c.real(5, 0.0), c.real(6, 0.0)])
        if c.text(8) or c.text(9):
            raise FormatError(f"{c.where}: {c.name} {c.int(0)}: pin flags PA/PB are not "
                              "supported")
        wa = np.array([c.real(k, 0.0) for k in (10, 11, 12)])
        wb = np.array([c.real(k, 0.0) for k in (13, 14, 15)])
        if not np.allclose(wa, wb):
            raise FormatError(f"{c.where}: {c.name} {c.int(0)}: offsets WA and WB must be "
                              "equal")
        if np.linalg.norm(v) == 0:
            raise FormatError(f"{c.where}: {c.name} {c.int(0)}: orientation vector is zero")
        bgroups[(pid, tuple(np.round(v / np.linalg.norm(v), 12)), tuple(wa))].append([ga, gb])
    for (pid, v, w), els in bgroups.items():
        members.append(BeamSet(np.array(els), beams[pid], orientation=v, offset=w,
                               name=f"beam:{pid}:{v}:{w}"))
    for c in cards.get("CONM2", []):
        if c.int(2, 0) != 0:
            raise FormatError(f"{c.where}: CONM2 {c.int(0)}: CID must be 0 (global)")
        i11, i21, i22, i31, i32, i33 = (c.real(k, 0.0) for k in range(8, 14))
        J = np.array([[i11, -i21, -i31], [-i21, i22, -i32], [-i31, -i32, i33]])
        members.append(PointMass(node(c.int(1, what="G"), c.where), c.real(3, what="M"), J,
                                 tuple(c.real(k, 0.0) for k in (4, 5, 6))))
    pelas = {c.int(0): c.real(1, what="K") for c in cards.get("PELAS", [])}
    for c in cards.get("CELAS1", []) + cards.get("CELAS2", []):
        if c.name == "CELAS1":
            pid = c.int(1, what="PID")
            if pid not in pelas:
                raise FormatError(f"{c.where}: CELAS1 {c.int(0)}: PELAS {pid} not defined")
            k = pelas[pid]
        else:
            k = c.real(1, what="K")
        g1, c1 = c.int(2, what="G1"), c.text(3)
        g2, c2 = c.int(4, 0), c.text(5)
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
        deps = [node(c.int(k), c.where) for k in range(3, len(c)) if c._raw(k)]
        members.append(RigidLink(gn, deps, "rbe2", tuple(_components(c.text(2), c.where))))
    spc_sets: dict[int, list[tuple[int, list[str]]]] = defaultdict(list)
    for c in cards.get("SPC1", []):
        sid, comps = c.int(0, what="SID"), _components(c.text(1), c.where)
        rest = [c._raw(k) for k in range(2, len(c)) if c._raw(k)]
        if len(rest) == 3 and rest[1].upper() == "THRU":
            gids = [g for g in ids if int(rest[0]) <= g <= int(rest[2])]
        else:
            gids = [int(g) for g in rest]
        spc_sets[sid].extend((node(g, c.where), comps) for g in gids)
    if len(spc_sets) > 1 and spc_id is None:
        raise FormatError(f"{path}: several SPC1 sets {sorted(spc_sets)}; choose one with "
                          "spc_id")
    chosen = spc_sets.get(spc_id) if spc_id is not None else next(iter(spc_sets.values()),
                                                                  [])
    if spc_id is not None and chosen is None:
        raise FormatError(f"{path}: no SPC1 set {spc_id}; sets: {sorted(spc_sets)}")
    supports: dict[str, list[str]] = {}
    for i, (n, comps) in enumerate(list(chosen) + [(index[g], c) for g, c in fixed_ps]):
        node_sets[f"_spc{i}"] = np.array([n])
        supports[f"_spc{i}"] = comps
    for sid, items in spc_sets.items():
        node_sets[f"spc1:{sid}"] = np.unique([n for n, _ in items])
    model = assemble_model(nodes, members, supports=supports, node_sets=node_sets,
                           node_ids=ids_a, name=name or path.stem,
                           meta={"source": str(path)})
    sets = {k: v for k, v in model.node_sets.items() if not k.startswith("_spc")}
    return FEModel(nodes=model.nodes, M=model.M, K=model.K, dof_node=model.dof_node,
                   dof_component=model.dof_component, node_sets=sets,
                   elements=model.elements, name=model.name, meta=model.meta,
                   node_ids=model.node_ids)
