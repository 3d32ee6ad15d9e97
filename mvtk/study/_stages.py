"""The stages of a study. Each returns ``(result: dict, arrays: xarray.Dataset | None)``.

The stages only call the public (or documented private) APIs of the other subpackages;
they hold no physics of their own beyond bookkeeping (pairing tables, load vectors of the
pin-force actuator model, settling-time and spectrum post-processing of simulations).
"""

from __future__ import annotations

import dataclasses
import warnings
from typing import Any

import numpy as np

from ..errors import ConfigError
from ._config import Study

__all__ = ["ingest", "fe_nominal", "damping", "updating", "uncertainty", "reduction",
           "control", "pair_targets", "nominal_modes"]


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
        ds = mvtk.io.read(path, **dict(meas[test].get("read_options") or {}))
        th = ds["time_history"]
        wanted = ([meas[test]["reference"], meas[test]["response"]]
                  if meas[test].get("kind") != "decay" else [meas[test]["channel"]])
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
    model = build_model(study.description())
    modes = modal_analysis(model, n_modes)
    em = effective_mass(model, "uz", n_modes=n_modes, modes=modes)   # the same modes
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
def _impact_half_power(arrays, test: str, m: dict, fn_guess: list[float], method: str):
    """Half-power damping of an impact test with :func:`mvtk.damping.estimate`.

    The same function and defaults as ``mvtk damping FILE``: the record (``record_s``)
    and the force window are chosen from the data unless the section sets them. Returns
    ``(FRF dataset, table dict, warnings, settings)``; ``settings`` holds what decided
    the numbers and the equivalent ``mvtk damping`` options.
    """
    import mvtk.damping as md

    th = _time_history(arrays, test)
    fs = 1.0 / float(th["time"].values[1] - th["time"].values[0])
    nperseg = None if m.get("record_s") is None else int(round(m["record_s"] * fs))
    fw = m.get("force_window_s")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        est = md.estimate(th, method="half_power", variant=method, fn_hz=fn_guess,
                          reference=m["reference"], channel=[m["response"]],
                          excitation="impact", nperseg=nperseg,
                          force_window_s="auto" if fw is None else fw)
    settings = {k: (v.item() if hasattr(v, "item") else v) for k, v in est.settings.items()
                if isinstance(v, str | int | float | list | tuple | type(None))
                or hasattr(v, "item")}
    opts = [f"--reference {m['reference']}", f"--channel {m['response']}", "--impact",
            "--method half_power", f"--variant {est.variant}",
            "--fn " + " ".join(repr(float(f)) for f in fn_guess)]
    if nperseg is not None:
        opts.append(f"--nperseg {nperseg}")
    if fw is not None:
        opts.append(f"--force-window {float(fw)!r}")
    settings["command_options"] = " ".join(opts)
    settings["force_window_given"] = fw is not None
    return est.frf, est.table.to_dict(orient="list"), _warning_messages(caught), settings


def _modes_to_cover(f_top: float, known_fn_hz=None) -> int:
    """Number of FE modes expected below ``f_top`` (Hz), with a margin, in 8..30.

    From known frequencies of (nearly) the same model: their count scaled linearly to
    ``f_top`` (a plate's modal density is constant, a beam's falls with frequency, so
    linear scaling over-counts rather than under-counts), plus 3.
    """
    f = np.asarray(known_fn_hz if known_fn_hz is not None else [], dtype=float)
    f = f[np.isfinite(f) & (f > 0)]
    if not f.size:
        return 8
    return int(np.clip(np.ceil(f.size * f_top / f.max()) + 3, 8, 30))


def _paired_mass_fractions(description: dict, fn_hz: np.ndarray, known_fn_hz=None) -> dict:
    """Effective mass fraction (uz) of the FE mode nearest to each identified mode.

    The FE model of ``description`` (the updated one when updating ran) is solved for
    enough modes to cover 1.3 times the highest identified frequency (at most 30); the
    count is estimated from ``known_fn_hz`` (lowest frequencies of the model, Hz), so
    one solve usually suffices, and raised by 8 until the modes cover it.
    """
    from ..fe import build_model
    from ..reduction import effective_mass

    model = build_model(description)
    f_top = 1.3 * float(np.max(fn_hz))
    n = _modes_to_cover(f_top, known_fn_hz)
    while True:
        em = effective_mass(model, "uz", n_modes=n)
        if em.fn_hz[-1] >= f_top or n >= 30:
            break
        n = min(30, n + 8)
    fe_fn = np.asarray(em.fn_hz, dtype=float)
    idx = [int(np.argmin(np.abs(fe_fn - f))) for f in fn_hz]
    return {"fe_mode": [i + 1 for i in idx], "fe_fn_hz": fe_fn[idx].tolist(),
            "pair_error_rel": (fe_fn[idx] / fn_hz - 1.0).tolist(),
            "mass_fraction": np.asarray(em.fraction, dtype=float)[idx].tolist(),
            "fe_mass_fraction_all": np.asarray(em.fraction, dtype=float).tolist(),
            "fe_fn_hz_all": fe_fn.tolist()}


def _first_of_each_mode(fn_hz: np.ndarray, rel: float = 0.02) -> np.ndarray:
    """True for each row whose frequency is not within ``rel`` of an earlier row's."""
    keep = np.ones(fn_hz.size, dtype=bool)
    for i in range(fn_hz.size):
        prev = fn_hz[:i][keep[:i] & np.isfinite(fn_hz[:i])]
        if np.isfinite(fn_hz[i]) and prev.size and np.min(np.abs(prev / fn_hz[i] - 1)) <= rel:
            keep[i] = False
    return keep


