"""The study report: tables, figures, pass/fail checks and provenance of a study run.

Every sentence is built from the study's own content; published values appear only
where the study declares them in ``[references]``.
"""

from __future__ import annotations

import math
from functools import partial
from pathlib import Path
from types import SimpleNamespace
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from .._format import parameter_unit
from ..report import Report, collect_provenance, display_checks
from ..report._provenance import relative_path
from ..validation import Check, check_table, frequency_table

if TYPE_CHECKING:  # pragma: no cover
    from ._run import StudyResult

__all__ = ["build_report", "study_checks"]


def _ref(res: StudyResult, key: str, default=None):
    return (res.study.config.get("references") or {}).get(key, default)


def _has_refs(res: StudyResult, *keys: str) -> bool:
    """True when the study's ``[references]`` give every one of ``keys``."""
    refs = res.study.config.get("references") or {}
    return bool(keys) and all(refs.get(k) is not None for k in keys)


def _refs_name(res: StudyResult) -> str:
    """How the text names the study's references: their ``source``, else "the references"."""
    return str(_ref(res, "source") or "the references")


def _title(base: str, res: StudyResult, tables: str, *keys: str) -> str:
    """``base``, with `` (paper Tables ...)`` only when the study gives those references."""
    return f"{base} (reference {tables})" if _has_refs(res, *keys) else base


def _list_modes(modes: list[int]) -> str:
    """``[1, 2]`` -> "modes 1-2", ``[3]`` -> "mode 3", ``[1, 3, 4]`` -> "modes 1, 3, 4"."""
    if len(modes) == 1:
        return f"mode {modes[0]}"
    if modes == list(range(modes[0], modes[-1] + 1)):
        return f"modes {modes[0]}-{modes[-1]}"
    return "modes " + ", ".join(map(str, modes))


def _not_configured(res: StudyResult, stage: str) -> bool:
    """True when the study file does not ask for ``stage`` (its section is left out)."""
    return stage not in res.results and str(
        res.unavailable.get(stage, "")).startswith("not configured")


def _stage_missing(sec, res: StudyResult, stage: str) -> bool:
    """Mark the section unavailable when the stage did not complete; True if missing."""
    if stage in res.results:
        return False
    reason = res.failed.get(stage) or res.unavailable.get(stage) or "did not run"
    sec.unavailable(f"stage '{stage}': {reason}")
    return True


def study_checks(res: StudyResult) -> list[Check]:
    """The pass/fail checks of a study run against its ``[checks]`` tolerances."""
    tol = res.study.config["checks"]
    src = _ref(res, "source", "references")
    checks: list[Check] = []
    # the independent checks of each damping estimate (half-power row i, or
    # ("decay", name)): an estimate its estimator flagged is only accepted when one passes
    confirm: dict = {}
    targets = _target_frequencies(res)
    dmp = res.results.get("damping", {})
    hp = dmp.get("half_power")
    if hp and targets:
        # each identified mode is checked against the target of the same mode (paired by
        # frequency from the modes the damping stage was asked for), never by position
        groups = _rows_by_test(dmp, hp)
        zref = _ref(res, "zeta", [])
        ref_f = (_ref(res, "experiment_fn_hz", []) or [])[: len(zref)]
        to_target, to_zref = {}, {}
        for rows, guess in groups:   # one-to-one within each test
            to_target.update({rows[i]: j for i, j in _pair(guess, targets).items()})
            if zref:
                to_zref.update({rows[i]: j for i, j in _pair(guess, ref_f).items()})
        for i, (fn, z) in enumerate(zip(hp["fn_hz"], hp["zeta"])):
            if i in to_target:
                checks.append(Check(f"identified f{i + 1} (half-power peak)", fn,
                                    targets[to_target[i]], tol["identified_fn_rel"], "Hz",
                                    source="study targets"))
            j = to_zref.get(i, i if not _ref(res, "experiment_fn_hz") else None)
            if j is not None and j < len(zref):
                checks.append(Check(f"identified zeta{i + 1} (half-power)", z, zref[j],
                                    tol["identified_zeta_rel"], "", source=src))
                confirm.setdefault(i, []).append(checks[-1])
    truth_pair = _truth_rayleigh(res)
    if hp and truth_pair:
        for i, (fn, z) in enumerate(zip(hp["fn_hz"], hp["zeta"])):
            if i not in confirm and np.isfinite([fn, z]).all():
                w = 2 * np.pi * fn
                checks.append(Check(f"identified zeta{i + 1} at {fn:.1f} Hz vs SYNTHETIC truth",
                                    z, truth_pair[0] / (2 * w) + truth_pair[1] * w / 2,
                                    tol["identified_zeta_rel"], "",
                                    source="study [truth] (simulated specimen)"))
                confirm.setdefault(i, []).append(checks[-1])
    env = dmp.get("envelope")
    zref = _ref(res, "zeta", [])
    if env and zref:
        checks.append(Check("identified zeta1 (envelope fit of the free decay)",
                            env["zeta"][0], zref[0], tol["identified_zeta_rel"], "", source=src))
        confirm.setdefault(("decay", next(iter(dmp.get("decays") or {"decay": 0}))),
                           []).append(checks[-1])
    rh = dmp.get("rayleigh_half_power")
    if rh and _ref(res, "half_power_alpha") is not None:
        checks.append(Check("Rayleigh alpha (half-power)", rh["alpha"],
                            _ref(res, "half_power_alpha"), tol["rayleigh_rel"], "1/s",
                            source=src))
        checks.append(Check("Rayleigh beta (half-power)", rh["beta"],
                            _ref(res, "half_power_beta"), tol["rayleigh_rel"], "s", source=src))
    checks += _correlation_checks(res, tol)
    checks += _consistency_checks(res, tol, confirm)
    checks += _flagged_estimates(res, confirm)
    up = res.results.get("updating")
    if up and "identifiable_study" in up:
        checks.append(Check(
            "updated parameters identifiable from the targets"
            + (f" (not: {up['not_identifiable_why']}; the data determine "
               f"{up['identifiable_combination']})" if not up["identifiable_study"] else ""),
            1.0 if up["identifiable_study"] else 0.0, 1.0, 0.0, "", kind="lower",
            source="log-sensitivity condition number and bounds"))
    if up:
        for i, (f, ft) in enumerate(zip(up["fn_hz"], up["targets_hz"])):
            checks.append(Check(f"updated FE f{i + 1}", f, ft, tol["updated_fn_rel"], "Hz",
                                source="study targets"))
        truth = res.study.config.get("truth") or {}
        for path, value in zip(up["parameters"], up["values"]):
            if path in truth:
                checks.append(Check(f"updated {path} vs SYNTHETIC truth", value,
                                    float(truth[path]), tol["truth_param_rel"], "",
                                    source="study [truth] (simulated specimen)"))
    unc = res.results.get("uncertainty")
    if unc and unc["statistics"]:
        s1 = unc["statistics"][0]
        checks.append(Check("Monte-Carlo CoV(f1) vs first-order estimate", s1["cov"],
                            s1["cov_first_order"], tol["uncertainty_cov_rel"], "",
                            source="linearised propagation (central-difference sensitivities)"))
    red = res.results.get("reduction")
    if red:
        m = red["modes"]
        for i, (fe, se) in enumerate(zip(m["fe_hz"], m["se_hz"])):
            checks.append(Check(f"SE f{i + 1} vs FE", se, fe, tol["se_fn_rel"], "Hz",
                                source="updated FE model"))
            checks.append(Check(f"SE f{i + 1} >= FE f{i + 1} (Rayleigh-Ritz bound)", se, fe,
                                1e-9 * fe, "Hz", kind="lower", source="Craig & Bampton 1968"))
        err = (red.get("static") or {}).get("rel_error_boundary")
        if err:
            checks.append(Check("SE static boundary displacement vs FE (max relative error)",
                                float(np.max(np.abs(err))), 0.0, 1e-6, "", kind="absolute",
                                source="constraint modes are statically exact"))
    ctl = res.results.get("control")
    if ctl:
        for row in ctl["metrics"]:
            name = row["controller"]
            if name == "open loop":
                continue
            if name.upper().startswith("PPF"):
                checks.append(Check(f"{name} settling time", row["settling_time_s"],
                                    tol["ppf_settling_s"], 0.0, "s", kind="upper",
                                    source="study tolerance"))
            if "peak_voltage_V" in row:
                checks.append(Check(f"{name} peak voltage within the actuator limit",
                                    row["peak_voltage_V"], ctl["actuator_limit_v"], 0.0, "V",
                                    kind="upper", source="study control.actuator_limit_v"))
            stable = row.get("stable")
            if stable is not None:
                if row.get("stability_basis", "").startswith("closed-loop eigenvalues"):
                    checks.append(Check(
                        f"{name} closed loop stable (largest real part of the poles)",
                        row["max_real_pole_1_per_s"] if stable
                        else max(row["max_real_pole_1_per_s"], 1e-300),
                        0.0, 0.0, "1/s", kind="upper", source="closed-loop eigenvalues"))
                else:
                    checks.append(Check(f"{name} closed loop stable (trajectory decays)",
                                        1.0 if stable else 0.0, 1.0, 0.0, "", kind="lower",
                                        source="simulated trajectory"))
            z = row["zeta_mode1"]
            if z is not None and not (isinstance(z, float) and math.isnan(z)):
                if stable is False:
                    # an unstable loop adds no damping, whatever the mode-1 pole does
                    z = row.get("zeta_min", -1.0)
                    if z is None or (isinstance(z, float) and math.isnan(z)):
                        z = -1.0
                checks.append(Check(f"{name} closed-loop zeta of mode 1"
                                    + ("" if stable is not False
                                       else " (loop UNSTABLE: least-damped pole)"), z,
                                    tol["closed_loop_zeta_min"], 0.0, "", kind="lower",
                                    source="study tolerance"))
    return checks


