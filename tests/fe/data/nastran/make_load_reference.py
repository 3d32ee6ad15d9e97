"""Write loads_reference.json: pyNastran's resultants of the load sets of loads.bdf.

loads.bdf is mvtk's own deck (a tilted, warped plate of CQUAD4/CTRIA3 with FORCE, MOMENT,
PLOAD4, PLOAD2, GRAV and a LOAD combination). Run with pyNastran 1.4.1 in a separate
environment (numpy < 2): ``venv/bin/python make_load_reference.py``. pyNastran's sum
ignores GRAV (set 40 is left out); the FORCE in a cylindrical system (set 11) is checked
against the local axes at the grid instead (pyNastran converts its direction vector as
a point).
"""

import json
from pathlib import Path

import numpy as np
from pyNastran.bdf.bdf import BDF
from pyNastran.bdf.mesh_utils.loads import sum_forces_moments

HERE = Path(__file__).parent
model = BDF(debug=None)
model.read_bdf(str(HERE / "loads.bdf"))
out = {}
for sid in (10, 20, 30, 100):
    f, m = sum_forces_moments(model, np.zeros(3), sid)
    out[str(sid)] = {"force": [float(v) for v in f], "moment": [float(v) for v in m]}
(HERE / "loads_reference.json").write_text(json.dumps(out, indent=1, sort_keys=True) + "\n")
