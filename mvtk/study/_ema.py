"""Study stages of the multi-point test: modal identification and test-FE correlation.

``[modal]`` names an FRF file of a multi-point test (UFF 58 FRFs with node/direction
fields, or any FRF matrix :func:`mvtk.io.read` returns) and its test geometry. The
``modal`` stage identifies the modes (:func:`mvtk.modal.identify`: pLSCF + LSFD); the
identified shapes pair the FE modes by MAC in the updating stage
(:func:`shape_targets`); the ``correlation`` stage maps the sensors onto the (updated) FE
model and tabulates MAC, pairing and COMAC (:func:`mvtk.correlation.correlate`),
including the modes that were NOT updating targets (the model-form check).

Figures are rendered when the stage runs and cached with it as PNG bytes, so the report
needs no state beyond the cache.
"""

from __future__ import annotations

import base64
import warnings

import numpy as np

from ..errors import ConfigError, MvtkError

__all__ = ["modal", "correlation", "shape_targets", "geometry_of"]


def _png(fig) -> str:
    """Base64 PNG of a figure at 100 dpi (built off pyplot: nothing to close)."""
    from mvtk.plot import figure_to_png

    return base64.b64encode(figure_to_png(fig, dpi=100)).decode("ascii")


def _frf_of(path, options=None):
    import mvtk.io
    import mvtk.modal

    with warnings.catch_warnings():
        # a UFF file of a multi-point test holds its geometry (dataset 15) beside the
        # FRFs: the reader's note that it skipped it is expected here
        warnings.filterwarnings("ignore", message=r".*dataset type 15 is not measurement")
        obj = mvtk.io.read(path, **(options or {}))
    try:
        return mvtk.modal.as_frf_matrix(obj)
    except Exception as err:  # noqa: BLE001 - re-raised with the study key named
        raise ConfigError(f"modal.file: {path.name} holds no FRF matrix that mvtk.modal can "
                          f"identify ({err})") from err


def _frf_of_sets(paths, options, reference, excitation):
    """FRF matrix of a roving test's time-history files (one measurement set each).

    Returns ``(frf, note)``; with more references than responses (roving hammer) the
    matrix is turned by reciprocity (:func:`mvtk.modal.reciprocal`) and ``note`` says so.
    """
    import mvtk.io
    import mvtk.modal
    from mvtk.errors import MvtkError

    sets = []
    for k, path in enumerate(paths):
        ds = mvtk.io.read(path, **options)
        if "time_history" not in ds:
            raise ConfigError(f"modal.sets[{k}]: {path.name} holds no time history "
                              f"(variables {list(ds.data_vars)}); expected force and response "
                              "channels")
        sets.append(ds["time_history"])
    try:
        frf = mvtk.modal.frf_of_sets(sets, reference, excitation=excitation)
    except MvtkError as err:
        names = ", ".join(p.name for p in paths)
        raise ConfigError(f"modal.sets ({names}): {err}") from err
    note = frf.attrs["reciprocity"]
    return frf, note


def modal(study):
    """Identify the multi-point test of ``[modal]`` with :func:`mvtk.modal.identify`.

    Returns the mode table (``fn_hz``, ``zeta``, ``mpc``, ``mpd``, ``stability_count``,
    ``reliable``, ``reason``) and the real (normalised) shapes ``("mode", "dof")`` with
    their ``node``/``direction`` coordinates as arrays.
    """
    import xarray as xr

    import mvtk.modal
    from mvtk.plot import plot_frf_synthesis, plot_stabilisation

    cfg = study.section("modal")
    options = dict(cfg.get("read_options") or {})
    note = ""
    orders = None
    if cfg.get("max_order") is not None:
        orders = range(2, int(cfg["max_order"]) + 1)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        if study.has_extra_file("modal_file"):
            path = study.extra_file("modal_file")
            frf = _frf_of(path, options)
            source = path.name
        else:
            paths = [study.extra_file(f"modal_set_{k + 1}") for k in range(len(cfg["sets"]))]
            frf, note = _frf_of_sets(paths, options, cfg.get("reference"), cfg["excitation"])
            source = f"{len(paths)} measurement sets ({paths[0].name} ... {paths[-1].name})"
        res = mvtk.modal.identify(frf, float(cfg["fmin_hz"]), float(cfg["fmax_hz"]),
                                  orders=orders)
    table = res.to_dataframe()
    shapes = res.real_shapes
    figures = {
        "stabilisation": _png(plot_stabilisation(res.diagram, res)),
        "synthesis": _png(plot_frf_synthesis(res)),
    }
    result = {
        "file": source,
        "note": note,
        "n_responses": int(frf.sizes["response"]),
        "n_references": int(frf.sizes["reference"]),
        "n_lines": int(frf.sizes["frequency"]),
        "band_hz": [float(cfg["fmin_hz"]), float(cfg["fmax_hz"])],
        "frf_type": str(frf.attrs.get("frf_type", "")),
        "table": table.to_dict(orient="list"),
        "figures": figures,
        "warnings": [f"{w.category.__name__}: {w.message}" for w in caught],
    }
    if frf.attrs.get("set_quality"):  # measurement sets: what each set was worth
        import json

        result["set_quality"] = json.loads(frf.attrs["set_quality"])
        result["window_policy"] = str(frf.attrs.get("window_policy", ""))
    ds = xr.Dataset({"shapes": xr.DataArray(
        np.asarray(shapes.values, dtype=float), dims=("mode", "dof"),
        coords={"mode": shapes["mode"].values, "dof": [str(d) for d in shapes["dof"].values],
                "node": ("dof", np.asarray(shapes["node"].values, dtype=int)),
                "direction": ("dof", [str(d) for d in shapes["direction"].values]),
                "fn_hz": ("mode", np.asarray(res.fn_hz, dtype=float))})})
    return result, ds