def _target_frequencies(res: StudyResult) -> list[float]:
    """The updating targets (Hz) in either form, else the reference experiment."""
    up = res.study.config.get("updating") or {}
    if up.get("targets_hz"):
        return [float(f) for f in up["targets_hz"]]
    if up.get("targets"):
        return [float(t["fn_hz"]) for t in up["targets"]]
    return [float(f) for f in _ref(res, "experiment_fn_hz", []) or []]


def _pair(a_hz, b_hz, max_rel: float = 0.1) -> dict[int, int]:
    """One-to-one pairs ``i -> j`` of two frequency lists by frequency (within max_rel)."""
    from ..updating import pair_by_frequency

    if not len(a_hz) or not len(b_hz):
        return {}
    got = pair_by_frequency(a_hz, b_hz, max_rel=max_rel)
    return {i: int(j) for i, j in enumerate(got) if j >= 0}


def _rows_by_test(dmp: dict, hp: dict) -> list[tuple[list[int], list[float]]]:
    """(row indices, searched frequencies) of each impact test of the damping table."""
    tests = list(hp.get("test", ["impact"] * len(hp["fn_hz"])))
    by = dmp.get("fn_guess_by_test")
    if not by:
        by = {"impact": list(dmp.get("fn_guess_hz", [])),
              "broadband": list(dmp.get("broadband_fn_guess_hz", []))}
    out = []
    for name in dict.fromkeys(tests):
        rows = [i for i, t in enumerate(tests) if t == name]
        guess = list(by.get(name) or [])
        if len(guess) != len(rows):
            guess = [hp["fn_hz"][i] for i in rows]
        out.append((rows, guess))
    return out


def _flagged_estimates(res: StudyResult, confirm: dict) -> list[Check]:
    """A damping estimate its estimator did not mark reliable (too few lines, a close
    mode, noise, NaN: the warnings of the damping stage) counts in the verdict: it
    passes only when an independent value confirms it (a reference, the SYNTHETIC
    truth, another test or a decay of the same mode, within their tolerances)."""
    d = res.results.get("damping", {})
    hp = d.get("half_power") or {}
    out = []
    tests = list(hp.get("test", ["impact"] * len(hp.get("fn_hz", []))))
    items = [(i, f"damping of mode {i + 1} ({hp['fn_hz'][i]:.4g} Hz, test {tests[i]}, "
                 "half-power)", hp["zeta"][i], bool(hp.get("reliable", [True] * (i + 1))[i]),
              str((hp.get("reason") or [""] * (i + 1))[i] or hp.get("quality", [""])[i]))
             for i in range(len(hp.get("fn_hz", [])))]
    for name, dec in (d.get("decays") or {}).items():
        env = dec.get("envelope") or {}
        if env.get("zeta"):
            items.append((("decay", name), f"damping of the decay {name} (envelope fit)",
                          env["zeta"][0], bool((env.get("reliable") or [True])[0]),
                          str((env.get("reason") or [""])[0])))
    for key, label, z, reliable, why in items:
        finite = z is not None and np.isfinite(z)
        if reliable and finite:
            continue
        ok = finite and any(c.passed for c in confirm.get(key, []))
        why = why if finite else "no estimate (NaN)"
        out.append(Check(f"{label}: flagged by its estimator ({why})"
                         + ("; confirmed by an independent value" if ok
                            else "; no independent value confirms it"),
                         1.0 if ok else 0.0, 1.0, 0.0, "", kind="lower",
                         source="estimator verdict and the checks above"))
    up = res.results.get("updating")
    if up and "success" in up:
        out.append(Check("updating converged" + ("" if up["success"] else
                                                 f" (not: {up.get('message', '')})"),
                         1.0 if up["success"] else 0.0, 1.0, 0.0, "", kind="lower",
                         source="mvtk.updating.update"))
    return out


def _repeat_checks(res: StudyResult, tol: dict, confirm: dict) -> list[Check]:
    """The same mode measured twice: by two impact tests, or by a decay and a hammer
    test. Each later estimate is compared with the first (``zeta_consistency_rel``)."""
    d = res.results.get("damping", {})
    hp = d.get("half_power")
    out: list[Check] = []
    if not hp:
        return out
    f = np.asarray(hp["fn_hz"], dtype=float)
    tests = list(hp.get("test", ["impact"] * f.size))
    for i in range(f.size):
        if not np.isfinite(f[i]):
            continue
        prev = [j for j in range(i) if np.isfinite(f[j]) and abs(f[j] / f[i] - 1) <= 0.02]
        if prev and tests[prev[0]] != tests[i]:
            j = prev[0]
            out.append(Check(f"zeta at {f[i]:.1f} Hz: test {tests[i]} vs test {tests[j]} "
                             "(half-power)", hp["zeta"][i], hp["zeta"][j],
                             tol["zeta_consistency_rel"], "", source="same mode, two tests"))
            confirm.setdefault(i, []).append(out[-1])
            confirm.setdefault(j, []).append(out[-1])
    for name, dec in (d.get("decays") or {}).items():
        env = dec.get("envelope") or {}
        for fe, ze in zip(env.get("fn_hz", []), env.get("zeta", [])):
            if not np.isfinite(fe) or not f.size:
                continue
            j = int(np.nanargmin(np.abs(f / fe - 1)))
            if abs(f[j] / fe - 1) <= 0.02:
                out.append(Check(f"zeta at {fe:.1f} Hz: decay {name} (envelope fit) vs "
                                 f"test {tests[j]} (half-power)", ze, hp["zeta"][j],
                                 tol["zeta_consistency_rel"], "",
                                 source="same mode, two methods"))
                confirm.setdefault(j, []).append(out[-1])
                confirm.setdefault(("decay", name), []).append(out[-1])
    return out


def _consistency_checks(res: StudyResult, tol: dict, confirm: dict) -> list[Check]:
    """The same quantity from two sections: damping (half-power vs multi-point
    identification), and the quality (MPC, MPD) of the multi-point shapes the study uses.

    A multi-point damping ratio is compared only where the test's line spacing resolves
    it (at least 5 lines across its half-power band 2 zeta f, the half-power estimator's
    ``min_lines``); where it does not, the leakage of the short records can only widen
    the peak, so the check is that it is not *below* the half-power value (an upper bound
    of the damping), and its name says so. Impact FRFs are exempt from that bound: a hit
    record's DFT holds each mode exactly as a pole (:func:`mvtk.modal.identify` fits it
    on the record's own lines), so there is no leakage to widen it.
    """
    out: list[Check] = _repeat_checks(res, tol, confirm)
    mod = res.results.get("modal")
    hp = res.results.get("damping", {}).get("half_power")
    if mod and hp:
        t = mod["table"]
        lines = _modal_df_hz(res)
        pairs = _pair(hp["fn_hz"], t["fn_hz"], max_rel=0.02)
        for i, j in pairs.items():
            z_hp, z_m, f = hp["zeta"][i], t["zeta"][j], t["fn_hz"][j]
            n_lines = 2 * z_m * f / lines if lines else float("nan")
            label = (f"zeta of mode {i + 1} ({f:.1f} Hz): multi-point test vs half-power")
            if np.isfinite(n_lines) and n_lines < 5 and mod.get("excitation") != "impact":
                out.append(Check(label + f" (multi-point band {n_lines:.1f} lines of "
                                 f"{lines:g} Hz: leakage-limited, an upper bound)",
                                 z_m, z_hp, 0.0, "", kind="lower",
                                 source="consistency between sections"))
            else:
                out.append(Check(label, z_m, z_hp, tol["zeta_consistency_rel"], "",
                                 source="consistency between sections"))
    out += _multipoint_repeat_checks(res, tol)
    up = res.results.get("updating")
    if mod and up:
        used = {int(k) for k in up.get("target_test_modes") or [] if k is not None}
        t = mod["table"]
        for m, mpc, mpd in zip(t["mode"], t["mpc"], t["mpd"]):
            if int(m) in used:
                out.append(Check(f"MPC of test mode {int(m)} (shape used to pair a target)",
                                 float(mpc), float(tol["mpc_min"]), 0.0, "", kind="lower",
                                 source="normal-mode shape"))
                out.append(Check(f"MPD of test mode {int(m)} (shape used to pair a target)",
                                 float(mpd), float(tol["mpd_max_deg"]), 0.0, "deg",
                                 kind="upper", source="normal-mode shape"))
    return out