def damping(study: Study, arrays, description: dict, known_fn_hz=None):
    """Half-power on the impact FRFs, envelope fit on the free decays, Rayleigh fits.

    Every impact-kind measurement gives a half-power estimate (:func:`mvtk.damping.
    estimate`, the estimator of ``mvtk damping``) of the modes it searches: its own
    ``fn_hz``, else ``damping.fn_hz`` (``damping.broadband_fn_hz`` for the one named
    ``broadband``); the one named ``impact`` comes first. Every decay-kind measurement
    gives an envelope fit and a logarithmic decrement of its mode (``fn_hz``, else the
    first of ``damping.fn_hz``); the first decay is the one of the paper's Table 3. The
    Rayleigh fits use each mode once (its first estimate). Rayleigh pairs: the
    paper's two-mode fit of modes 1 and 2 ("half-power"), the least-squares fit over all
    identified modes, and the Chowdhury pair (anchors by the effective mass of the FE
    modes of ``description`` paired with the identified ones by frequency).
    ``known_fn_hz`` (Hz): the lowest frequencies of that model from an earlier stage,
    used only to size its eigen solve.
    """
    import xarray as xr

    import mvtk.damping as md

    cfg = study.section("damping") or {}
    meas = study.section("measurements") or {}
    fn_guess = [float(f) for f in cfg["fn_hz"]]
    bb_guess = [float(f) for f in cfg.get("broadband_fn_hz", [])]
    method = cfg.get("half_power_method", "fit")
    result: dict[str, Any] = {"fn_guess_hz": fn_guess, "broadband_fn_guess_hz": bb_guess}
    out = {}
    zeta_hp = fn_hp = None
    # every impact-kind test, the one named "impact" first (the long record of the
    # paper's Table 3), the others in the order of the file
    # the test names (not the whole table: a path written otherwise must not change the
    # cache key), in the order of the file
    names = list(study.measurement_files)
    impacts = sorted((n for n in names if meas[n]["kind"] == "impact"),
                     key=lambda n: n != "impact")
    runs = []
    for name in impacts:
        m = meas[name]
        guess = m.get("fn_hz") or (bb_guess if name == "broadband" else fn_guess)
        if guess:
            runs.append((name, [float(f) for f in guess]))
    if runs:
        result["half_power_settings"] = {}
        result["half_power_warnings"] = []
        result["fn_guess_by_test"] = {n: g for n, g in runs}
        hp_d = None
        for k, (name, guess) in enumerate(runs):
            fr_k, d_k, warns, sett = _impact_half_power(arrays, name, meas[name], guess,
                                                        method)
            result["half_power_settings"][name] = sett
            d_k["test"] = [name] * len(guess)
            if k == 0:
                fr, hp_d = fr_k, d_k
                result["half_power_warnings"] += warns
                primary_guess = guess
                continue
            for key in hp_d:
                hp_d[key] = list(hp_d[key]) + (list(d_k[key]) if key in d_k
                                               else [float("nan")] * len(guess))
            result["half_power_warnings"] += [f"{name} test: {w}" for w in warns]
            if name == "broadband":
                H = fr_k["frf"].isel(response=0, reference=0)
                out["frequency_bb"] = fr_k["frequency"].values
                out["frf_abs_bb"] = (("frequency_bb",), np.abs(H.values))
        fn_guess = primary_guess
        hp_d["mode"] = list(range(len(hp_d["fn_hz"])))
        result["half_power"] = hp_d
        result["frf_attrs"] = {k: v for k, v in fr.attrs.items()
                               if isinstance(v, str | int | float)}
        fn_hp, zeta_hp = np.asarray(hp_d["fn_hz"], float), np.asarray(hp_d["zeta"], float)
        # the Rayleigh fits take each mode once: the first test's estimate of it (the
        # same mode from another test is a consistency check of the report)
        ok = np.isfinite(fn_hp) & np.isfinite(zeta_hp) & _first_of_each_mode(fn_hp)
        H = fr["frf"].isel(response=0, reference=0)
        f = fr["frequency"].values
        band = (f >= 0.5 * min(fn_guess)) & (f <= 1.3 * max(fn_guess))
        out["frf_abs"] = (("frequency",), np.abs(H.values[band]))
        out["frequency"] = f[band]
        if "coherence" in fr:
            out["coherence"] = (("frequency",),
                                fr["coherence"].isel(response=0, reference=0).values[band])
        result["frf_units"] = str(H["units"].values) if "units" in H.coords else ""
        # the paper's pair: two-mode closed form through modes 1 and 2
        fit = md.rayleigh_fit(fn_hp[:2], zeta_hp[:2], "two_mode")
        result["rayleigh_half_power"] = {"alpha": fit.alpha, "beta": fit.beta,
                                         "zeta_fit": list(fit.alpha / (4 * np.pi * fn_hp)
                                                          + fit.beta * np.pi * fn_hp)}
        if ok.sum() >= 3:
            ls = md.rayleigh_fit(fn_hp[ok], zeta_hp[ok], "least_squares")
            result["rayleigh_least_squares"] = {
                "alpha": ls.alpha, "beta": ls.beta, "n_modes": int(ok.sum()),
                "zeta_fit": list(ls.alpha / (4 * np.pi * fn_hp) + ls.beta * np.pi * fn_hp)}
        # Chowdhury: anchors by effective mass of the paired (updated) FE modes
        target = float(cfg.get("chowdhury_target_mass", 0.95))
        try:
            pair = _paired_mass_fractions(description, fn_hp[ok], known_fn_hz)
            frac = np.asarray(pair["mass_fraction"])
            reached = float(np.sum(frac))
            used, note = target, ""
            if reached < target - 1e-12:
                used = reached
                note = (f"the identified modes hold {reached:.3f} of the effective mass (uz), "
                        f"below the target {target:g} (and below EN 1998's 0.90): the upper "
                        f"anchor is the mode at which the highest reached fraction "
                        f"{reached:.3f} is attained")
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                ch = md.rayleigh_fit(fn_hp[ok], zeta_hp[ok], "chowdhury", mass_fraction=frac,
                                     target_mass=min(used, 1.0))
            ids = np.flatnonzero(ok)
            result["rayleigh_chowdhury"] = {
                "alpha": ch.alpha, "beta": ch.beta,
                "zeta_fit": list(ch.alpha / (4 * np.pi * fn_hp) + ch.beta * np.pi * fn_hp),
                "anchors": [int(ids[i]) for i in ch.anchors],
                "target_mass": target, "target_used": used, "mass_reached": reached,
                "note": note, "pairing": pair, "mass_fraction": frac.tolist(),
                "warnings": _warning_messages(caught)}
        except (ValueError, RuntimeError) as err:  # MvtkError subclasses these
            result["rayleigh_chowdhury"] = {"error": str(err)}
    decays = [n for n in names if meas[n]["kind"] == "decay"]
    result["decays"] = {}
    for k, name in enumerate(decays):
        m = meas[name]
        th = _time_history(arrays, name)
        band = tuple(m["band_hz"]) if m.get("band_hz") else None
        f0 = float(m["fn_hz"]) if m.get("fn_hz") is not None else fn_guess[0]
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            env = md.envelope_fit(th, f0, channel=m["channel"], band_hz=band)
            logd = md.log_decrement(th, f0, channel=m["channel"], band_hz=band)
        one = {"envelope": env.to_dataframe().to_dict(orient="list"),
               "log_decrement": logd.to_dataframe().to_dict(orient="list"),
               "warnings": _warning_messages(caught), "fn_guess_hz": f0,
               "channel": m["channel"],
               "settings": {"method": "envelope", "variant": "hilbert", "fn_hz": f0,
                            "band_hz": band,
                            "command_options": f"--channel {m['channel']} --method envelope "
                            f"--fn {float(f0)!r}" + ("" if band is None else
                                                    f" --band {float(band[0])!r} "
                                                    f"{float(band[1])!r}")}}
        result["decays"][name] = one
        if k:
            continue
        result["envelope"] = one["envelope"]
        result["log_decrement"] = one["log_decrement"]
        x = th.sel(channel=m["channel"]).values
        t = th["time"].values
        step = max(1, len(t) // 6000)
        out["decay_t"] = (("decay_time",), t[::step])
        out["decay_x"] = (("decay_time",), x[::step])
        result["decay_units"] = str(th["units"].values[0]) if "units" in th.coords else ""
    result["decay_warnings"] = [w if k == 0 else f"{name} test: {w}"
                                for k, name in enumerate(decays)
                                for w in result["decays"][name]["warnings"]]
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
def _affine_parameters(desc: dict, paths: list[str]) -> bool:
    """True when K and M of a ``type = "plate"`` structure are affine in every path.

    On a fixed mesh the plate's laminate stiffness (ABD and shear about the fixed
    base mid-plane) is linear in each isotropic or piezo modulus ``materials.<m>.E``,
    the mass in each density ``materials.<m>.rho``, and K in the clamp and spring
    stiffnesses; :func:`mvtk.updating.update` with ``affine=True`` then forms K and M
    from two builds per parameter instead of building every evaluation and its
    difference steps (the smart beam: 4 builds instead of 71, 19 eigen solves instead
    of 23, and 4.6 s instead of 10.2 s CPU at load 5), and checks the assumption by a
    real build at the solution (``affine_check_rel``, a warning above 1e-6). Thickness,
    Poisson ratio, geometry, orthotropic moduli (``E1``, ``E2`` enter through
    ``nu21 = nu12 E2 / E1``) and other structure types are not affine.
    """
    if (desc.get("structure") or {}).get("type", "plate") != "plate" or not paths:
        return False
    mats = desc.get("materials") or {}
    for path in paths:
        parts = path.split(".")
        if (len(parts) == 3 and parts[0] == "materials" and parts[2] in ("E", "rho")
                and isinstance(mats.get(parts[1]), dict) and "E" in mats[parts[1]]):
            continue
        if path in ("boundary.clamp_stiffness", "boundary.clamp_translational_stiffness"):
            continue
        if (len(parts) == 4 and parts[:2] == ["boundary", "springs"]
                and parts[2].isdigit() and parts[3] == "k"):
            continue
        return False
    return True


def nominal_modes(model, f_top_hz: float, n_min: int = 8, n_max: int = 60):
    """Modes of ``model`` up to at least ``f_top_hz`` (Hz), at most ``n_max`` of them.

    Solves for ``n_min`` modes and raises the count by 8 until the highest mode reaches
    ``f_top_hz`` (or the model has no more free DOFs).
    """
    from ..fe import modal_analysis

    n = max(1, min(int(n_min), model.n_dof))
    while True:
        modes = modal_analysis(model, n)
        if modes.fn_hz[-1] >= f_top_hz or n >= min(n_max, model.n_dof):
            return modes
        n = min(n + 8, n_max, model.n_dof)


def pair_targets(desc: dict, targets: list, builder, model=None):
    """Fix the FE mode of every target without one by pairing on the nominal model.

    A target that names its ``mode`` keeps it; one with a measured shape is paired by MAC
    (and stays paired by MAC at every evaluation of the update); every other target is
    paired one-to-one with the nominal FE mode nearest in frequency
    (:func:`mvtk.updating.pair_modes` with ``rest="frequency"``, mode types respected),
    and that mode is written into the target, so a measurement that missed a mode
    cannot shift the pairing to the next mode in order.

    Returns
    -------
    (list of FrequencyTarget, list of dict)
        The targets (with ``mode`` set where paired by frequency) and one row per target:
        ``target``, ``fn_hz``, ``fe_mode`` (1-based), ``fe_fn_hz`` (nominal model),
        ``df_pct``, ``paired_by`` (``fixed``, ``mac``, ``frequency``) and ``mac``.
    """
    import dataclasses

    from ..updating import classify_modes, pair_modes, target_mac

    if not targets:
        return targets, []
    model = builder(desc) if model is None else model
    need = max([t.mode or 0 for t in targets] + [len(targets) + 4, 8])
    f_top = 1.3 * max(t.fn_hz for t in targets)
    modes = nominal_modes(model, f_top, n_min=need)
    # the update numbers elastic modes only: rigid-body modes (below 1 % of the lowest
    # target, as mvtk.updating.update drops them) are not counted
    elastic = np.asarray(modes.fn_hz) >= 0.01 * min(t.fn_hz for t in targets)
    fn = np.asarray(modes.fn_hz, dtype=float)[elastic]
    vectors = np.asarray(modes.shapes)[:, elastic]
    kinds = (classify_modes(model, vectors) if any(t.kind for t in targets) else None)
    macm = (target_mac(model, vectors, targets) if any(t.has_shape for t in targets)
            else None)
    pr = pair_modes(targets, fn, macm, kinds, rest="frequency")
    out, rows = [], []
    for i, t in enumerate(targets):
        m = int(pr.modes[i])
        if pr.method[i] == "frequency":
            t = dataclasses.replace(t, mode=m + 1)
        out.append(t)
        f_fe = float(fn[m])
        rows.append({"target": t.label or f"f{i + 1}", "fn_hz": float(t.fn_hz),
                     "fe_mode": m + 1, "fe_fn_hz": f_fe,
                     "df_pct": 100.0 * (f_fe / t.fn_hz - 1.0), "paired_by": pr.method[i],
                     "mac": float(pr.mac[i])})
    return out, rows


def identifiability(res, paths: list[str], cond_max: float) -> dict:
    """The study's identifiability verdict of an update, from its log-sensitivities.

    ``S = d ln f / d ln p`` (targets x free parameters, :attr:`UpdateResult.sensitivity`)
    is the Jacobian of the log-frequencies in log-parameters: ``S'S`` is the Fisher
    matrix for a uniform relative frequency error, ``S'WS`` for targets of relative
    standard deviations ``s_i`` (``W = diag(s_min^2 / s_i^2)``, the update's weights
    scaled to 1 for the best-known target: equal standard deviations give ``S'S``); its
    rows are weighted so. The update is *identifiable* when
    :func:`mvtk.updating.update` found no null direction, no parameter ended on a bound,
    and ``cond(S) = s_max / s_min <= cond_max`` (a relative frequency error ``e`` moves
    the weakest parameter combination by up to ``cond(S) e / s_max``). Otherwise the
    parameter combination the frequencies do determine is stated: the right singular
    vector of ``s_max``, as a product of powers ``p1^a1 p2^a2 ...`` (largest ``|a|``
    = 1). A single free parameter with a nonzero sensitivity is always identifiable
    unless it ends on a bound.

    Returns
    -------
    dict
        ``identifiable_study`` (bool), ``log_condition_number``, ``not_identifiable_why``
        (str, empty when identifiable) and ``identifiable_combination`` (str).
    """
    S = np.asarray(res.sensitivity, dtype=float)
    sd = getattr(res, "target_std_hz", None)
    if sd is not None and S.ndim == 2:
        rel = np.asarray(sd, dtype=float) / np.array([t.fn_hz for t in res.targets])
        if rel.size == S.shape[0] and np.all(np.isfinite(rel) & (rel > 0)):
            S = S * (rel.min() / rel)[:, None]
    free = [p for p, prm in zip(paths, res.parameters) if not prm.fixed]
    at_bound = [p for p, b in zip(paths, np.asarray(res.at_bound, bool)) if b]
    why = []
    cond, combo = float("nan"), ""
    if S.ndim == 2 and S.size and np.isfinite(S).all():
        _, sv, vt = np.linalg.svd(S, full_matrices=False)
        cond = float(sv[0] / sv[-1]) if sv[-1] > 0 else float("inf")
        v = vt[0] / vt[0][np.argmax(np.abs(vt[0]))]   # the largest exponent is +1
        combo = " * ".join(f"{p}^{c:.2f}" for p, c in zip(free, v) if abs(c) > 5e-3)
        if S.shape[1] > S.shape[0]:
            why.append(f"{S.shape[0]} target(s) for {S.shape[1]} free parameters")
        elif cond > cond_max:
            why.append(f"condition number of the log-sensitivities {cond:.3g} > {cond_max:g}")
    if not bool(res.identifiable) and not why:
        why.append("mvtk.updating found a null direction")
    if at_bound:
        why.append(f"{', '.join(at_bound)} ended on a bound")
    return {"identifiable_study": not why, "log_condition_number": cond,
            "not_identifiable_why": "; ".join(why), "identifiable_combination": combo}


def _normal_mode_shapes(study: Study, targets: list, attached: list, modal_result):
    """Keep only the identified shapes that are normal modes (MPC and MPD in tolerance).

    A shape with a modal phase collinearity below ``checks.mpc_min`` or a mean phase
    deviation above ``checks.mpd_max_deg`` (a complex shape: leakage, a close mode,
    noise) is not a reliable basis for a MAC pairing; its target is paired by frequency
    instead. Returns the targets, the attached test modes and one note per shape dropped.
    """
    import dataclasses

    if not modal_result:
        return targets, attached, []
    tol = study.config["checks"]
    tab = modal_result.get("table") or {}
    q = {int(m): (float(c), float(d)) for m, c, d in
         zip(tab.get("mode", []), tab.get("mpc", []), tab.get("mpd", []))}
    out, att, notes = [], [], []
    for t, k in zip(targets, attached):
        if k is not None and k in q:
            mpc, mpd = q[k]
            if not (mpc >= tol["mpc_min"] and mpd <= tol["mpd_max_deg"]):
                notes.append(f"target {t.label or t.fn_hz}: the shape of test mode {k} "
                             f"({t.fn_hz:.4g} Hz) is not a normal mode (MPC {mpc:.3f} < "
                             f"{tol['mpc_min']:g} or MPD {mpd:.1f} > {tol['mpd_max_deg']:g} "
                             "deg): paired by frequency instead of MAC")
                t, k = dataclasses.replace(t, shape=None), None
        out.append(t)
        att.append(k)
    return out, att, notes


def updating(study: Study, modal_arrays=None, modal_result=None):
    """Sensitivity-based update of the configured parameters to the target frequencies.

    Reads ``[updating]`` through :func:`mvtk.study._updating.updating_inputs`:
    ``targets_hz`` (labels f1, f2, ...) or ``targets`` tables, ``parameters`` (a field
    absent from the structure is created with ``initial``) and the solver settings
    (``max_iter``, ``n_modes``, ``regularization``, ``mac_weight``, ``frequency_std``,
    ``model_form_std``, ``builder``). With a ``[modal]`` test (``modal_arrays``, the
    identified shapes) and ``modal.pair_updating``, each target carries the identified
    shape nearest in frequency, so the FE modes are paired by MAC; with its mode table
    (``modal_result``) each target carries the identified ``fn_std_hz`` as its
    standard deviation, and the update weights the targets by ``1 / sigma^2`` with the
    model-form term ``model_form_std`` (:func:`mvtk.updating.update`).
    """
    from ..updating import update
    from ._updating import updating_inputs

    cfg = study.section("updating")
    inp = updating_inputs(study, modal_arrays, modal_result)
    params, targets, kwargs = inp["parameters"], inp["targets"], inp["kwargs"]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        res = update(inp["description"], params, targets, **kwargs)
    table = res.residual_table()
    result = {
        "success": bool(res.success), "message": str(res.message),
        "affine": bool(kwargs.get("affine", False)),
        "affine_check_rel": res.meta.get("affine_check_rel"),
        "parameters": [p.path for p in params],
        "initial_values": res.initial_values, "values": res.values, "std": res.std,
        "covariance": np.asarray(res.covariance, dtype=float).tolist(),
        "covariance_scaling": res.meta.get("covariance_scaling"),
        "at_bound": res.at_bound,
        "targets_hz": [float(t.fn_hz) for t in targets],
        "target_test_modes": inp["attached"],
        "target_std_source": inp["std_source"],
        "identification_std_hz": table["id_std_hz"].to_numpy(dtype=float),
        "target_std_hz": table["std_hz"].to_numpy(dtype=float),
        "model_form_std": res.meta.get("model_form_std"),
        "residual_hz": table["residual_hz"].to_numpy(dtype=float),
        "noise_limit_hz": table["noise_limit_hz"].to_numpy(dtype=float),
        "limit_hz": table["limit_hz"].to_numpy(dtype=float),
        "residual_verdict": list(res.verdicts),
        "variance_factor": res.meta.get("variance_factor"),
        "pairing": list(res.pairing_method),
        "mac": [float(v) for v in np.asarray(res.mac, dtype=float)],
        "fn_hz_initial": res.fn_hz_initial, "fn_hz": res.fn_hz,
        "modes": res.modes, "model_fn_hz": res.model_fn_hz,
        "model_kinds": list(res.model_kinds),
        "identifiable": bool(res.identifiable), "condition_number": res.condition_number,
        "nominal_pairing": inp["pairing_table"],
        "shapes_not_used": inp["shapes_not_used"],
        **identifiability(res, [p.path for p in params], float(cfg["identifiability_cond_max"])),
        "n_evaluations": res.n_evaluations,
        "description": res.description,
        "warnings": _warning_messages(caught),
        "summary": res.to_dict(),
    }
    return result, None


# ------------------------------------------------------------------------ uncertainty
def _first_order_cov(description: dict, scatter: dict, n_modes: int):
    """Log-sensitivities d ln f / d ln p and the first-order CoV of each frequency.

    For independent inputs with coefficients of variation ``c_i``, to first order
    ``CoV(f_j) = sqrt(sum_i (S_ij c_i)^2)`` with ``S_ij = d ln f_j / d ln p_i``. ``S`` is
    the analytic eigenvalue sensitivity ``p_i phi_j'(dK/dp_i - omega_j^2 dM/dp_i)
    phi_j / (2 omega_j^2)`` (:func:`mvtk.updating.eigen_sensitivity`: one eigen solve
    of the nominal model and central differences of the assembled matrices), so a
    mode cannot swap order between two perturbed solves, and no perturbed model is
    solved. The matrix step is 1 % of each input: the difference of two assembled
    matrices loses about ``eps / step`` of their largest (membrane) entries, which the
    ill-conditioned bending energy amplifies (a 1e-4 step put 2.6e-6 on the exact
    1/2 of a plate's E), while the truncation error of a central difference of a
    cubic (plate bending in the thickness) is only ``step^2 / 3`` (3e-5).
    """
    from ..fe import build_model
    from ..updating import eigen_sensitivity

    sens = eigen_sensitivity(description, list(scatter), builder=build_model,
                             n_modes=n_modes, rel_step=0.01).normalised.T  # (n_params, n_modes)
    c = np.array([float(v) for v in scatter.values()])
    return sens, np.sqrt(((sens * c[:, None]) ** 2).sum(axis=0))


def _path_counts(samples) -> dict:
    """Number of samples per solution path (``reduced``, ``reduced+correction``, ``full``)."""
    if "path" not in samples:
        return {"full": int(samples.sizes.get("sample", 0))}
    paths, counts = np.unique(np.asarray(samples["path"].values, dtype=str),
                              return_counts=True)
    return {str(p) or "failed": int(c) for p, c in zip(paths, counts)}


def _max_bound(samples) -> float | None:
    """Largest relative frequency error bound of the reduced-path samples (None: none)."""
    if "error_bound" not in samples:
        return None
    b = np.asarray(samples["error_bound"].values, dtype=float)
    b = b[np.isfinite(b)]
    return float(b.max()) if b.size else None


def uncertainty(study: Study, description: dict):
    """Monte-Carlo propagation of the ``[uncertainty]`` input scatter to eigenfrequencies.

    Runs :func:`mvtk.scale.monte_carlo` in process (no dask needed) on ``description``
    (the updated structure when updating ran); each input is drawn with its value in
    ``description`` as the mean and ``scatter[path] * |mean|`` as the standard deviation.
    Also gives the first-order (linearised) CoV of each frequency for comparison.
    """
    import xarray as xr

    from ..fe import get_by_path
    from ..scale import monte_carlo

    cfg = study.section("uncertainty")
    scatter = {str(k): float(v) for k, v in cfg["scatter"].items()}
    n = int(cfg.get("n_samples", 40))
    seed = int(cfg.get("seed", 0))
    n_modes = int(cfg.get("n_modes", 4))
    kind = str(cfg.get("distribution", "normal"))
    nominal = {}
    for path in scatter:
        try:
            nominal[path] = float(get_by_path(description, path))
        except ConfigError as err:
            raise ConfigError(f"uncertainty.scatter.{path!r}: {err}") from None
        except (TypeError, ValueError):
            raise ConfigError(f"uncertainty.scatter.{path!r}: the structure value at this "
                              "path is not a number") from None
    dists = {p: (kind, (nominal[p], rel * abs(nominal[p]))) for p, rel in scatter.items()}
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        mc = monte_carlo(description, dists, n, np.random.default_rng(seed), n_modes=n_modes,
                         on_error="nan")
    sens, cov_fo = _first_order_cov(description, scatter, n_modes)
    stats = mc.to_dataframe()
    stats["cov_first_order"] = cov_fo
    # the linearised model on the SAME samples: ln f - ln f0 = sum_i S_ij ln(p_i / p0_i);
    # free of the sampling error, so it isolates the nonlinearity of f(p)
    values = np.column_stack([mc.samples[p].values for p in scatter])
    ok = np.isfinite(mc.fn_hz).all(axis=1) & (values > 0).all(axis=1)
    logs = np.log(values[ok] / np.array([nominal[p] for p in scatter]))
    stats["cov_first_order_same_samples"] = (np.std(logs @ sens, axis=0, ddof=1)
                                             if ok.sum() > 1 else np.nan)
    result = {
        "n_samples": n, "seed": seed, "distribution": kind, "n_modes": n_modes,
        "parameters": [{"path": p, "mean": nominal[p], "rel_std": scatter[p],
                        "std": scatter[p] * abs(nominal[p]),
                        **{f"dlnf{j + 1}/dlnp": float(sens[i, j]) for j in range(n_modes)}}
                       for i, p in enumerate(scatter)],
        "statistics": stats.to_dict(orient="records"),
        "n_failed": int(mc.samples.attrs.get("n_failed", 0)),
        "scheduler": str(mc.samples.attrs.get("scheduler", "")),
        # how each sample was solved: Rayleigh-Ritz on a reduced basis (with its error
        # bound) or a full eigen solve (mvtk.scale.parameter_study, method="auto")
        "method": str(mc.samples.attrs.get("method", "exact")),
        "reduced_note": str(mc.samples.attrs.get("reduced_note", "")),
        "paths": _path_counts(mc.samples),
        "max_error_bound": _max_bound(mc.samples),
        "warnings": _warning_messages(caught),
    }
    ds = xr.Dataset(
        {"fn_hz": (("sample", "mode"), mc.fn_hz, {"units": "Hz"}),
         "parameter_value": (("sample", "parameter"), values)},
        coords={"sample": np.arange(n), "mode": np.arange(1, n_modes + 1),
                "parameter": list(scatter)},
    )
    return result, ds


# -------------------------------------------------------------------------- reduction
def _plies(desc: dict, layers: list, where: str) -> list:
    """Ply objects of a layer list of a structure description (isotropic / piezo only)."""
    from ..fe import IsotropicMaterial, PiezoMaterial, Ply

    out = []
    for layer in layers:
        name = layer["material"]
        m = desc["materials"][name]
        args = (name, float(m["E"]), float(m["nu"]), float(m["rho"]))
        mat = PiezoMaterial(*args, float(m["d31"])) if "d31" in m else IsotropicMaterial(*args)
        out.append(Ply(mat, float(layer["thickness"]), float(layer.get("angle", 0.0))))
    if not out:
        raise ConfigError(f"{where}: no layers")
    return out


def _patch_stack(desc: dict, patch_name: str | None):
    """(patch table, plies bottom to top, index of the piezo ply) of a structure's patch."""
    from ..fe import PiezoMaterial

    patches = desc.get("patches", [])
    if patch_name is None:
        if len(patches) != 1:
            raise ConfigError(f"control.patch: the structure has {len(patches)} patches; "
                              "name the actuator patch")
        patch = patches[0]
    else:
        found = [pt for pt in patches if pt.get("name") == patch_name]
        if not found:
            raise ConfigError(f"control.patch: no patch {patch_name!r} in the structure; "
                              f"expected one of {[pt.get('name') for pt in patches]}")
        patch = found[0]
    layers = (_plies(desc, desc["structure"]["layers"], "structure.layers")
              + _plies(desc, patch["layers"], f"patch {patch.get('name')!r}"))
    idx = [i for i, ply in enumerate(layers) if isinstance(ply.material, PiezoMaterial)]
    if len(idx) != 1:
        raise ConfigError(f"patch {patch.get('name')!r}: expected one piezo layer (with d31) "
                          f"in the stack, found {len(idx)}")
    return patch, layers, idx[0]


def patch_actuator(desc: dict, patch_name: str | None = None) -> dict:
    """Moment per volt of a structure's piezo patch (paper eqs. 3-7).

    The stack is the base laminate plus the patch layers, bottom to top; the driven layer
    is the patch layer of a piezo material (with ``d31``).

    Parameters
    ----------
    desc : dict
        Structure description (:func:`mvtk.fe.load_structure`).
    patch_name : str, optional
        Patch name; default the only patch of the structure.

    Returns
    -------
    dict
        ``name``, ``width_m`` (patch width b), ``moment_per_volt_per_m`` (N m/(V m)),
        ``moment_per_volt`` (N m/V, times b), ``paper_eq7_moment_per_volt`` (the paper's
        printed closed form for a beam/adhesive/piezo stack, N m/V, when the stack has
        exactly those three layers), ``piezo_thickness_m``.

    Raises
    ------
    ConfigError
        No such patch, several patches without a name, or no piezo layer.
    """
    from ..fe import paper_eq7_moment_per_volt, piezo_moment_per_volt

    patch, layers, idx = _patch_stack(desc, patch_name)
    width = float(patch["y1"]) - float(patch["y0"])
    per_m = piezo_moment_per_volt(layers, idx)
    out = {"name": str(patch.get("name")), "width_m": width,
           "moment_per_volt_per_m": per_m, "moment_per_volt": per_m * width,
           "piezo_thickness_m": layers[idx].thickness,
           "paper_eq7_moment_per_volt": float("nan")}
    if len(layers) == 3 and idx == 2:
        b_, a_, p_ = layers
        out["paper_eq7_moment_per_volt"] = paper_eq7_moment_per_volt(
            E_p=p_.material.E, E_a=a_.material.E, E_b=b_.material.E, t_p=p_.thickness,
            t_a=a_.thickness, t_b=b_.thickness, d31=p_.material.d31, width=width)
    return out


def reduction(study: Study, description: dict, model_damping: dict | None):
    """Craig-Bampton SE of the (updated) model, FE-vs-SE checks, and the SE plant.

    The plant input is the patch voltage (V): the pin-force moment pair of the patch
    (``moment_per_volt`` of :func:`patch_actuator`, i.e. the moment per volt per metre
    times the patch width) acting on ``ry`` of the two retained actuator-edge nodes, as
    in the paper (moments at its nodes 2 and 3). A load on retained nodes is carried
    exactly by the SE's constraint modes; the patch's edge-line load (the same moments
    spread over the edge nodes) is compared with it on the full FE model (static tip
    deflection per volt, ``actuator["tip_per_volt_*"]``).
    """

    from ..control._plant import dof_load, structural_plant
    from ..fe import PiezoPatch, build_model, edge_moment_load, modal_analysis, static_solve
    from ..reduction import verify
    from ..reduction._config import super_element_from_config

    cfg = study.section("reduction")
    ctl = study.section("control") or {}
    model = build_model(description)
    se, points = super_element_from_config(model, cfg)
    named = {p.name: p.nodes[0] for p in points}
    n_cmp = min(int(cfg.get("n_compare", 4)), se.n_dof)
    ver = verify(model, se, n=n_cmp)
    result = {
        "retained_nodes": named,
        "retained_xyz": {k: model.nodes[v].tolist() for k, v in named.items()},
        "retained": [{"name": p.name, "nodes": list(p.nodes), "free_dofs": p.n_free_dofs,
                      "snap_distance_m": p.snap_distance_m} for p in points],
        "model": model.name, "n_boundary": int(se.n_boundary), "n_modes": int(se.n_modes),
        "verify": ver.to_dict(),
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
    if ctl and ctl.get("actuators"):
        result["actuator"], ds = _piezo_plant(model, se, named, cfg, ctl, model_damping)
        fe_hz = np.asarray(ver.modes.fe_hz, dtype=float)
        result["fe_fn_hz_updated"] = (fe_hz if fe_hz.min() > 1e-3 * fe_hz.max()
                                      else modal_analysis(model, n_cmp).fn_hz)
    elif ctl and model_damping is not None:
        act = patch_actuator(description, ctl.get("patch"))
        single = {p.name: p for p in points}
        for key in ("actuator_nodes", "sensor_node"):
            for n in (ctl[key] if key == "actuator_nodes" else [ctl[key]]):
                if len(single[n].nodes) != 1:
                    raise ConfigError(f"control.{key}: retained item {n!r} has "
                                      f"{len(single[n].nodes)} nodes; expected one node")
        x0, x1 = (named[n] for n in ctl["actuator_nodes"])
        tip = named[ctl["sensor_node"]]
        # pin-force moment pair per volt on ry of the two retained edge nodes (single-node
        # edges: moment_per_length x width); positive voltage bends the tip towards +z
        load = edge_moment_load(model, [x0], [x1], act["moment_per_volt_per_m"], "ry",
                                width=act["width_m"])
        _, layers, idx = _patch_stack(description, act["name"])
        line = PiezoPatch(act["name"], tuple(layers), idx,
                          edges=(f"patch:{act['name']}:x0", f"patch:{act['name']}:x1"),
                          width=act["width_m"])
        tip_row = dof_load(model, tip, "uz", 1.0)
        u = static_solve(model, np.column_stack([load, line.load_vector(model)]))
        act["tip_per_volt_nodes_m"] = float(tip_row @ u[:, 0])
        act["tip_per_volt_edge_lines_m"] = float(tip_row @ u[:, 1])
        if model.meta.get("piezo_patches"):
            # the same patch coupled in the shells (biaxial induced strain), a printed
            # cross-check of the pin-force idealisation the plant keeps
            from ..fe import piezo_coupling

            cpl = piezo_coupling(model)
            if act["name"] in cpl.names:
                b = cpl.B[:, cpl.names.index(act["name"])]
                act["tip_per_volt_shell_coupled_m"] = float(tip_row @ static_solve(model, b))
        n_plant = min(int(cfg.get("plant_modes", 12)), se.n_dof)
        # modal form: shell drilling rotations of the boundary have no inertia (singular
        # physical M); n_plant modes + the static residual of the others (exact DC gain)
        plant = structural_plant(se, inputs={"voltage": load},
                                 outputs={"tip": (tip, "uz")},
                                 alpha=float(model_damping["alpha"]),
                                 beta=float(model_damping["beta"]), form="modal",
                                 n_modes=n_plant, static_correction=True,
                                 input_units=["V"], output_units=["m"])
        act["tip_per_volt_plant_m"] = float(plant.to_state_space().dc_gain()[0, 0])
        act["plant_modes"] = n_plant
        act["plant_fn_max_hz"] = float(np.max(plant.meta["fn_hz"]))
        result["actuator"] = act
        ds = _plant_dataset(plant, {"moment_per_volt": act["moment_per_volt"]})
        # the FE frequencies verify() compared (the same eigen solve as modal_analysis);
        # modal_analysis only where it would classify near-zero modes as rigid
        fe_hz = np.asarray(ver.modes.fe_hz, dtype=float)
        result["fe_fn_hz_updated"] = (fe_hz if fe_hz.min() > 1e-3 * fe_hz.max()
                                      else modal_analysis(model, n_cmp).fn_hz)
    return result, ds


def _piezo_plant(model, se, named: dict, cfg: dict, ctl: dict, model_damping):
    """Plant of piezo electrodes on any shell structure: every actuator's voltage in
    (``control.actuators``, in order), the sensors' charge or voltage and the sensor
    node's displacement (``"tip"``) out, on the super element with the electrodes'
    static shapes and residual inertia vectors (:func:`mvtk.reduction.with_electrodes`).
    The DC gains reported are those of the first actuator."""
    import dataclasses

    from ..control import piezo_plant
    from ..errors import MvtkError
    from ..fe import modal_emcc, piezo_coupling, static_solve
    from ..reduction import with_electrodes

    try:
        cp = piezo_coupling(model)
        acts = [cp.names[i] for i in cp.index(ctl["actuators"])]
        sens = [cp.names[i] for i in cp.index(ctl["sensors"])]
    except MvtkError as err:
        raise ConfigError(f"control.actuators/sensors: {err}") from err
    if model_damping is not None:
        damp = {"alpha": float(model_damping["alpha"]), "beta": float(model_damping["beta"])}
        damp_text = "Rayleigh pair of [damping]"
    elif ctl.get("zeta") is not None:
        damp = {"modal_damping": float(ctl["zeta"])}
        damp_text = f"modal damping ratio {float(ctl['zeta']):g} (control.zeta)"
    else:
        raise ConfigError("control.zeta: the piezo plant needs a damping: give [damping] "
                          "or control.zeta (modal damping ratio)")
    se_e, _ = with_electrodes(se, cp)
    tip = named[ctl["sensor_node"]]
    n_plant = min(int(cfg.get("plant_modes", 12)), se_e.n_dof)
    plant = piezo_plant(se_e, cp, acts, sens, sensing=ctl.get("sensing", "charge"),
                        points=[(tip, "uz")], form="modal", n_modes=n_plant,
                        static_correction=True, **damp)
    plant = dataclasses.replace(plant, outputs=plant.outputs[:-1] + ("tip",))
    i_a = cp.names.index(acts[0])
    w_full = float(model.expand(static_solve(model, cp.B[:, i_a]))[tip, 2])
    emcc = [r for r in modal_emcc(model, cp, n_modes=min(6, model.n_dof - 1),
                                  electrodes=acts + [n for n in sens if n not in acts])]
    act = {"piezo": True, "name": acts[0], "actuators": acts, "sensors": sens,
           "sensing": ctl.get("sensing", "charge"), "damping": damp_text,
           "capacitance_F": {n: float(cp.C[cp.names.index(n)]) for n in acts + sens},
           "tip_per_volt_full_m": w_full,
           "tip_per_volt_plant_m": float(plant.to_state_space().dc_gain()[-1, 0]),
           "sensor_per_volt_plant": float(plant.to_state_space().dc_gain()[0, 0]),
           "sensor_unit": plant.output_units[0],
           "plant_modes": n_plant, "plant_fn_max_hz": float(np.max(plant.meta["fn_hz"])),
           "emcc": emcc, "moment_per_volt": float("nan")}
    ds = _plant_dataset(plant, {"moment_per_volt": float("nan"),
                                "output_units": "|".join(plant.output_units)})
    return act, ds


def _plant_dataset(plant, attrs: dict):
    """The second-order plant's matrices as the cached Dataset of the reduction stage."""
    import xarray as xr

    coords = list(plant.coords)
    return xr.Dataset({
        k: (("coord", "coord2"), getattr(plant, k)) for k in ("M", "C", "K")
    } | {
        "B": (("coord", "input"), plant.B),
        "Cq": (("output", "coord"), plant.Cq),
        "Cv": (("output", "coord"), plant.Cv),
        "D": (("output", "input"), plant.D),
    }, coords={"coord": coords, "coord2": coords, "input": list(plant.inputs),
               "output": list(plant.outputs)}, attrs=attrs)


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
        coords=[str(v) for v in pa["coord"].values], input_units=["V"] * pa.sizes["input"],
        output_units=str(pa.attrs.get("output_units", "m")).split("|"),
        D=pa["D"].values,
    )
    mode = int(cfg.get("release_mode", 1))
    if mode != 1:
        # the released mode's frequency, from the plant (the first mode's is given)
        om = closed_loop_modes(plant)
        fosc = np.sort(om.fn_hz[om.eigenvalues.imag > 0])
        if mode > fosc.size:
            raise ConfigError(f"control.release_mode: {mode} exceeds the plant's "
                              f"{fosc.size} modes")
        fn1_hz = float(fosc[mode - 1])
    x0 = release_state(plant, mode, "tip", float(cfg["initial_tip_displacement_m"]))
    t_end, fs = float(cfg["t_end_s"]), float(cfg["fs_out"])
    if fs <= 2.4 * fn1_hz:
        raise ConfigError(f"control.fs_out = {fs:g} Hz cannot resolve the first mode "
                          f"({fn1_hz:.4g} Hz) in the spectra: expected fs_out > 2.4 x "
                          f"{fn1_hz:.4g} = {2.4 * fn1_hz:.4g} Hz")
    band = float(cfg["settle_band"])
    limit_v = float(cfg.get("actuator_limit_v", 100.0))
    m_per_v = abs(float(pa.attrs.get("moment_per_volt", float("nan"))))
    runs = {"open loop": None}
    methods = {"open loop": "auto"}
    rates: dict[str, float | None] = {"open loop": None}
    open_sim = simulate(plant, None, t_end=t_end, fs_out=fs, initial=x0)
    n = plant.n_coords
    # generalised actuator force times velocity, B' q', of the open loop (for a boundary
    # layer given relative to its initial amplitude)
    switching = {a: plant.B[:, i] @ open_sim["states"].values[n:, :]
                 for i, a in enumerate(plant.inputs)}
    switching_peaks = {a: float(np.max(np.abs(v))) for a, v in switching.items()}
    switching_peak = switching_peaks[plant.inputs[0]]
    for c in cfg.get("controllers", []):
        kind = c["type"]
        where = f"control.controllers[{c['name']!r}]"
        for key, names in (("actuator", plant.inputs), ("sensor", plant.outputs)):
            if c.get(key) is not None and c[key] not in names:
                raise ConfigError(f"{where}.{key}: {c[key]!r} is not a plant "
                                  f"{'input' if key == 'actuator' else 'output'}; "
                                  f"expected one of {list(names)}")
        if kind in ("PPF", "SRF"):
            ctrl = getattr(mc, kind)(targets=[(float(c["f_hz"]), float(c["zeta_f"]),
                                               float(c["gain"]))],
                                     sensor=c.get("sensor"), actuator=c.get("actuator"),
                                     u_max=c.get("u_max"))
        elif kind == "VelocityFeedback":
            ctrl = VelocityFeedback(float(c["gain"]), sensor=c.get("sensor"),
                                    actuator=c.get("actuator"), u_max=c.get("u_max"))
        elif kind == "LQR":
            acts = c.get("actuators") or [plant.inputs[0]]
            bad = [a for a in acts if a not in plant.inputs]
            if bad:
                raise ConfigError(f"{where}.actuators: {bad} are not plant inputs; "
                                  f"expected names from {list(plant.inputs)}")
            ctrl = mc.LQR(R=float(c["R"]), q_scale=float(c.get("q_scale", 1.0)),
                          actuator=list(acts), u_max=c.get("u_max"))
        else:
            eps = (float(c["boundary_layer"]) if "boundary_layer" in c
                   else float(c["boundary_layer_rel"])
                   * switching_peaks[c.get("actuator") or plant.inputs[0]])
            ctrl = LyapunovBangBang(u_max=float(c["u_max"]), boundary_layer=eps,
                                    actuator=c.get("actuator"))
        runs[str(c["name"])] = ctrl
        methods[str(c["name"])] = str(c.get("method", "auto"))
        rates[str(c["name"])] = (float(c["control_rate_hz"]) if "control_rate_hz" in c
                                 else None)
    rows, series, inputs = [], {}, {}
    amp0 = float(cfg["initial_tip_displacement_m"])
    t = None
    for name, ctrl in runs.items():
        sim = open_sim if ctrl is None else simulate(plant, ctrl, t_end=t_end, fs_out=fs,
                                                     initial=x0, method=methods[name],
                                                     control_rate_hz=rates[name])
        y = sim["outputs"].sel(output="tip").values
        if "inputs" in sim:  # the command of the actuator with the largest peak
            us = sim["inputs"].values
            u = us[int(np.argmax(np.max(np.abs(us), axis=1)))]
        else:
            u = np.zeros_like(y)
        t = sim["time"].values
        series[name], inputs[name] = y, u
        zeta_cl = fn_cl = float("nan")
        stab = _stability(plant, ctrl, y, amp0)
        if ctrl is None:
            om = closed_loop_modes(plant)
            osc = om.eigenvalues.imag > 0
            order = np.argsort(om.fn_hz[osc])
            zeta_cl = float(om.zeta[osc][order][mode - 1])
            fn_cl = float(om.fn_hz[osc][order][mode - 1])
        elif kind_linear(ctrl):
            # small-signal closed-loop mode 1 (the actuator limit is not active in it)
            ad = added_damping(plant, dataclasses.replace(ctrl, u_max=None), mode)
            zeta_cl, fn_cl = ad["zeta_closed"], ad["fn_hz_closed"]
        f, a = _amplitude_spectrum(y, fs)
        rows.append({"controller": name,
                     "settling_time_s": settling_time(y, t, band=band, reference=amp0),
                     "zeta_mode1": zeta_cl, "fn_mode1_hz": fn_cl, **stab,
                     "peak_tip_m_after_1s": float(np.max(np.abs(y[t >= 1.0]))),
                     "peak_voltage_V": float(np.max(np.abs(u))),
                     "peak_moment_Nm": float(np.max(np.abs(u))) * m_per_v,
                     "voltage_within_limit": bool(np.max(np.abs(u)) <= limit_v * (1 + 1e-9)),
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
            "fn1_hz": float(fn1_hz),
            "actuator_limit_v": limit_v, "moment_per_volt": m_per_v,
            "methods": methods, "control_rate_hz": rates,
            "switching_peak": switching_peak,
            "controllers": {k: repr(v) for k, v in runs.items()}}, ds


def _stability(plant, ctrl, y: np.ndarray, amp0: float) -> dict:
    """Stability verdict and margins of one loop.

    Linear laws (also the small-signal loop of a saturated linear law): the eigenvalues
    of the closed-loop state matrix (:func:`mvtk.control.closed_loop`); the loop is
    stable when every pole has a real part below ``-1e-9 max|p|`` (a pole on the
    imaginary axis is marginal, i.e. not stable). Nonlinear laws: along the simulated
    trajectory, finite and with the peak of the last fifth of the record below the
    release amplitude. Margins (:func:`mvtk.control.loop_margins`, the loop broken at
    the actuator input): gain margin (dB), phase margin (deg) and the factor on the loop
    gain at the edge of stability, for a linear law with one actuator; NaN otherwise
    (no crossover: NaN too, the critical factor then says whether any gain
    destabilises the loop).
    """
    from ..control import closed_loop, closed_loop_modes, loop_margins

    nan = float("nan")
    margins = {"gain_margin_db": nan, "phase_margin_deg": nan, "critical_gain_factor": nan}
    if ctrl is None or kind_linear(ctrl):
        if ctrl is None:
            poles = closed_loop_modes(plant).eigenvalues
        else:
            lin = dataclasses.replace(ctrl, u_max=None)
            poles = closed_loop(plant, lin).poles()
            if not isinstance(getattr(lin, "actuator", None), list | tuple) or len(
                    lin.actuator) == 1:
                lm = loop_margins(plant, lin)
                margins = {"gain_margin_db": float(lm.gain_margin_db),
                           "phase_margin_deg": float(lm.phase_margin_deg),
                           "critical_gain_factor": float(lm.critical_gain_factor)}
                margins = {k: (v if np.isfinite(v) else nan) for k, v in margins.items()}
        poles = np.asarray(poles, dtype=complex)
        k = int(np.argmax(poles.real))
        p = poles[k]
        margin = 1e-9 * float(np.max(np.abs(poles)))
        zeta_min = float(-p.real / abs(p)) if abs(p) > 0 else 0.0
        return {"stable": bool(p.real < -margin), "max_real_pole_1_per_s": float(p.real),
                "critical_pole_imag_rad_s": float(abs(p.imag)), "zeta_min": zeta_min,
                **margins, "stability_basis": "closed-loop eigenvalues"}
    tail = y[int(0.8 * len(y)):]
    ok = bool(np.all(np.isfinite(y)) and tail.size and np.max(np.abs(tail)) < abs(amp0))
    return {"stable": ok, "max_real_pole_1_per_s": nan,
            "critical_pole_imag_rad_s": nan, "zeta_min": nan, **margins,
            "stability_basis": "simulated trajectory (decays below the release amplitude)"}


def kind_linear(ctrl) -> bool:
    """True for the linear controllers (closed-loop poles exist)."""
    return type(ctrl).__name__ in ("PPF", "SRF", "VelocityFeedback", "LQR")
