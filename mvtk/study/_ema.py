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

__all__ = ["modal", "correlation", "shape_targets", "geometry_of", "compare_tests"]


def _png(fig) -> str:
    """Base64 PNG of a figure at 100 dpi (built off pyplot: nothing to close)."""
    from mvtk.plot import figure_to_png

    return base64.b64encode(figure_to_png(fig, dpi=100)).decode("ascii")


def _frf_of(path, options=None, where="modal"):
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
        raise ConfigError(f"{where}.file: {path.name} holds no FRF matrix that mvtk.modal can "
                          f"identify ({err})") from err


def _frf_of_sets(paths, options, reference, excitation, where="modal"):
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
            raise ConfigError(f"{where}.sets[{k}]: {path.name} holds no time history "
                              f"(variables {list(ds.data_vars)}); expected force and response "
                              "channels")
        sets.append(ds["time_history"])
    try:
        frf = mvtk.modal.frf_of_sets(sets, reference, excitation=excitation)
    except MvtkError as err:
        names = ", ".join(p.name for p in paths)
        raise ConfigError(f"{where}.sets ({names}): {err}") from err
    note = frf.attrs["reciprocity"]
    return frf, note


def _identify_test(study, cfg, band, where: str, file_key: str, set_key):
    """Read and identify one multi-point test: ``(frf, IdentificationResult, note,
    source)``. ``file_key`` / ``set_key(k)``: its names in the study's extra files."""
    import mvtk.modal

    options = dict(cfg.get("read_options") or {})
    note = ""
    orders = None
    if cfg.get("max_order") is not None:
        orders = range(2, int(cfg["max_order"]) + 1)
    if study.has_extra_file(file_key):
        path = study.extra_file(file_key)
        frf = _frf_of(path, options, where)
        source = path.name
    else:
        paths = [study.extra_file(set_key(k + 1)) for k in range(len(cfg["sets"]))]
        frf, note = _frf_of_sets(paths, options, cfg.get("reference"), cfg["excitation"],
                                 where)
        source = f"{len(paths)} measurement sets ({paths[0].name} ... {paths[-1].name})"
    res = mvtk.modal.identify(frf, float(band[0]), float(band[1]), orders=orders)
    return frf, res, note, source


def _test_summary(frf, res, note: str, source: str, band) -> dict:
    """The result entries that describe one identified multi-point test."""
    out = {
        "file": source,
        "note": note,
        "n_responses": int(frf.sizes["response"]),
        "n_references": int(frf.sizes["reference"]),
        "n_lines": int(frf.sizes["frequency"]),
        "df_hz": float(np.median(np.diff(np.asarray(frf["frequency"].values, dtype=float)))),
        "band_hz": [float(band[0]), float(band[1])],
        "frf_type": str(frf.attrs.get("frf_type", "")),
        "excitation": str(frf.attrs.get("excitation", "")),
        "table": res.to_dataframe().to_dict(orient="list"),
        "orders": [int(res.diagram.orders.min()), int(res.diagram.orders.max())],
        # how identify adapted to the data (higher orders, the record's own lines)
        "analysis": [part for part in str(getattr(res, "band_reason", "")).split("; ")
                     if part.startswith(("model orders raised",
                                         "identified on the record's own lines"))],
    }
    if frf.attrs.get("set_quality"):  # measurement sets: what each set was worth
        import json

        out["set_quality"] = json.loads(frf.attrs["set_quality"])
        out["window_policy"] = str(frf.attrs.get("window_policy", ""))
    return out