def _multipoint_repeat_checks(res: StudyResult, tol: dict) -> list[Check]:
    """Every reliable mode of a further multi-point test against the reliable [modal]
    mode it was paired with: frequency (``identified_fn_rel``), damping
    (``zeta_consistency_rel``) and MAC on the common DOFs (``mac_min``)."""
    mod = res.results.get("modal") or {}
    out: list[Check] = []
    ok_a = list(mod.get("table", {}).get("reliable", []))
    for name, t in (mod.get("tests") or {}).items():
        c, ok_b = t["comparison"], list(t["table"].get("reliable", []))
        src = f"same specimen, two multi-point tests ({t['file']})"
        for j, i in enumerate(c["paired_mode"]):
            if not i or not (j < len(ok_b) and ok_b[j]) or not (i - 1 < len(ok_a)
                                                                 and ok_a[i - 1]):
                continue
            what = f"mode {i} ({c['paired_fn_hz'][j]:.1f} Hz): multi-point test {name} vs [modal]"
            out.append(Check(f"f of {what}", c["fn_hz"][j], c["paired_fn_hz"][j],
                             tol["identified_fn_rel"], "Hz", source=src))
            out.append(Check(f"zeta of {what}", c["zeta"][j], c["paired_zeta"][j],
                             tol["zeta_consistency_rel"], "", source=src))
            if np.isfinite(c["mac"][j]):
                out.append(Check(f"MAC of {what}", c["mac"][j], float(tol["mac_min"]), 0.0,
                                 "", kind="lower", source=src))
    return out


def _modal_df_hz(res: StudyResult) -> float:
    """Line spacing (Hz) of the multi-point FRFs (0 when unknown)."""
    mod = res.results.get("modal") or {}
    if mod.get("df_hz"):
        return float(mod["df_hz"])
    arr = res.arrays.get("modal")
    if arr is not None and "frequency" in arr.coords and arr.sizes.get("frequency", 0) > 1:
        f = arr["frequency"].values
        return float(f[1] - f[0])
    return 0.0


def _correlation_checks(res: StudyResult, tol: dict) -> list[Check]:
    """MAC of every test-FE pair of a reliable test mode and the frequency of the
    non-target (predicted) modes."""
    cor = res.results.get("correlation")
    if not cor:
        return []
    pairs = pd.DataFrame(cor["pairs"])
    out = []
    src = f"multi-point test ({res.results['modal']['file']})"
    tab = res.results["modal"].get("table") or {}
    reliable = dict(zip(tab.get("mode", []), tab.get("reliable", [])))
    for _, r in pairs.iterrows():
        t = int(r["test_mode"])
        # a mode the identification marked not reliable (its row says why) is shown in
        # the pairing table but checks nothing: its shape may be two modes' mixture
        if not bool(r["paired"]) or not reliable.get(t, True):
            continue
        out.append(Check(f"MAC test mode {t} ({r['fn_test_hz']:.1f} Hz) / FE mode "
                         f"{int(r['fe_mode'])}", float(r["mac"]), float(tol["mac_min"]), 0.0,
                         "", kind="lower", source=src))
        if not bool(r.get("updating target", True)):
            out.append(Check(f"predicted f of test mode {t} (not an updating target)",
                             float(r["fn_fe_hz"]), float(r["fn_test_hz"]),
                             tol["prediction_fn_rel"], "Hz", source=src))
    return out


def _truth_rayleigh(res: StudyResult) -> tuple[float, float] | None:
    """(alpha, beta) of the SYNTHETIC truth (``[truth] rayleigh_alpha/beta``), if given."""
    truth = res.study.config.get("truth") or {}
    if "rayleigh_alpha" in truth and "rayleigh_beta" in truth:
        return float(truth["rayleigh_alpha"]), float(truth["rayleigh_beta"])
    return None


def _section_run(rep: Report, res: StudyResult) -> None:
    sec = rep.section("Study and run summary")
    if res.study.synthetic:
        parts = ["The measurement data of this study are SYNTHETIC (the study file says "
                 "so: [study] synthetic = true): simulated, not measured."]
        if res.study.config.get("truth"):
            parts.append("The simulated specimen's own values ([truth]) are shown next to "
                         "mvtk's numbers and checked.")
        if res.study.config.get("references"):
            parts.append(f"The values of {_refs_name(res)} are shown for comparison.")
        sec.note(" ".join(parts))
    sec.text(f"Study: {res.study.name} ({res.study.path.name}).")
    df = res.to_dataframe()
    df = df[df["stage"] != "report"]
    sec.table(df, "run_stages", "Stages (cached = loaded from the stage cache)",
              passed_column=None)


def _section_measurements(rep: Report, res: StudyResult) -> None:
    if _not_configured(res, "ingest"):
        return
    sec = rep.section("Measurements")
    if _stage_missing(sec, res, "ingest"):
        return
    sec.table(pd.DataFrame(res.results["ingest"]["channels"]), "measurement_channels",
              "Channels read with mvtk.io.read", passed_column=None)


