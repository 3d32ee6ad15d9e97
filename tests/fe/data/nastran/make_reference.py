"""Write pynastran_reference.json: pyNastran's reading of the decks in this folder.

Run with pyNastran 1.4.1 (which needs numpy < 2) in a separate environment:

    python -m venv venv && venv/bin/pip install "numpy<2" pyNastran==1.4.1
    venv/bin/python make_reference.py

The decks are copied unchanged from pyNastran's test models (repository
SteveDoyle2/pyNastran, folder models/, BSD licence: LICENSE-pyNastran.md). Only values
are recorded here, per card, for the test in tests/fe/test_nastran_decks.py.
"""

import json
from pathlib import Path

from pyNastran.bdf.bdf import BDF

HERE = Path(__file__).parent
DECKS = ["static_solid_shell_bar.bdf", "static_solid_shell_bar_global_radial_cd.bdf",
         "pbarl_bar.bdf", "pbeaml_l.bdf", "a101x.dat", "bah_Pstructure.dat",
         "good_sine.dat", "tst1d3.bdf"]


def fl(x):
    return [float(v) for v in x]


def one(path):
    model = BDF(debug=None)
    model.read_bdf(str(path), xref=True, punch=path.suffix == ".bdf"
                   and "BEGIN BULK" not in path.read_text())
    out = {"card_count": {k: int(v) for k, v in model.card_count.items()}}
    out["GRID"] = {str(n.nid): {"cp": n.cp, "cd": n.cd, "ps": n.ps or "",
                                "xyz": fl(n.xyz), "basic": fl(n.get_position())}
                   for n in model.nodes.values()}
    out["CORD"] = {str(c.cid): {"type": c.type, "origin": fl(c.origin),
                                "axes": [fl(r) for r in c.beta()]}
                   for c in model.coords.values() if c.cid != 0}
    out["CONM2"] = {str(m.eid): {"nid": m.nid, "cid": m.cid, "mass": m.mass, "X": fl(m.X),
                                 "I": fl(m.I)}
                    for m in model.masses.values() if m.type == "CONM2"}
    out["PBARL"] = {str(p.pid): {"type": p.type, "mid": p.mid, "Type": p.Type,
                                 "dim": [fl(d) for d in p.dim] if p.type == "PBEAML"
                                 else fl(p.dim)}
                    for p in model.properties.values() if p.type in ("PBARL", "PBEAML")}
    out["SPC1"] = [{"sid": c.conid, "components": str(c.components),
                    "nodes": sorted(int(n) for n in c.node_ids)}
                   for cs in model.spcs.values() for c in cs if c.type == "SPC1"]
    rig = {}
    for e in model.rigid_elements.values():
        if e.type == "RBE2":
            rig[str(e.eid)] = {"type": "RBE2", "gn": e.gn, "cm": str(e.cm),
                               "Gmi": [int(g) for g in e.Gmi_node_ids]}
        elif e.type == "RBE3":
            rig[str(e.eid)] = {"type": "RBE3", "refgrid": e.refgrid, "refc": str(e.refc),
                               "weights": fl(e.weights), "comps": [str(c) for c in e.comps],
                               "Gijs": [[int(g) for g in gs] for gs in e.Gijs]}
    out["RIGID"] = rig
    out["SHELL"] = {str(e.eid): {"type": e.type, "pid": e.pid, "nodes": list(e.node_ids),
                                 "theta_mcid": e.theta_mcid if isinstance(e.theta_mcid, int)
                                 else float(e.theta_mcid), "zoffset": float(e.zoffset)}
                    for e in model.elements.values() if e.type in ("CQUAD4", "CTRIA3")}
    out["BAR"] = {str(e.eid): {"type": e.type, "pid": e.pid, "ga": e.ga, "gb": e.gb,
                               "x": None if e.x is None else fl(e.x), "g0": e.g0,
                               "offt": e.offt if isinstance(e.offt, str) else None,
                               "wa": fl(e.wa), "wb": fl(e.wb)}
                  for e in model.elements.values() if e.type in ("CBAR", "CBEAM")}
    out["MAT1"] = {str(m.mid): {"e": m.e, "g": m.g, "nu": m.nu, "rho": m.rho}
                   for m in model.materials.values() if m.type == "MAT1"}
    return out


ref = {}
for d in DECKS:
    try:
        ref[d] = one(HERE / d)
    except Exception as err:  # recorded: pyNastran refuses the deck
        ref[d] = {"error": f"{type(err).__name__}: {err}"}
(HERE / "pynastran_reference.json").write_text(json.dumps(ref, indent=1, sort_keys=True))
