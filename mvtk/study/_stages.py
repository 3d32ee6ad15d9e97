"""The stages of a study. Each returns ``(result: dict, arrays: xarray.Dataset | None)``.

The stages only call the public (or documented private) APIs of the other subpackages;
they hold no physics of their own beyond bookkeeping (pairing tables, load vectors of the
pin-force actuator model, settling-time and spectrum post-processing of simulations).
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np

from ..errors import ConfigError
from ._config import Study

__all__ = ["ingest", "fe_nominal", "damping", "updating", "reduction", "control"]


def _warning_messages(caught) -> list[str]:
    return [f"{w.category.__name__}: {w.message}" for w in caught]


# ----------------------------------------------------------------------------- ingest
def ingest(study: Study):
    """Read every measurement file with :func:`mvtk.io.read`; keep the configured channels."""
    import xarray as xr

    import mvtk.io

    meas = study.section("measurements") or {}
    rows, arrays = [], {}
    for test, path in study.measurement_files.items():
        ds = mvtk.io.read(path)
        th = ds["time_history"]
        wanted = ([meas[test]["reference"], meas[test]["response"]] if test == "impact"
                  else [meas[test]["channel"]])
        names = [str(c) for c in th["channel"].values]
        missing = [w for w in wanted if w not in names]
        if missing:
            raise ConfigError(f"measurements.{test}: channels {missing} not in {path.name}; "
                              f"the file has {names}")
        th = th.sel(channel=wanted)
        fs = 1.0 / float(th["time"].values[1] - th["time"].values[0])
        for ch in wanted:
            c = th.sel(channel=ch)
            rows.append({"test": test, "file": path.name, "channel": ch,
                         "quantity": str(c["quantity"].values) if "quantity" in c.coords else "",
                         "units": str(c["units"].values) if "units" in c.coords else "",
                         "fs_hz": fs, "n_samples": int(th.sizes["time"]),
                         "duration_s": th.sizes["time"] / fs})
        keep = {k: th[k].values for k in ("quantity", "units") if k in th.coords}
        arrays[test] = xr.DataArray(
            th.values, dims=(f"{test}_channel", f"{test}_time"),
            coords={f"{test}_channel": wanted, f"{test}_time": th["time"].values,
                    **{f"{test}_{k}": (f"{test}_channel", v.astype(str))
                       for k, v in keep.items()}},
        )
    return {"channels": rows}, xr.Dataset(arrays)


def _time_history(arrays, test: str):
    """Rebuild the ("channel", "time") DataArray of ``test`` from the ingest arrays."""
    import xarray as xr

    a = arrays[test]
    coords = {"channel": a[f"{test}_channel"].values, "time": a[f"{test}_time"].values}
    for k in ("quantity", "units"):
        name = f"{test}_{k}"
        if name in a.coords:
            coords[k] = ("channel", a[name].values.astype(str))
    return xr.DataArray(a.values, dims=("channel", "time"), coords=coords, name="time_history")


# ------------------------------------------------------------------------- FE nominal
def _uz_shapes(model, shapes: np.ndarray) -> np.ndarray:
    from ..fe import DOF_NAMES

    full = model.expand(shapes)  # (n_nodes, 6, k)
    return full[:, DOF_NAMES.index("uz"), :]


def fe_nominal(study: Study):
    """Nominal FE model: sizes, lowest modes, effective masses, mode shapes (uz)."""
    import xarray as xr

    from ..fe import build_model, modal_analysis
    from ..reduction import effective_mass

    n_modes = int((study.section("fe") or {}).get("n_modes", 6))
    model = build_model(study.structure_file)
    modes = modal_analysis(model, n_modes)
    em = effective_mass(model, "uz", n_modes=n_modes)
    result = {
        "n_nodes": model.n_nodes, "n_elements": model.n_elements, "n_dof": model.n_dof,
        "fn_hz": modes.fn_hz, "mode_type": list(modes.mode_type),
        "mass_fraction_uz": em.fraction, "total_mass_kg": em.total_mass_kg,
    }
    ds = xr.Dataset({
        "nodes": (("node", "xyz"), model.nodes),
        "uz": (("node", "mode"), _uz_shapes(model, modes.shapes)),
    })
    return result, ds


# ---------------------------------------------------------------------------- damping
def damping(study: Study, arrays, fe: dict):
    """Half-power on the impact FRF, envelope fit on the free decay, Rayleigh fits."""
    import xarray as xr

    import mvtk.damping as md
    import mvtk.signal as ms

    cfg = study.section("damping") or {}
    meas = study.section("measurements") or {}
    fn_guess = [float(f) for f in cfg["fn_hz"]]
    result: dict[str, Any] = {"fn_guess_hz": fn_guess}
    out = {}
    zeta_hp = fn_hp = None
    if "impact" in meas:
        m = meas["impact"]
        th = _time_history(arrays, "impact")
        fs = 1.0 / float(th["time"].values[1] - th["time"].values[0])
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            fr = ms.frf(th, reference=m["reference"], response=m["response"],
                        excitation="impact", nperseg=int(round(m["record_s"] * fs)),
                        force_window_s=m.get("force_window_s"))
            hp = md.half_power(fr, fn_hz=fn_guess,
                               method=cfg.get("half_power_method", "interpolate"))
        result["half_power"] = hp.to_dataframe().to_dict(orient="list")
        result["half_power_warnings"] = _warning_messages(caught)
        result["frf_attrs"] = {k: v for k, v in fr.attrs.items()
                               if isinstance(v, str | int | float)}
        fn_hp, zeta_hp = np.asarray(hp.fn_hz), np.asarray(hp.zeta)
        H = fr["frf"].isel(response=0, reference=0)
        f = fr["frequency"].values
        band = (f >= 0.5 * min(fn_guess)) & (f <= 1.3 * max(fn_guess))
        out["frf_abs"] = (("frequency",), np.abs(H.values[band]))
        out["frequency"] = f[band]
        if "coherence" in fr:
            out["coherence"] = (("frequency",),
                                fr["coherence"].isel(response=0, reference=0).values[band])
        result["frf_units"] = str(H["units"].values) if "units" in H.coords else ""
        fit = md.rayleigh_fit(fn_hp, zeta_hp, "two_mode")
        result["rayleigh_half_power"] = {"alpha": fit.alpha, "beta": fit.beta,
                                         "zeta_fit": fit.zeta_fit}
        # Chowdhury: anchors by effective mass of the paired nominal FE modes
        frac = np.asarray(fe["mass_fraction_uz"], dtype=float)[: len(fn_hp)]
        try:
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                ch = md.rayleigh_fit(fn_hp, zeta_hp, "chowdhury", mass_fraction=frac,
                                     target_mass=float(cfg.get("chowdhury_target_mass", 0.95)))
            result["rayleigh_chowdhury"] = {"alpha": ch.alpha, "beta": ch.beta,
                                            "zeta_fit": ch.zeta_fit,
                                            "anchors": list(ch.anchors),
                                            "mass_fraction": frac,
                                            "warnings": _warning_messages(caught)}
        except (ValueError, RuntimeError) as err:  # MvtkError subclasses these
            result["rayleigh_chowdhury"] = {"error": str(err)}
    if "decay" in meas:
        m = meas["decay"]
        th = _time_history(arrays, "decay")
        band = tuple(m["band_hz"]) if m.get("band_hz") else None
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            env = md.envelope_fit(th, fn_guess[0], channel=m["channel"], band_hz=band)
            logd = md.log_decrement(th, fn_guess[0], channel=m["channel"], band_hz=band)
        result["envelope"] = env.to_dataframe().to_dict(orient="list")
        result["log_decrement"] = logd.to_dataframe().to_dict(orient="list")
        result["decay_warnings"] = _warning_messages(caught)
        x = th.sel(channel=m["channel"]).values
        t = th["time"].values
        step = max(1, len(t) // 6000)
        out["decay_t"] = (("decay_time",), t[::step])
        out["decay_x"] = (("decay_time",), x[::step])
        result["decay_units"] = str(th["units"].values[0]) if "units" in th.coords else ""
    if zeta_hp is not None:
        model_damping = cfg.get("model_damping", "half_power")
        pair = result.get(f"rayleigh_{model_damping}", {})
        if "alpha" not in pair:
            pair = result["rayleigh_half_power"]
            model_damping = "half_power"
        result["model_damping"] = {"method": model_damping, "alpha": pair["alpha"],
                                   "beta": pair["beta"]}
    return result, (xr.Dataset(out) if out else None)


# --------------------------------------------------------------------------- updating
def updating(study: Study):
    """Sensitivity-based update of the configured parameters to the target frequencies."""
    from ..fe import load_structure
    from ..updating import FrequencyTarget, Parameter, update

    cfg = study.section("updating")
    desc = load_structure(study.structure_file)
    params = []
    for p in cfg["parameters"]:
        path = p["path"]
        if "initial" in p:
            # a field absent from the nominal description (e.g. an elastic clamp) starts
            # at the configured value
            head, _, leaf = path.rpartition(".")
            node = desc
            for part in head.split(".") if head else []:
                node = node.setdefault(part, {})
            node.setdefault(leaf, float(p["initial"]))
        params.append(Parameter(path, initial=p.get("initial"), lower=p.get("lower"),
                                upper=p.get("upper")))
    targets = [FrequencyTarget(float(f), label=f"f{i + 1}")
               for i, f in enumerate(cfg["targets_hz"])]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        res = update(desc, params, targets, max_iter=int(cfg.get("max_iter", 30)))
    result = {
        "success": bool(res.success), "message": str(res.message),
        "parameters": [p.path for p in params],
        "initial_values": res.initial_values, "values": res.values, "std": res.std,
        "at_bound": res.at_bound,
        "targets_hz": [float(f) for f in cfg["targets_hz"]],
        "fn_hz_initial": res.fn_hz_initial, "fn_hz": res.fn_hz,
        "modes": res.modes, "model_fn_hz": res.model_fn_hz,
        "model_kinds": list(res.model_kinds),
        "identifiable": bool(res.identifiable), "condition_number": res.condition_number,
        "n_evaluations": res.n_evaluations,
        "description": res.description,
        "warnings": _warning_messages(caught),
    }
    return result, None


# -------------------------------------------------------------------------- reduction
def reduction(study: Study, description: dict, model_damping: dict | None):
    """Craig-Bampton SE of the (updated) model, FE-vs-SE checks, and the SE plant."""
    import xarray as xr

    from ..control._plant import dof_load, dof_output, structural_plant
    from ..fe import build_model, modal_analysis
    from ..reduction import craig_bampton, verify

    cfg = study.section("reduction")
    ctl = study.section("control") or {}
    model = build_model(description)
    named = {str(r["name"]): model.nearest_node(r["xyz"]) for r in cfg["retained"]}
    se = craig_bampton(model, retained=list(named.values()), n_modes=int(cfg.get("n_modes",
                                                                              10)))
    n_cmp = int(cfg.get("n_compare", 4))
    ver = verify(model, se, n=n_cmp)
    result = {
        "retained_nodes": named,
        "retained_xyz": {k: model.nodes[v].tolist() for k, v in named.items()},
        "sizes": ver.sizes.to_dataframe().rename_axis("quantity").reset_index()
        .to_dict(orient="list")
        if hasattr(ver.sizes, "to_dataframe") else {},
        "modes": ver.modes.to_dataframe().to_dict(orient="list"),
        "static": ver.static.to_dataframe().to_dict(orient="list")
        if hasattr(ver.static, "to_dataframe") else {},
        "se_n_dof": int(se.n_dof), "se_labels": list(se.labels),
        "interior_fn_hz": se.interior_fn_hz,
    }
    ds = None
    if ctl and model_damping is not None:
        x0, x1 = (named[n] for n in ctl["actuator_nodes"])
        # pin-force model: equal and opposite moments about y at the patch ends (N m per
        # unit input); positive input bends the tip towards +z.
        load = dof_load(model, x1, "ry", 1.0) - dof_load(model, x0, "ry", 1.0)
        tip = named[ctl["sensor_node"]]
        # modal form: shell drilling rotations of the boundary have no inertia, so the
        # physical-form mass matrix is singular
        plant = structural_plant(se, inputs={"actuator": load},
                                 outputs={"tip": (tip, "uz")},
                                 alpha=float(model_damping["alpha"]),
                                 beta=float(model_damping["beta"]), form="modal",
                                 static_correction=False,  # all SE modes are kept
                                 input_units=["N m"], output_units=["m"])
        coords = list(plant.coords)
        ds = xr.Dataset({
            k: (("coord", "coord2"), getattr(plant, k)) for k in ("M", "C", "K")
        } | {
            "B": (("coord", "input"), plant.B),
            "Cq": (("output", "coord"), plant.Cq),
            "Cv": (("output", "coord"), plant.Cv),
            "D": (("output", "input"), plant.D),
        }, coords={"coord": coords, "coord2": coords, "input": list(plant.inputs),
                   "output": list(plant.outputs)})
        fe_modes = modal_analysis(model, n_cmp)
        result["fe_fn_hz_updated"] = fe_modes.fn_hz
        _ = dof_output  # documented helper, kept for symmetry with dof_load
    return result, ds


# ---------------------------------------------------------------------------- control
def _amplitude_spectrum(y: np.ndarray, fs: float) -> tuple[np.ndarray, np.ndarray]:
    n = len(y)
    a = np.abs(np.fft.rfft(y)) * 2.0 / n
    return np.fft.rfftfreq(n, 1.0 / fs), a


def control(study: Study, plant_arrays, fn1_hz: float):
    """Open loop and each controller on the SE plant, released from mode 1."""
    import xarray as xr

    import mvtk.control as mc

    from ..control import (  # noqa: F401 - looked up by name below
        PPF,
        SRF,
        LyapunovBangBang,
        StructuralPlant,
        VelocityFeedback,
        added_damping,
        closed_loop_modes,
        release_state,
        settling_time,
        simulate,
    )

    cfg = study.section("control")
    pa = plant_arrays
    plant = StructuralPlant(
        pa["M"].values, pa["C"].values, pa["K"].values, pa["B"].values, pa["Cq"].values,
        pa["Cv"].values, inputs=[str(v) for v in pa["input"].values],
        outputs=[str(v) for v in pa["output"].values],
        coords=[str(v) for v in pa["coord"].values], input_units=["N m"],
        output_units=["m"], D=pa["D"].values,
    )
    x0 = release_state(plant, 1, "tip", float(cfg["initial_tip_displacement_m"]))
    t_end, fs = float(cfg["t_end_s"]), float(cfg["fs_out"])
    band = float(cfg["settle_band"])
    runs = {"open loop": None}
    methods = {"open loop": "auto"}
    open_sim = simulate(plant, None, t_end=t_end, fs_out=fs, initial=x0)
    n = plant.n_coords
    # generalised actuator force times velocity, B' q', of the open loop (for a boundary
    # layer given relative to its initial amplitude)
    switching = plant.B[:, 0] @ open_sim["states"].values[n:, :]
    switching_peak = float(np.max(np.abs(switching)))
    for c in cfg.get("controllers", []):
        kind = c["type"]
        if kind in ("PPF", "SRF"):
            ctrl = getattr(mc, kind)(targets=[(float(c["f_hz"]), float(c["zeta_f"]),
                                               float(c["gain"]))],
                                     u_max=c.get("u_max"))
        elif kind == "VelocityFeedback":
            ctrl = VelocityFeedback(float(c["gain"]), u_max=c.get("u_max"))
        else:
            eps = (float(c["boundary_layer"]) if "boundary_layer" in c
                   else float(c["boundary_layer_rel"]) * switching_peak)
            ctrl = LyapunovBangBang(u_max=float(c["u_max"]), boundary_layer=eps)
        runs[str(c["name"])] = ctrl
        methods[str(c["name"])] = str(c.get("method", "auto"))
    rows, series, inputs = [], {}, {}
    amp0 = float(cfg["initial_tip_displacement_m"])
    t = None
    for name, ctrl in runs.items():
        sim = open_sim if ctrl is None else simulate(plant, ctrl, t_end=t_end, fs_out=fs,
                                                     initial=x0, method=methods[name])
        y = sim["outputs"].sel(output="tip").values
        u = sim["inputs"].values[0] if "inputs" in sim else np.zeros_like(y)
        t = sim["time"].values
        series[name], inputs[name] = y, u
        zeta_cl = fn_cl = float("nan")
        if ctrl is None:
            om = closed_loop_modes(plant)
            osc = om.eigenvalues.imag > 0
            zeta_cl, fn_cl = float(om.zeta[osc][0]), float(om.fn_hz[osc][0])
        elif kind_linear(ctrl) and getattr(ctrl, "u_max", None) is None:
            ad = added_damping(plant, ctrl, 1)
            zeta_cl, fn_cl = ad["zeta_closed"], ad["fn_hz_closed"]
        f, a = _amplitude_spectrum(y, fs)
        rows.append({"controller": name,
                     "settling_time_s": settling_time(y, t, band=band, reference=amp0),
                     "zeta_mode1": zeta_cl, "fn_mode1_hz": fn_cl,
                     "peak_tip_m_after_1s": float(np.max(np.abs(y[t >= 1.0]))),
                     "peak_actuator_Nm": float(np.max(np.abs(u))),
                     "spectrum_peak_m": float(np.max(a[(f > 0.8 * fn1_hz) & (f < 1.2 * fn1_hz)]))})
    ref = rows[0]["spectrum_peak_m"]
    for r in rows:
        r["peak_reduction_db"] = float(20 * np.log10(ref / r["spectrum_peak_m"]))
    f, _ = _amplitude_spectrum(series["open loop"], fs)
    ds = xr.Dataset(
        {"tip": (("run", "time"), np.array([series[k] for k in series])),
         "actuator": (("run", "time"), np.array([inputs[k] for k in inputs])),
         "spectrum": (("run", "frequency"),
                      np.array([_amplitude_spectrum(series[k], fs)[1] for k in series]))},
        coords={"run": list(series), "time": t, "frequency": f},
    )
    return {"metrics": rows, "settle_band": band, "fs_out": fs, "t_end_s": t_end,
            "switching_peak": switching_peak,
            "controllers": {k: repr(v) for k, v in runs.items()}}, ds


def kind_linear(ctrl) -> bool:
    """True for the linear controllers (closed-loop poles exist)."""
    return type(ctrl).__name__ in ("PPF", "SRF", "VelocityFeedback", "LQR")