def _section_damping(rep: Report, res: StudyResult) -> None:
    from ..plot import plot_decay, plot_frf

    if _not_configured(res, "damping"):
        return
    sec = rep.section(_title("Damping identification", res, "Table 3", "half_power_alpha"))
    if _stage_missing(sec, res, "damping"):
        return
    d = res.results["damping"]
    arr = res.arrays.get("damping")
    zref = _ref(res, "zeta", [])
    rows = []
    hp = d.get("half_power")
    n = len(hp["fn_hz"]) if hp else 1
    tests = hp.get("test", ["impact"] * n) if hp else []
    truth_pair = _truth_rayleigh(res)
    for i in range(n):
        row = {"mode": i + 1}
        if hp:
            row.update({"test": tests[i], "fn_hz (half-power)": hp["fn_hz"][i],
                        "zeta half-power": hp["zeta"][i],
                        "lines in band": hp["n_lines"][i], "quality": hp["quality"][i]})
        if i == 0 and d.get("envelope"):
            row["zeta envelope fit"] = d["envelope"]["zeta"][0]
            row["zeta log decrement"] = d["log_decrement"]["zeta"][0]
        for meth in ("half_power", "least_squares", "chowdhury"):
            r = d.get(f"rayleigh_{meth}", {})
            if "zeta_fit" in r and i < len(r["zeta_fit"]):
                row[f"zeta Rayleigh ({meth})"] = r["zeta_fit"][i]
        if i < len(zref):
            row["zeta paper"] = zref[i]
        if truth_pair and hp:
            w = 2 * np.pi * hp["fn_hz"][i]
            row["zeta SYNTHETIC truth"] = truth_pair[0] / (2 * w) + truth_pair[1] * w / 2
        rows.append(row)
    by_test: dict[str, list[int]] = {}
    for i, t in enumerate(tests):
        by_test.setdefault(str(t), []).append(i + 1)
    origin = "; ".join(f"{_list_modes(m)} from the {t} test" for t, m in by_test.items())
    sec.table(pd.DataFrame(rows), "damping_per_mode",
              "Identified damping per mode" + (f" ({origin})" if origin else ""),
              passed_column=None)
    rows = []
    ch = d.get("rayleigh_chowdhury", {})
    ls = d.get("rayleigh_least_squares", {})
    anchors = (f"anchors: modes {ch['anchors'][0] + 1} and {ch['anchors'][1] + 1}"
               if "anchors" in ch else "")
    for meth, label, used, note in (
            ("half_power", "half-power", "two-mode fit: modes 1 and 2", ""),
            ("least_squares", "least squares",
             f"all {ls.get('n_modes', '')} identified modes", ls.get("error", "")),
            ("chowdhury", "Chowdhury", anchors, ch.get("error", ch.get("note", "")))):
        r = d.get(f"rayleigh_{meth}", {})
        row = {"method": label, "modes used": used,
               "alpha [1/s]": r.get("alpha", float("nan")),
               "beta [s]": r.get("beta", float("nan"))}
        if _has_refs(res, "half_power_alpha"):
            row["alpha paper"] = _ref(res, f"{meth}_alpha", float("nan"))
            row["beta paper"] = _ref(res, f"{meth}_beta", float("nan"))
        row["note"] = note
        rows.append(row)
    sec.table(pd.DataFrame(rows), "table3_rayleigh",
              _title("Rayleigh alpha and beta", res, "Table 3", "half_power_alpha"),
              passed_column=None)
    if "error" in ch:
        sec.text("Chowdhury pair not computed: its anchor rule (mode 1 and the lowest mode at "
                 "which the cumulative effective mass reaches the target) needs more "
                 "identified modes than the tests provide. With two identified modes any "
                 "anchor choice is modes 1 and 2, i.e. the half-power pair.")
    if "anchors" in ch:
        pair = ch["pairing"]
        sec.text(f"Chowdhury pair: anchors at identified modes {ch['anchors'][0] + 1} and "
                 f"{ch['anchors'][1] + 1}; target cumulative effective mass "
                 f"{ch['target_mass']:g} (study), used {ch['target_used']:.3f}; the "
                 f"identified modes hold {ch['mass_reached']:.3f} of the effective mass (uz) "
                 "of the FE model used for the SE (updated when updating ran), each paired "
                 "with the FE mode nearest in frequency. "
                 + ("That is below the target (and below EN 1998's 0.90), so the "
                    "upper anchor is the mode at which the highest fraction reached is "
                    "attained. " if ch["note"] else "")
                 + (f"The Chowdhury pair of {_refs_name(res)} rests on damping ratios "
                    "that are not published with it, so it is not expected to be "
                    "reproduced." if _has_refs(res, "chowdhury_alpha") else ""))
        sec.table(pd.DataFrame({
            "identified mode": [a + 1 for a in range(len(pair["fe_mode"]))],
            "FE mode": pair["fe_mode"], "FE fn_hz": pair["fe_fn_hz"],
            "pairing error (rel)": pair["pair_error_rel"],
            "mass fraction uz": pair["mass_fraction"],
            "cumulative": np.cumsum(pair["mass_fraction"])}),
            "chowdhury_pairing", "Identified modes paired with FE modes (effective mass)",
            passed_column=None)
    sett = d.get("half_power_settings") or {}
    files = {k: p.name for k, p in res.study.measurement_files.items()}
    if sett:
        parts = []
        for name, st in sett.items():
            rec = (f"{st['frf_nperseg']} samples per record"
                   if st.get("frf_nperseg") is not None else "record chosen from the data")
            pad = (f", FFT length {st['frf_nfft']}" if st.get("frf_nfft") not in
                   (None, st.get("frf_nperseg")) else "")
            parts.append(f"{name} ({files.get(name, '')}): {st.get('variant')} variant, "
                         f"{rec}{pad}; the same table: `mvtk damping {files.get(name, 'FILE')}"
                         f" {st.get('command_options', '')}`")
        sec.text("Half-power estimates by mvtk.damping.estimate, the estimator of `mvtk "
                 "damping`, with its defaults unless the study sets them: "
                 + "; ".join(parts) + ".")
    decays = d.get("decays") or {}
    if len(decays) > 1:
        sec.table(pd.DataFrame([
            {"test": name, "channel": dec["channel"],
             "fn_hz (envelope)": (dec["envelope"].get("fn_hz") or [np.nan])[0],
             "zeta envelope fit": (dec["envelope"].get("zeta") or [np.nan])[0],
             "zeta log decrement": (dec["log_decrement"].get("zeta") or [np.nan])[0],
             "reliable": (dec["envelope"].get("reliable") or [None])[0]}
            for name, dec in decays.items()]), "damping_decays",
            "Free decays (envelope fit and logarithmic decrement of each)",
            passed_column=None)
    md = d.get("model_damping")
    if md:
        sec.text(f"Rayleigh pair used for the SE and the controllers: {md['method']} "
                 f"(alpha = {md['alpha']:.5g} 1/s, beta = {md['beta']:.5g} s).")
    for w in d.get("half_power_warnings", []) + d.get("decay_warnings", []):
        sec.note(w, kind="unavailable")
    def _bands(test: str):
        if not hp:
            return []
        return [(a, b, c) for a, b, c, t in zip(hp["f1_hz"], hp["f2_hz"], hp["fn_hz"], tests)
                if t == test and np.isfinite([a, b, c]).all()]

    if arr is not None and "frf_abs_bb" in arr:
        sec.figure(partial(plot_frf, arr["frequency_bb"].values, arr["frf_abs_bb"].values,
                            bands=_bands("broadband"), f_range=(5.0, 400.0),
                            ylabel=f"|H| [{d.get('frf_units', '')}]",
                            title="Broadband impact FRF (H1) with half-power bands"),
                   "Short broadband impact test: FRF up to the anti-aliasing cut-off with the "
                   "half-power bands of the higher identified modes (shaded).")
    if arr is not None and "frf_abs" in arr:
        bands = _bands("impact")
        coh = arr["coherence"].values if "coherence" in arr else None
        sec.figure(partial(plot_frf, arr["frequency"].values, arr["frf_abs"].values, bands=bands,
                            ylabel=f"|H| [{d.get('frf_units', '')}]", coherence=coh,
                            title="Impact FRF (H1) with half-power bands"),
                   "Impact-test FRF with the half-power bands of each mode (shaded) and its "
                   "coherence (below): where the coherence drops, the FRF is not to be trusted.")
        for i, (lo, hi, fn) in enumerate(bands):
            w = max(6 * (hi - lo), 0.3)
            sec.figure(partial(plot_frf, arr["frequency"].values, arr["frf_abs"].values,
                                bands=[(lo, hi, fn)], f_range=(fn - w, fn + w),
                                ylabel=f"|H| [{d.get('frf_units', '')}]", markers=True,
                                coherence=coh,
                                title=f"Mode {i + 1}: zoom on the half-power band"),
                       f"Half-power band of mode {i + 1} and the frequency lines across it.")
    if arr is not None and "decay_x" in arr and d.get("envelope"):
        t = arr["decay_t"].values
        x = arr["decay_x"].values
        fn, z = d["envelope"]["fn_hz"][0], d["envelope"]["zeta"][0]
        a0 = float(np.max(np.abs(x[t < t[0] + 2.0 / fn])))
        fit = a0 * np.exp(-z * 2 * np.pi * fn * (t - t[0]))
        sec.figure(partial(plot_decay, t, x, fit=fit, label_fit=f"exp(-zeta wn t), zeta = {z:.3e}",
                              ylabel=f"tip displacement [{d.get('decay_units', '')}]",
                              title="Free decay from mode 1 and the envelope fit"),
                   "Free decay (raw, not band-passed) with the fitted exponential envelope "
                   "(scaled to the initial amplitude).",
                   # a band of 1000 min/max columns and two 2000-point fits: its SVG is
                   # larger than the PNG, so the PNG is rendered directly
                   image_format="png")


def _section_fe(rep: Report, res: StudyResult) -> None:
    from ..plot import plot_mode_shapes

    if _not_configured(res, "fe"):
        return
    sec = rep.section(_title("FE model and updating", res, "Table 2", "fe_fn_hz"))
    if _stage_missing(sec, res, "fe"):
        return
    fe = res.results["fe"]
    sec.text(f"Nominal FE model: {fe['n_nodes']} nodes, {fe['n_elements']} elements, "
             f"{fe['n_dof']} free DOFs; total mass moving with the clamp "
             f"{fe['total_mass_kg']:.4g} kg.")
    cols = {}
    up = res.results.get("updating")
    targets = (up or {}).get("targets_hz") or _ref(res, "experiment_fn_hz")
    updated = list(up["fn_hz"]) if up else None
    if targets:
        # rows in mode order whatever the order the targets were listed in (the updated
        # frequency of each target follows it)
        order = np.argsort(np.asarray(targets, dtype=float), kind="stable")
        targets = [targets[i] for i in order]
        if updated is not None and len(updated) == len(order):
            updated = [updated[i] for i in order]
        cols["experiment"] = targets
    cols["FE nominal"] = _nominal_by_pairing(fe, up, targets)
    if up:
        cols["FE updated"] = updated
    if _ref(res, "fe_fn_hz"):
        cols["paper FE"] = _ref(res, "fe_fn_hz")
    if targets:
        sec.table(frequency_table(cols, "experiment"), "table2_frequencies",
                  ("Table 2: " if _has_refs(res, "fe_fn_hz") else "")
                  + "FE vs experiment eigenfrequencies [Hz] (errors in % of the "
                  "experiment)", passed_column=None)
        text = _model_form_text(res)
        if text:
            sec.text(text)
        if up and "mac" in up.get("pairing", []):
            macs = ", ".join(f"{m:.3f}" for m in up.get("mac", []))
            sec.text("The updating paired each target with an FE mode by MAC against the "
                     f"shape identified from the multi-point test (MAC {macs}), not by mode "
                     "order: a mode swap during updating cannot pass unnoticed.")
    modes = pd.DataFrame({"mode": np.arange(1, len(fe["fn_hz"]) + 1),
                          "fn_hz nominal": fe["fn_hz"], "type": fe["mode_type"],
                          "mass fraction uz": fe["mass_fraction_uz"]})
    if up:
        k = min(len(up["model_fn_hz"]), len(modes))
        modes["fn_hz updated"] = np.nan
        modes.loc[: k - 1, "fn_hz updated"] = up["model_fn_hz"][:k]
    sec.table(modes, "fe_modes", f"The {len(modes)} lowest modes of the FE model",
              passed_column=None)
    if up:
        truth = res.study.config.get("truth") or {}
        prm = pd.DataFrame({"parameter": up["parameters"],
                            "unit": [parameter_unit(p) for p in up["parameters"]],
                            "initial": up["initial_values"],
                            "updated": up["values"], "std": up["std"],
                            "at bound": up["at_bound"]})
        if truth:
            prm["SYNTHETIC truth"] = [truth.get(p, float("nan")) for p in up["parameters"]]
        sec.table(prm, "updating_parameters",
                  f"Updated parameters ({up['n_evaluations']} evaluations, "
                  f"condition number {up['condition_number']:.3g}, "
                  f"identifiable: {up['identifiable']}; parameter std: "
                  f"{up.get('covariance_scaling') or 'a posteriori (residual variance)'})",
                  passed_column=None)
        if up.get("residual_verdict"):
            _updating_residuals(sec, up)
        for w in up.get("warnings", []):
            sec.note(w, kind="unavailable")
    elif "updating" in res.failed or "updating" in res.unavailable:
        _stage_missing(sec, res, "updating")
    arr = res.arrays.get("fe")
    if arr is not None:
        k = min(4, arr.sizes["mode"])
        sec.figure(partial(plot_mode_shapes, arr["nodes"].values, arr["uz"].values[:, :k],
                                    fe["fn_hz"][:k]),
                   "Mode shapes (uz) of the nominal FE model; black line: nodal line.")
        if "correlation" not in res.results:
            _mode_animation(sec, res)