def _shapes(modal_arrays):
    """The identified shapes of the cached modal stage as a ("mode", "dof") DataArray."""
    return modal_arrays["shapes"]


def geometry_of(study, modal_arrays):
    """Test geometry of ``[modal]`` with the sensor DOFs of the identified shapes."""
    from mvtk.correlation import read_test_geometry

    shapes = _shapes(modal_arrays)
    sensors = sorted({(int(n), str(d)) for n, d in zip(shapes["node"].values,
                                                       shapes["direction"].values)})
    if study.has_extra_file("modal_geometry"):
        source = study.extra_file("modal_geometry")
    elif study.has_extra_file("modal_file"):
        source = study.extra_file("modal_file")
    else:
        source = study.extra_file("modal_set_1")
    try:
        return read_test_geometry(source, sensors=sensors)
    except MvtkError as err:
        if study.has_extra_file("modal_geometry"):
            raise
        raise ConfigError(
            f"modal.geometry: not given, and {source.name} holds no test geometry ({err}); "
            "expected geometry = \"<file>\" in [modal]: UFF 15/2411, or a CSV/TOML table of "
            "node, x, y, z in m with the nodes of the measurement") from err


def _mapping(study, modal_arrays, model):
    from mvtk.correlation import map_sensors

    cfg = study.section("modal")
    return map_sensors(geometry_of(study, modal_arrays), model, method=str(cfg["mapping"]),
                       tol=float(cfg["tolerance_m"]))


def shape_targets(study, targets, modal_arrays, model):
    """``targets`` with the identified shape nearest in frequency attached (MAC pairing).

    A target gets the shape of the identified mode within ``modal.pair_within`` (relative)
    of its frequency; targets without such a mode keep frequency-only pairing. The
    frequencies and weights of the targets are not changed: the shapes decide which FE
    mode each target is compared with.
    """
    import dataclasses

    cfg = study.section("modal")
    shapes = _shapes(modal_arrays)
    mp = _mapping(study, modal_arrays, model)
    sel = shapes.sel(dof=list(mp.dof))
    fn = np.asarray(shapes["fn_hz"].values, dtype=float)
    within = float(cfg["pair_within"])
    out, attached = [], []
    for t in targets:
        k = int(np.argmin(np.abs(fn - t.fn_hz))) if fn.size else -1
        if k < 0 or abs(fn[k] / t.fn_hz - 1) > within:
            out.append(t)
            attached.append(None)
            continue
        shape = {"values": np.asarray(sel.values[k], dtype=float), "observation": mp.matrix,
                 "labels": [str(d) for d in sel["dof"].values]}
        out.append(dataclasses.replace(t, shape=shape))
        attached.append(int(shapes["mode"].values[k]))
    return out, attached


def correlation(study, modal_arrays, description: dict, n_modes: int, targets_hz):
    """Map the test onto the (updated) FE model; MAC, pairing and COMAC tables.

    The pairing table marks which identified modes were updating targets: the others are
    predictions of the updated model (the model-form check of the report).
    """
    from mvtk.correlation import correlate
    from mvtk.fe import build_model, modal_analysis

    cfg = study.section("modal")
    model = build_model(description)
    test = _shapes(modal_arrays)
    # a few FE modes beyond the identified ones, so every test mode has candidates
    fe = modal_analysis(model, max(int(n_modes), test.sizes["mode"] + 4))
    geometry = geometry_of(study, modal_arrays)
    res = correlate(geometry, model, fe, test, method=str(cfg["mapping"]),
                    tol=float(cfg["tolerance_m"]))
    pairs = res.pairing_table().reset_index()
    targets = np.asarray(targets_hz or [], dtype=float)
    test_f = [c for c in pairs.columns if "test" in c and "hz" in c.lower()]
    if test_f and targets.size:
        f = pairs[test_f[0]].to_numpy(dtype=float)
        pairs["updating target"] = [bool(np.any(np.abs(targets / x - 1) < 0.02))
                                    if np.isfinite(x) else False for x in f]
    dofs = res.dof_table().reset_index()
    figures = {name: _png(fig) for name, fig in res.figures(model).items()}
    mac = np.asarray(res.mac.values, dtype=float)
    result = {
        "pairs": pairs.to_dict(orient="list"),
        "dofs": dofs.to_dict(orient="list"),
        "mac": mac.tolist(),
        "n_sensors": int(len(res.mapping.dof)),
        "mapping": str(res.mapping.method),
        "fe_fn_hz": np.asarray(fe.fn_hz, dtype=float).tolist(),
        "figures": figures,
    }
    return result, None