def compare_tests(fn_a, zeta_a, shapes_a, fn_b, zeta_b, shapes_b, within: float) -> dict:
    """Each mode of test B against the mode of test A nearest in frequency.

    Parameters
    ----------
    fn_a, zeta_a, fn_b, zeta_b : array_like
        Natural frequencies (Hz) and damping ratios of the identified modes of each test.
    shapes_a, shapes_b : xarray.DataArray
        Real shapes ``("mode", "dof")`` with ``dof`` labels (node and direction): the MAC
        is taken on the DOFs both tests measured.
    within : float
        Largest relative frequency difference of a pair (e.g. 0.03).

    Returns
    -------
    dict of lists
        One row per mode of B: ``mode``, ``fn_hz``, ``zeta``, ``paired_mode`` (1-based
        mode of A, 0 when none within ``within``), ``paired_fn_hz``, ``df_pct``,
        ``paired_zeta``, ``mac`` (NaN when unpaired or fewer than 3 common DOFs) and
        ``n_common_dofs``.
    """
    import mvtk.modal

    fa, fb = np.asarray(fn_a, dtype=float), np.asarray(fn_b, dtype=float)
    za, zb = np.asarray(zeta_a, dtype=float), np.asarray(zeta_b, dtype=float)
    la = [str(d) for d in shapes_a["dof"].values]
    lb = [str(d) for d in shapes_b["dof"].values]
    common = [d for d in la if d in set(lb)]
    ia = [la.index(d) for d in common]
    ib = [lb.index(d) for d in common]
    va = np.asarray(shapes_a.values, dtype=float)[:, ia]
    vb = np.asarray(shapes_b.values, dtype=float)[:, ib]
    macs = mvtk.modal.mac(va, vb) if len(common) >= 3 else None
    rows: dict[str, list] = {k: [] for k in ("mode", "fn_hz", "zeta", "paired_mode",
                                             "paired_fn_hz", "df_pct", "paired_zeta", "mac",
                                             "n_common_dofs")}
    for j in range(fb.size):
        i = int(np.argmin(np.abs(fa - fb[j]))) if fa.size else -1
        ok = i >= 0 and abs(fb[j] / fa[i] - 1) <= within
        mac = float(macs[i, j]) if ok and len(common) >= 3 else float("nan")
        rows["mode"].append(j + 1)
        rows["fn_hz"].append(float(fb[j]))
        rows["zeta"].append(float(zb[j]))
        rows["paired_mode"].append(i + 1 if ok else 0)
        rows["paired_fn_hz"].append(float(fa[i]) if ok else float("nan"))
        rows["df_pct"].append(100.0 * (fb[j] / fa[i] - 1) if ok else float("nan"))
        rows["paired_zeta"].append(float(za[i]) if ok else float("nan"))
        rows["mac"].append(mac)
        rows["n_common_dofs"].append(len(common))
    return rows


def modal(study):
    """Identify the multi-point test of ``[modal]`` with :func:`mvtk.modal.identify`, and
    every multi-point measurement (``kind = "multi-point"``) on its own.

    Returns the mode table of ``[modal]`` (``fn_hz``, ``zeta``, ``mpc``, ``mpd``,
    ``stability_count``, ``reliable``, ``reason``) and its real (normalised) shapes
    ``("mode", "dof")`` with their ``node``/``direction`` coordinates as arrays; under
    ``tests`` the same description of every multi-point measurement, by name, with the
    comparison of each of its modes with the ``[modal]`` mode nearest in frequency
    (:func:`compare_tests`, within ``modal.pair_within``).
    """
    import xarray as xr

    from mvtk.plot import plot_frf_synthesis, plot_modal_uncertainty, plot_stabilisation

    from ._config import multipoint_file

    cfg = study.section("modal")
    band = (float(cfg["fmin_hz"]), float(cfg["fmax_hz"]))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        frf, res, note, source = _identify_test(study, cfg, band, "modal", "modal_file",
                                                lambda k: f"modal_set_{k}")
    shapes = res.real_shapes
    figures = {
        "stabilisation": _png(plot_stabilisation(res.diagram, res)),
        "synthesis": _png(plot_frf_synthesis(res)),
        "uncertainty": _png(plot_modal_uncertainty(res)),
    }
    result = {**_test_summary(frf, res, note, source, band), "figures": figures,
              "warnings": [f"{w.category.__name__}: {w.message}" for w in caught]}
    meas = study.section("measurements") or {}
    # the names only (a tracked section records them so; a plain dict has no names())
    names = meas.names() if hasattr(meas, "names") else list(meas)
    others = [n for n in names if meas[n]["kind"] == "multi-point"]
    if others:
        result["tests"] = {}
    for name in others:
        m = meas[name]
        where = f"measurements.{name}"
        b = (float(m["fmin_hz"] if m.get("fmin_hz") is not None else band[0]),
             float(m["fmax_hz"] if m.get("fmax_hz") is not None else band[1]))
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            f_b, r_b, note_b, src_b = _identify_test(
                study, m, b, where, multipoint_file(name, "file"),
                lambda k, name=name: multipoint_file(name, f"set_{k}"))
        entry = _test_summary(f_b, r_b, note_b, src_b, b)
        entry["warnings"] = [f"{name}: {w.category.__name__}: {w.message}" for w in caught]
        entry["comparison"] = compare_tests(res.fn_hz, res.zeta, shapes, r_b.fn_hz,
                                            r_b.zeta, r_b.real_shapes,
                                            float(cfg["pair_within"]))
        result["tests"][name] = entry
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