def _nominal_by_pairing(fe: dict, up: dict | None, targets) -> list:
    """Nominal FE frequency of the mode paired with each target (in target order).

    The pairing is the updating's (by MAC, or by frequency on the nominal model); its
    mode numbers count elastic modes, so rigid-body modes of the nominal table are
    skipped. Without an updating the targets are paired by frequency. NaN where the
    paired mode is beyond the modes the FE stage tabulated.
    """
    f = np.asarray(fe["fn_hz"], dtype=float)
    if not targets:
        return list(f)
    if up and up.get("modes") is not None and len(up["modes"]) == len(targets):
        t_up = np.asarray(up["targets_hz"], dtype=float)
        order = np.argsort(t_up, kind="stable")
        elastic = f[f >= 0.01 * float(np.min(t_up))]
        modes = [int(up["modes"][i]) for i in order]
        return [float(elastic[m - 1]) if 0 < m <= elastic.size else float("nan")
                for m in modes]
    pairs = _pair(list(targets), list(f), max_rel=1.0)
    return [float(f[pairs[i]]) if i in pairs else float("nan") for i in range(len(targets))]


def _mc_paths(u: dict) -> str:
    """How the Monte-Carlo samples were solved, with the reduced path's error bound."""
    paths = u.get("paths") or {}
    n_red = sum(n for p, n in paths.items() if p.startswith("reduced"))
    if not n_red:
        note = u.get("reduced_note") or ""
        return ("every sample by a full eigen solve" + (f" ({note})" if note else "") + ".")
    bound = u.get("max_error_bound")
    bound_txt = f"{bound:.1e}" if bound is not None else "n/a"
    return (f"{n_red} samples by Rayleigh-Ritz on a reduced basis of the centre model "
            f"({paths.get('reduced+correction', 0)} of them after a correction step; "
            f"Kato-Temple bound of the relative frequency error at most {bound_txt} for "
            "the interpolated K and M, whose entries are checked against a real build to "
            f"1e-11), {paths.get('full', 0)} by a full eigen solve.")


def _section_uncertainty(rep: Report, res: StudyResult) -> None:
    from ..plot import plot_fn_histogram

    if "uncertainty" not in res.study.config:
        return
    sec = rep.section("Uncertainty propagation (Monte Carlo)")
    if _stage_missing(sec, res, "uncertainty"):
        return
    u = res.results["uncertainty"]
    base = "updated" if "updating" in res.results else "nominal"
    names = ", ".join(f"{p['path']} ({100 * p['rel_std']:g} %)" for p in u["parameters"])
    sec.text(f"Scatter of the inputs {names} (relative standard deviations; independent "
             f"{u['distribution']} distributions centred on the {base} structure) propagated "
             f"to the eigenfrequencies by Monte Carlo with mvtk.scale.monte_carlo: "
             f"{u['n_samples']} samples (seed {u['seed']}, {u['scheduler']}), "
             f"{u['n_failed']} failed; {_mc_paths(u)} Only the scatter of the inputs "
             "named is propagated "
             "(no other material, geometry or boundary uncertainty, no model-form error). "
             "cov_first_order is the linearised estimate sqrt(sum (S c)^2) from the "
             "log-sensitivities S = d ln f / d ln p below; with small input scatter it "
             "should match the sampled CoV within the sampling error of "
             f"{u['n_samples']} samples (about {100 / np.sqrt(2 * (u['n_samples'] - 1)):.0f} "
             "% of the CoV). cov_first_order_same_samples applies the same linearisation "
             "to the drawn samples themselves: free of sampling error, its difference to "
             "cov measures only the nonlinearity of f(p).")
    sec.table(pd.DataFrame(u["statistics"]), "uncertainty_statistics",
              "Sampled eigenfrequency statistics per mode [Hz] (std with ddof = 1, "
              "cov = std / mean)", passed_column=None)
    inputs = pd.DataFrame(u["parameters"])
    if "path" in inputs:
        inputs.insert(1, "unit", [parameter_unit(p) for p in inputs["path"]])
    sec.table(inputs, "uncertainty_inputs",
              "Input scatter (mean and std in SI units) and log-sensitivities of the "
              "eigenfrequencies", passed_column=None)
    for w in u.get("warnings", []):
        sec.note(w, kind="unavailable")
    arr = res.arrays.get("uncertainty")
    if arr is not None:
        # the samples as they are (not mvtk.scale.MonteCarloResult: importing mvtk.scale
        # would load its dask and signal-processing stack for one figure)
        sec.figure(partial(plot_fn_histogram, SimpleNamespace(fn_hz=arr["fn_hz"].values), bins=12),
                   "Histograms of the sampled eigenfrequencies: mean (black) and the 5 % / "
                   "95 % percentiles (red, dashed).")


def _section_se(rep: Report, res: StudyResult) -> None:
    if _not_configured(res, "reduction"):
        return
    sec = rep.section(_title("Super element", res, "Tables 4 and 5", "fe4_fn_hz", "se4_fn_hz"))
    if _stage_missing(sec, res, "reduction"):
        return
    r = res.results["reduction"]
    sec.text("Retained nodes (nearest FE node to each configured point): " + "; ".join(
        f"{k} -> node {v}" for k, v in r["retained_nodes"].items()) + ".")
    if r.get("sizes"):
        sizes = pd.DataFrame(r["sizes"]).set_index("quantity")
        fe_s, se_s = _ref(res, "fe_sizes"), _ref(res, "se_sizes")
        if fe_s and se_s and len(sizes) == len(fe_s):
            sizes["paper FE"] = fe_s
            sizes["paper SE"] = se_s
        sec.table(sizes, "table4_sizes", ("Table 4: " if fe_s and se_s else "")
                  + "FE vs SE model sizes", passed_column=None)
    m = pd.DataFrame(r["modes"])
    fe4, se4 = _ref(res, "fe4_fn_hz"), _ref(res, "se4_fn_hz")
    if fe4 and se4 and len(fe4) >= len(m):
        m["paper FE"] = fe4[: len(m)]
        m["paper SE"] = se4[: len(m)]
    n_ret = len(r["retained_nodes"])
    n_fix = res.study.config["reduction"].get("n_modes")
    text = (f"Craig-Bampton super element with {n_ret} retained nodes and {n_fix} "
            "fixed-interface modes. A truncated Craig-Bampton SE can only be stiffer than "
            "its FE model (Rayleigh-Ritz bound); its eigenfrequency errors are in the table.")
    if fe4 and se4:
        pub = 100 * (np.asarray(se4, float) / np.asarray(fe4, float) - 1)
        text += (f" The published SE of {_refs_name(res)} is {pub.min():.2g}-{pub.max():.2g} "
                 "% stiffer than its own FE model.")
    sec.text(text)
    sec.table(m, "table5_fe_vs_se", ("Table 5: " if fe4 and se4 else "")
              + "FE vs SE eigenfrequencies [Hz]; error = 100 (SE - FE) / FE, error of SE = "
              "100 (SE - FE) / SE", passed_column=None)
    if r.get("static"):
        st = pd.DataFrame(r["static"])
        num = st.select_dtypes("number")
        summary = pd.DataFrame({"quantity": list(num.columns),
                                "max over the unit boundary loads": num.abs().max().values})
        sec.table(summary, "se_static_check_summary",
                  f"Static check: unit loads on each of the {len(st)} boundary DOFs, FE vs SE "
                  "displacement (relative errors; constraint modes are statically exact)",
                  passed_column=None)
        rep.tables["se_static_check"] = st  # full table as CSV only


