"""Small FE models shared by the correlation tests."""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from mvtk.fe import IsotropicMaterial, Ply, modal_analysis, plate_model

STEEL = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)


@lru_cache(maxsize=1)
def cantilever_plate():
    """0.3 m x 0.2 m x 2 mm steel plate clamped at x = 0, 12 x 8 MITC4 elements."""
    model = plate_model(0.3, 0.2, [Ply(STEEL, 2e-3)], nx=12, ny=8, clamp="x0")
    return model, modal_analysis(model, 10)


def grid_points(nx=4, ny=3, x0=0.05, x1=0.3, y0=0.01, y1=0.19):
    return np.array([[x, y, 0.0] for x in np.linspace(x0, x1, nx)
                     for y in np.linspace(y0, y1, ny)])


def plate_setup(n_modes=6):
    """Plate, its modes, a 5 x 4 grid of +z sensors, the mapping and mapped FE shapes."""
    from mvtk import correlation as co

    model, modal = cantilever_plate()
    geo = co.TestGeometry(np.arange(1, 21), grid_points(5, 4))
    geo = geo.with_sensors([(n, "+z") for n in geo.node])
    mp = co.map_sensors(geo, model)
    return model, modal, geo, mp, mp.project(modal).isel(mode=slice(0, n_modes))


def sdynpy_module(relpath: str):
    """One pure-numpy module of SDynPy (e.g. ``"fem/sdynpy_dof.py"``), loaded by file.

    SDynPy's package ``__init__`` pulls in its VTK/Qt GUI, so the module is executed
    alone; skips the calling test when SDynPy (a test extra) is not installed.
    """
    import importlib.util
    from pathlib import Path

    import pytest

    spec = importlib.util.find_spec("sdynpy")
    if spec is None:
        pytest.skip("SDynPy not installed (pip install sdynpy --no-deps, test extra)")
    path = Path(spec.submodule_search_locations[0]) / relpath
    s = importlib.util.spec_from_file_location("_sdynpy_" + Path(relpath).stem, path)
    mod = importlib.util.module_from_spec(s)
    s.loader.exec_module(mod)
    return mod
