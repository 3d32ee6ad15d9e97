"""Regenerate curved_panel.msh from the Gmsh geometry curved_panel.geo.

Run from anywhere: ``python data/structures/curved_panel/make_mesh.py`` (needs the Gmsh
Python API: ``pip install gmsh``, included in ``mvtk[test]``), or with the Gmsh program:
``gmsh -2 -format msh22 curved_panel.geo -o curved_panel.msh``. The mesh is structured
(transfinite) and deterministic: 20 x 16 first-order quads on a 60 degree arc of radius
0.5 m, 0.4 m long; physical groups ``skin`` (2-D), ``stiffener`` and ``ends`` (1-D).
"""

import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent


def generate(out: Path, geo: Path = HERE / "curved_panel.geo", order: int = 1) -> Path:
    """Mesh ``geo`` with Gmsh and write it to ``out`` as Gmsh 2.2 ASCII.

    ``order = 2`` writes complete second-order elements (nine-node quads, three-node
    lines) on the same element grid: ``curved_panel_quad9.msh``.
    """
    import gmsh

    # no user gmshrc (the same mesh everywhere); keep Python's Ctrl-C handling
    gmsh.initialize(readConfigFiles=False, interruptible=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.open(str(geo))
        gmsh.option.setNumber("Mesh.MshFileVersion", 2.2)
        gmsh.option.setNumber("Mesh.Binary", 0)
        gmsh.model.mesh.generate(2)
        if order != 1:
            gmsh.option.setNumber("Mesh.SecondOrderIncomplete", 0)
            gmsh.model.mesh.setOrder(order)
        gmsh.write(str(out))
    finally:
        gmsh.finalize()
    return out


if __name__ == "__main__":
    try:
        import gmsh  # noqa: F401
    except (ImportError, OSError) as err:
        sys.exit(f"make_mesh.py needs the Gmsh Python API ({err}); install it with: "
                 "pip install gmsh")
    print(f"wrote {generate(HERE / 'curved_panel.msh')}")
    print(f"wrote {generate(HERE / 'curved_panel_quad9.msh', order=2)}")