def _section_control(rep: Report, res: StudyResult) -> None:
    from ..plot import plot_spectra, plot_time_responses

    if _not_configured(res, "control"):
        return
    sec = rep.section("Active vibration control on the SE")
    if _stage_missing(sec, res, "control"):
        return
    c = res.results["control"]
    cfg = res.study.config["control"]
    act = (res.results.get("reduction") or {}).get("actuator")
    if act and act.get("piezo"):
        caps = ", ".join(f"{k} {1e9 * v:.4g} nF" for k, v in act["capacitance_F"].items())
        sec.text(
            "Piezo electrodes coupled in the shells (mvtk.fe.piezo_coupling): "
            + (f"actuator '{act['name']}' (input, V)" if len(act.get("actuators", [])) < 2
               else f"actuators {', '.join(act['actuators'])} (inputs, V; a controller "
               f"drives '{act['name']}' unless it names others, the static deflection "
               "below is its)")
            + f", sensor(s) {', '.join(act['sensors'])} read as "
            f"{act['sensing']} (the controllers' measurement is the first one, "
            f"{act['sensor_unit']}); blocked capacitances {caps}. The super element keeps "
            "each electrode's static shape and a block of residual inertia vectors "
            "(mvtk.reduction.with_electrodes), so the voltage-to-sensor feed-through of "
            "the collocated pair is kept. Static tip "
            f"deflection per volt: {1e6 * act['tip_per_volt_full_m']:.4g} um/V on the full "
            f"FE model, {1e6 * act['tip_per_volt_plant_m']:.4g} um/V from the plant "
            f"({act['plant_modes']} eigenmodes up to {act['plant_fn_max_hz']:.0f} Hz plus "
            f"the static residual); damping: {act['damping']}. "
            f"Actuator limit: ±{c['actuator_limit_v']:g} V ([control] actuator_limit_v).")
        em = pd.DataFrame(act["emcc"])
        if len(em):
            sec.table(em, "piezo_emcc", "Modal electromechanical coupling k^2 = (f_oc^2 - "
                      "f_sc^2) / f_sc^2 of each electrode (the others shorted)",
                      passed_column=None)
    elif act:
        eq7 = act.get("paper_eq7_moment_per_volt", float("nan"))
        eq7_text = (f" ({_refs_name(res)}, printed eq. 7: {eq7:.5g} N m/V)"
                    if res.study.config.get("references") and np.isfinite(eq7) else "")
        sec.text(
            f"Actuator input: the voltage of patch '{act['name']}' (V). Moment per volt "
            "(pin-force model, Crawley & de Luis 1987, integrated over the layers under the "
            f"patch): {act['moment_per_volt_per_m']:.5g} N m/(V m), times the patch width "
            f"{1e3 * act['width_m']:.4g} mm = {act['moment_per_volt']:.5g} N m/V{eq7_text}. "
            "The moment pair acts on the rotations of the two retained actuator-edge nodes, "
            "where the super element represents it exactly (constraint modes). Static tip "
            "deflection per volt on the full FE model: "
            f"{1e6 * act['tip_per_volt_nodes_m']:.4g} um/V with the moments at the two nodes, "
            f"{1e6 * act['tip_per_volt_edge_lines_m']:.4g} um/V with the same moments spread "
            "along the patch edge lines; SE plant DC gain "
            f"{1e6 * act['tip_per_volt_plant_m']:.4g} um/V ({act['plant_modes']} SE eigenmodes "
            f"up to {act['plant_fn_max_hz']:.0f} Hz plus the static residual of the others). "
            f"Actuator limit: ±{c['actuator_limit_v']:g} V ([control] actuator_limit_v).")
        if act.get("tip_per_volt_shell_coupled_m") is not None:
            w_c, w_e = act["tip_per_volt_shell_coupled_m"], act["tip_per_volt_edge_lines_m"]
            sec.text(
                "Cross-check: the same patch coupled in the shells (mvtk.fe.piezo_coupling, "
                "the biaxial induced strain of the piezo ply, no pin-force idealisation) "
                f"deflects the tip by {1e6 * w_c:.4g} um/V, {100 * (w_c / w_e - 1):+.0f} % "
                "against the edge-line moments: the plate around the patch holds it "
                "laterally, so it bends the plate with the factor 1 + nu of cylindrical "
                "bending that the beam-like pin-force model leaves out. The plant keeps the "
                "pin-force model.")
    lyap = [k["name"] for k in cfg.get("controllers", [])
            if str(k.get("type", "")).startswith("Lyapunov")]
    sec.text("The SE plant is released from its first mode with a tip displacement of "
             f"{cfg['initial_tip_displacement_m']:g} m and the controllers are switched on "
             "at t = 0. Peak voltage in V and the equivalent edge moment in N m; closed-loop "
             "zeta of the linear controllers is the small-signal one (command below the "
             "limit). Settling time: after it the tip displacement stays "
             f"within {100 * c['settle_band']:g} % of its initial amplitude. Gain and "
             "phase margins: the loop broken at the actuator input "
             "(mvtk.control.loop_margins), with the factor on the loop gain at the edge of "
             "stability; – where there is none (open loop, a multi-input or nonlinear law, no "
             "crossover)."
             + (f" {', '.join(lyap)}: the velocity form of the Lyapunov controller with a "
                "boundary layer (mvtk.control.LyapunovBangBang); being nonlinear it has no "
                "closed-loop poles (zeta shown as –)." if lyap else ""))
    df = pd.DataFrame(c["metrics"])
    sec.table(df, "controller_comparison", "Controller comparison", passed_column=None)
    ps, os_ = _ref(res, "ppf_settling_s"), _ref(res, "other_settling_s")
    if ps is not None:
        sec.text(f"{_refs_name(res)}: PPF settles in about {ps} s, the other controllers "
                 f"in about {os_} s.")
    arr = res.arrays.get("control")
    if arr is not None:
        t = arr["time"].values
        tips = {str(r): arr["tip"].sel(run=r).values for r in arr["run"].values}
        sec.figure(partial(plot_time_responses, t, tips, zoom=(0.0, min(1.0, t[-1])),
                                       title="Tip displacement with and without control"),
                   "Tip displacement vs time (top) and a zoom on the first second (bottom).")
        f = arr["frequency"].values
        spec = {str(r): arr["spectrum"].sel(run=r).values for r in arr["run"].values}
        fmax = min(f[-1], max(60.0, 3.0 * float(res.results["control"].get("fn1_hz", 0.0))))
        sec.figure(partial(plot_spectra, f, spec, f_range=(0.0, fmax),
                                title="Amplitude spectra of the tip displacement"),
                   "FFT amplitude spectra of the tip displacement with and without control.")


def _png(b64: str) -> bytes:
    import base64

    return base64.b64decode(b64)


#: How the report's text counts the updating residual verdicts.
_VERDICT_TEXT = {"noise": "within identification noise",
                 "model-form term": "explained by the model-form term",
                 "model form": "model form (beyond noise and the model-form term)",
                 "no redundancy": "not testable (no redundancy)"}


def _updating_residuals(sec, up: dict) -> None:
    """The updating residuals with their standard deviations and noise/model-form verdicts."""
    n = len(up["targets_hz"])
    rows = (up.get("summary") or {}).get("residuals") or [{}] * n
    labels = [r.get("target", f"f{i + 1}") for i, r in enumerate(rows)]
    tab = pd.DataFrame({
        "target": labels, "target_hz": up["targets_hz"], "updated_hz": up["fn_hz"],
        "residual_hz": up["residual_hz"],
        "identification_std_hz": up["identification_std_hz"],
        "std from": up.get("target_std_source") or [""] * n,
        "std_hz": up["target_std_hz"],
        "noise_limit_hz": up["noise_limit_hz"],
        "model_form_limit_hz": up["limit_hz"],
        "verdict": up["residual_verdict"]})
    mf = up.get("model_form_std")
    term = (f"a model-form term of {100 * mf:.3g} % of the frequency" if mf is not None
            else "no model-form term")
    sec.table(tab, "updating_residuals",
              "Updating residuals against their standard deviations: std = identification "
              f"std combined with {term}, each target weighted by 1/std^2; the limits are "
              "twice the residual's standard deviation after the fit (noise alone; noise "
              "and the model-form term). Verdict: noise (within the noise limit), "
              "model-form term (explained by the stated model-form term), model form "
              "(beyond both: the model lacks something no updated value supplies), "
              "no redundancy (as many parameters as targets fit it exactly)",
              passed_column=None)


def _model_form_text(res: StudyResult) -> str | None:
    """What updating explains and what it cannot: residuals vs identification scatter."""
    up = res.results.get("updating")
    if not up or not up.get("targets_hz"):
        return None
    f_up = np.asarray(up["fn_hz"], dtype=float)
    f_t = np.asarray(up["targets_hz"], dtype=float)
    resid = 100 * np.abs(f_up / f_t - 1)
    parts = [f"After updating {len(up['parameters'])} parameter(s) against {len(f_t)} "
             f"target frequencies the residual is {resid.min():.2g}-{resid.max():.2g} %."]
    verdicts = list(up.get("residual_verdict") or [])
    counted = {v: verdicts.count(v) for v in ("noise", "model-form term", "model form",
                                              "no redundancy") if v in verdicts}
    mod = res.results.get("modal")
    if counted:
        vf = up.get("variance_factor")
        parts.append(
            "Against the targets' standard deviations (identification and model-form "
            "term, table below): "
            + ", ".join(f"{v} {_VERDICT_TEXT[k]}" for k, v in counted.items()) + "."
            + (f" The variance factor chi^2 / (m - n) = {vf:.3g} tests the stated "
               "standard deviations (about 1 when they describe the residuals)."
               if vf is not None and np.isfinite(vf) else ""))
    elif mod:
        fn_id = np.asarray(mod["table"]["fn_hz"], dtype=float)
        near = [fn_id[np.argmin(np.abs(fn_id - f))] for f in f_t]
        scatter = 100 * np.abs(np.asarray(near) / f_t - 1)
        parts.append(f"The same modes identified independently from the multi-point test "
                     f"differ from the targets by at most {scatter.max():.2g} %.")
    std = np.asarray(up["std"], dtype=float)
    cov = np.asarray(up.get("covariance") or [[]], dtype=float)
    if cov.ndim == 2 and cov.shape[0] >= 2 and np.isfinite(cov).all():
        d = np.sqrt(np.diag(cov))
        names = [p for p, s in zip(up["parameters"], std) if np.isfinite(s)]
        if d.all() and len(names) == cov.shape[0]:
            rho = cov / np.outer(d, d)
            pairs = [f"{names[i]} / {names[j]} {rho[i, j]:+.2f}"
                     for i in range(len(names)) for j in range(i + 1, len(names))]
            parts.append("Correlation of the updated parameters (from their covariance "
                         "(J' W J)^-1): " + ", ".join(pairs) + ".")
    if np.isfinite(std).any():
        parts.append("The parameter standard deviations (from the Jacobian and the "
                     "targets' standard deviations) describe the scatter of the fit, not the "
                     "bias that the "
                     "model-form error puts on the parameters: an updated parameter can be "
                     "several standard deviations from the specimen's own value.")
    return " ".join(parts)


def _slug(name: str) -> str:
    """A file-name part of a test name (letters, digits, underscores)."""
    import re

    return re.sub(r"[^A-Za-z0-9_]+", "_", str(name)).strip("_") or "test"


def _orders_text(mod: dict) -> str:
    """``", model orders 2..N"`` of an identified test (empty for older results)."""
    orders = mod.get("orders")
    return f", model orders {orders[0]}..{orders[1]}" if orders else ""


def _section_multipoint(rep: Report, res: StudyResult) -> None:
    """Multi-point test: identified modes, stabilisation, correlation with the FE model."""
    if "modal" not in res.study.config:
        return
    sec = rep.section("Multi-point test, identified modes and test-FE correlation")
    if _stage_missing(sec, res, "modal"):
        return
    mod = res.results["modal"]
    sec.text(f"{mod['file']}: {mod['n_responses']} responses x {mod['n_references']} "
             f"reference(s), {mod['n_lines']} lines ({mod['frf_type'] or 'FRF'}), identified "
             f"by pLSCF + LSFD (mvtk.modal{_orders_text(mod)}) in {mod['band_hz'][0]:g}-"
             f"{mod['band_hz'][1]:g} Hz. A mode marked not reliable says why in its row."
             + (f" {mod['note'][0].upper()}{mod['note'][1:]}." if mod.get("note") else "")
             + "".join(f" {a[0].upper()}{a[1:]}." for a in mod.get("analysis") or ()))
    sec.table(pd.DataFrame(mod["table"]), "modal_modes",
              "Identified modes with their quality (MPC, MPD, stable orders)",
              passed_column=None)
    sec.figure(_png(mod["figures"]["stabilisation"]),
               "Stabilisation diagram (CMIF behind); dashed: selected modes")
    sec.figure(_png(mod["figures"]["synthesis"]), "Measured vs synthesised FRFs")
    if "uncertainty" in mod["figures"]:
        sec.figure(_png(mod["figures"]["uncertainty"]),
                   "Identified damping against frequency, bars +-2 standard deviations "
                   "(fn_std_hz, zeta_std: first-order, from the FRF fit residual); hollow: "
                   "not reliable")
    for name, t in (mod.get("tests") or {}).items():
        n_common = (t["comparison"]["n_common_dofs"] or [0])[0]
        sec.text(f"Multi-point test {name}, {t['file']}: {t['n_responses']} responses x "
                 f"{t['n_references']} reference(s), {t['n_lines']} lines, identified on "
                 f"its own{_orders_text(t)} in {t['band_hz'][0]:g}-{t['band_hz'][1]:g} Hz; "
                 "each of its modes "
                 "beside the mode of the test above nearest in frequency (within "
                 f"modal.pair_within; 0: none), MAC on the {n_common} DOFs both tests measured."
                 + (f" {t['note'][0].upper()}{t['note'][1:]}." if t.get("note") else "")
                 + "".join(f" {a[0].upper()}{a[1:]}." for a in t.get("analysis") or ()))
        sec.table(pd.DataFrame(t["table"]), f"modal_modes_{_slug(name)}",
                  f"Identified modes of multi-point test {name}", passed_column=None)
        sec.table(pd.DataFrame(t["comparison"]), f"modal_compare_{_slug(name)}",
                  f"Multi-point test {name} vs the test above: the same modes",
                  passed_column=None)
    if "correlation" not in res.results:
        _stage_missing(sec, res, "correlation")
        return
    cor = res.results["correlation"]
    pairs = pd.DataFrame(cor["pairs"])
    pairs = pairs.drop(columns=[c for c in ("index",) if c in pairs.columns])
    sec.text(f"{cor['n_sensors']} sensor DOFs mapped onto the updated FE model "
             f"({cor['mapping']} functions). The modes that were not updating targets are "
             "predictions of the updated model: their frequency error is the model-form "
             "check.")
    sec.table(pairs, "correlation_pairs",
              "Test-FE mode pairs: updated FE model vs the multi-point test (MAC, frequency "
              "error; 'updating target' = used in the updating)", passed_column=None)
    pred = pairs[pairs["paired"] & ~pairs.get("updating target", False)] if len(pairs) else pairs
    if len(pred):
        worst = pred.loc[pred["df_pct"].abs().idxmax()]
        sec.text(f"Model-form check: {len(pred)} mode(s) not used as targets are predicted "
                 f"within {abs(worst['df_pct']):.2g} % (worst: test mode "
                 f"{int(worst['test_mode'])} at {worst['fn_test_hz']:.2f} Hz). Whatever "
                 "the specimen has and the model lacks (added masses, joints, thickness "
                 "tolerances, mesh) shows most in the modes that load those details.")
    dofs = pd.DataFrame(cor["dofs"])
    dofs = dofs.drop(columns=[c for c in ("index",) if c in dofs.columns])
    sec.table(dofs, "correlation_dofs", "Sensor mapping and COMAC per test DOF",
              passed_column=None)
    captions = {"mac": "MAC matrix: test vs updated FE", "paired_shapes":
                "Paired test and FE shapes", "test_on_mesh":
                "FE mesh with the test wireframe and sensors"}
    for name, b64 in cor["figures"].items():
        sec.figure(_png(b64), captions.get(name, name))
    _mode_animation(sec, res)


def _stage_warnings(res: StudyResult) -> list[str]:
    """Warnings the stages raised, and results the stages marked as not reliable."""
    out: list[str] = []
    for stage, r in res.results.items():
        if not isinstance(r, dict):
            continue
        for key in sorted(k for k in r if str(k).endswith("warnings")):
            out += [f"{stage}: {w}" for w in (r[key] or [])]
        for sub in r.values():   # e.g. damping.rayleigh_chowdhury.warnings
            if isinstance(sub, dict):
                out += [f"{stage}: {w}" for w in (sub.get("warnings") or [])]
    mod = res.results.get("modal")
    if mod:
        for name, tab in [("", mod["table"])] + [(f" of {n}", t["table"]) for n, t in
                                                (mod.get("tests") or {}).items()]:
            t = pd.DataFrame(tab)
            if "reliable" in t:
                for _, row in t[~t["reliable"].astype(bool)].iterrows():
                    out.append(f"modal: identified mode {int(row['mode'])}{name} at "
                               f"{row['fn_hz']:.4g} Hz is not reliable: "
                               f"{row.get('reason', '')}")
        for t in (mod.get("tests") or {}).values():
            out += [f"modal: {w}" for w in t.get("warnings") or []]
    cor = res.results.get("correlation")
    if cor:
        pairs = pd.DataFrame(cor["pairs"])
        for _, p in pairs.iterrows():
            if not bool(p.get("paired", True)):
                out.append(f"correlation: test mode {p['test_mode']} has no FE partner"
                           + (f" ({p['reason']})" if p.get("reason") else ""))
    up = res.results.get("updating")
    if up:
        for name, at in zip(up["parameters"], up.get("at_bound", [])):
            if at:
                out.append(f"updating: {name} ended at a bound of its range")
        if up.get("identifiable") is False:
            out.append("updating: the parameters are not identifiable from the targets")
        rows = (up.get("summary") or {}).get("residuals") or []
        beyond = [r.get("target", f"f{i + 1}") for i, (r, v) in
                  enumerate(zip(rows, up.get("residual_verdict") or [])) if v == "model form"]
        if beyond:
            out.append(f"updating: the residual of {', '.join(beyond)} is beyond noise and "
                       "the model-form term (model form: the model lacks something no "
                       "updated value supplies)")
    return list(dict.fromkeys(out))


#: two estimates of one mode's damping ratio from different sections that differ by more
#: than this factor are listed as an inconsistency in the summary
ZETA_FACTOR = 1.5


def _inconsistencies(res: StudyResult) -> list[str]:
    """Disagreements between sections: one mode's frequency and damping from the
    single-point tests (half-power) and the multi-point test (pLSCF + LSFD)."""
    hp = (res.results.get("damping") or {}).get("half_power")
    mod = res.results.get("modal")
    if not hp or not mod:
        return []
    tol = res.study.config["checks"]["identified_fn_rel"]
    t = pd.DataFrame(mod["table"])
    f_m, z_m = t["fn_hz"].to_numpy(float), t["zeta"].to_numpy(float)
    out = []
    tests = hp.get("test", ["impact"] * len(hp["fn_hz"]))
    for i, (fn, z, test) in enumerate(zip(hp["fn_hz"], hp["zeta"], tests)):
        if not np.isfinite([fn, z]).all() or not len(f_m):
            continue
        j = int(np.argmin(np.abs(f_m - fn)))
        if abs(f_m[j] / fn - 1) > 0.05:
            continue   # not the same mode
        if abs(f_m[j] / fn - 1) > tol:
            out.append(f"mode {i + 1}: {fn:.5g} Hz from the {test} test (half-power) vs "
                       f"{f_m[j]:.5g} Hz from the multi-point test ({100 * (f_m[j] / fn - 1):+.2g}"
                       f" %, more than the {100 * tol:g} % identification tolerance)")
        if z > 0 and z_m[j] > 0 and max(z / z_m[j], z_m[j] / z) > ZETA_FACTOR:
            out.append(f"mode {i + 1} ({fn:.4g} Hz): damping ratio {z:.3g} from the {test} test "
                       f"(half-power) vs {z_m[j]:.3g} from the multi-point test (pLSCF): a "
                       f"factor {max(z / z_m[j], z_m[j] / z):.2g} apart (more than "
                       f"{ZETA_FACTOR:g})")
    return out


def _relative_strings(obj, base: Path):
    """``obj`` (a parsed study) with every absolute path written relative to ``base``."""
    if isinstance(obj, dict):
        return {k: _relative_strings(v, base) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [_relative_strings(v, base) for v in obj]
    if isinstance(obj, str | Path) and Path(obj).is_absolute():
        return relative_path(obj, base)
    return obj


def _mode_animation(sec, res: StudyResult) -> None:
    """Animated FE mode shapes on the FE mesh; with a multi-point test, the test
    wireframe over it moving with the identified mode paired to each FE mode by MAC."""
    arr = res.arrays.get("fe")
    if arr is None:
        return
    fe = res.results["fe"]
    xyz = np.asarray(arr["nodes"].values, dtype=float)
    uz = np.asarray(arr["uz"].values, dtype=float)
    k = uz.shape[1]
    fn = list(fe["fn_hz"])[:k]
    labels = [f"FE mode {i + 1}: {fn[i]:.4g} Hz" for i in range(k)]
    overlay = None
    caption = (f"The {k} lowest modes of the nominal FE model (uz) on its mesh; drag to "
               "rotate, choose the mode above. The page plays it offline.")
    marr = res.arrays.get("modal")
    if marr is not None and "modal" in res.results:
        from ._ema import geometry_of

        files = res.study.extra_files
        study = SimpleNamespace(has_extra_file=files.__contains__, extra_file=files.__getitem__)
        try:
            geo = geometry_of(study, marr)
        except Exception:   # noqa: BLE001 - the animation shows the FE model alone
            geo = None
        if geo is not None:
            shapes = np.real(np.asarray(marr["shapes"].values))        # (mode, dof)
            vec = geo.sensor_vectors()                                   # (dof, 3)
            rows = [geo.row(sn.node) for sn in geo.sensors]
            disp = np.zeros((geo.n_nodes, 3, shapes.shape[0]))
            for d, r in enumerate(rows):
                disp[r] += vec[d][:, None] * shapes[:, d][None, :]
            # FE uz at the FE node nearest each test node: MAC pairing and sign
            near = np.argmin(np.linalg.norm(xyz[None, :, :] - geo.xyz[:, None, :], axis=2),
                             axis=1)
            fe_at = uz[near]                                             # (n_test, k)
            test_z = disp[:, 2, :]                                       # (n_test, modes)
            num = (fe_at.T @ test_z) ** 2
            den = np.outer((fe_at**2).sum(0), (test_z**2).sum(0))
            mac = np.divide(num, den, out=np.zeros_like(num), where=den > 0)   # (k, modes)
            ov = np.full((geo.n_nodes, 3, k), np.nan)
            f_test = np.asarray(marr["fn_hz"].values, dtype=float)
            for j in range(shapes.shape[0]):
                i = int(np.argmax(mac[:, j]))
                if mac[i, j] < 0.5 or np.isfinite(ov[0, 0, i]):
                    continue
                sign = np.sign(fe_at[:, i] @ test_z[:, j]) or 1.0
                ov[:, :, i] = sign * disp[:, :, j]
                labels[i] += f" / test mode {j + 1}: {f_test[j]:.4g} Hz (MAC {mac[i, j]:.2f})"
            edges = geo.edges()
            overlay = {"xyz": geo.xyz, "shapes": ov, "name": "test wireframe",
                       "edges": edges if len(edges) else None}
            caption = (f"The {k} lowest modes of the nominal FE model (uz, blue mesh) with "
                       f"the test wireframe ({geo.n_nodes} test nodes, red"
                       + ("" if len(edges) else "; lines: triangulation of the test nodes")
                       + ") moving with the identified mode paired to each FE mode by MAC "
                       "(0.5 at least); drag to rotate, choose the mode above. The page "
                       "plays it offline.")
    sec.mode_animation(xyz, uz, labels, caption, overlay=overlay)


def build_report(res: StudyResult, hashes: dict[str, str]) -> Path:
    """Write ``res.out_dir/index.html`` (+ tables/*.csv) and return the page path."""
    import datetime as _dt

    doc = dict(res.study.config.get("report") or {})
    title = doc.pop("title", None) or f"Validation report: {res.study.name}"
    rep = Report(title)
    doc["date"] = doc.get("date") or _dt.datetime.now(_dt.UTC).date().isoformat()
    rep.set_document(**doc)
    _section_run(rep, res)
    _section_measurements(rep, res)
    _section_damping(rep, res)
    _section_fe(rep, res)
    _section_multipoint(rep, res)
    _section_uncertainty(rep, res)
    _section_se(rep, res)
    _section_control(rep, res)
    sec = rep.section("Pass/fail checks")
    checks = study_checks(res)
    checks_df = check_table(checks)
    if checks:
        sec.table(display_checks(checks_df), "checks", "Checks against the study's tolerances "
                  "(deviation: relative error of a two-sided check; margin: distance to the "
                  "nearest limit in % of that limit, negative when failed)")
        rep.tables["checks"] = checks_df   # the CSV keeps the tolerance as defined
    else:
        sec.unavailable("no check could be evaluated (no stage produced comparable numbers)")
    done = [s for s in ("damping", "modal", "updating", "correlation", "reduction", "control")
            if s in res.results]
    tests = sorted(p.name for p in res.study.measurement_files.values())
    if "modal" in res.results:
        tests.append(res.results["modal"]["file"])
        tests += [t["file"] for t in (res.results["modal"].get("tests") or {}).values()]
    sf = res.study.structure_file
    model = sf.name if sf is not None else "the inline structure"
    rep.executive_summary(
        checks_df,
        validated=(f"{res.study.name}: the FE model of {model} and the stages "
                   f"{', '.join(done) or 'none'}"),
        against=(f"the measurements {', '.join(tests) or '(none)'}"
                 + (" (SYNTHETIC)" if res.study.synthetic else "")
                 + " and the tolerances"
                 + (" and references" if res.study.config.get("references") else "")
                 + " of the study file"),
        warnings=_stage_warnings(res), inconsistencies=_inconsistencies(res))
    base = res.study.path.parent
    params = {"study": _relative_strings(res.study.config, base),
              "file_sha256": {relative_path(k, base): v for k, v in hashes.items()}}
    rep.add_provenance(collect_provenance(res.study.input_files, params, base=base))
    return rep.write(res.out_dir)
