"""Run a whole study: ingest -> FE -> damping -> updating -> SE -> controllers -> report."""

from __future__ import annotations

import sys
import time
import traceback
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..errors import ConfigError
from ._cache import StageCache, code_hash, stage_key
from ._config import Study, load_study

__all__ = ["StudyResult", "run", "STAGES"]

#: Subpackages whose source is part of each stage's cache key.
_CODE = {
    "ingest": ("io", "study/_stages.py"),
    "fe": ("fe", "reduction", "study/_stages.py"),
    "damping": ("signal", "damping", "fe", "reduction", "study/_stages.py"),
    "updating": ("fe", "updating", "study/_stages.py"),
    "uncertainty": ("fe", "updating", "scale", "study/_stages.py"),
    "reduction": ("fe", "reduction", "control", "study/_stages.py"),
    "control": ("control", "study/_stages.py"),
}

#: Stage names in execution order.
STAGES = ("ingest", "fe", "updating", "uncertainty", "damping", "reduction", "control",
          "report")


@dataclass(frozen=True)
class StudyResult:
    """Everything a study run produced.

    Attributes
    ----------
    study : Study
        The parsed study.
    out_dir : Path
    report_path : Path or None
        ``out_dir/index.html`` (None when the report stage was not reached).
    results : dict of str to dict
        JSON-like result of each completed stage.
    arrays : dict of str to xarray.Dataset
        Array results (time series, spectra, matrices) of the stages that have them.
    unavailable : dict of str to str
        Stages that did not run and why (API missing, upstream missing, not configured).
    failed : dict of str to str
        Stages that raised; the message and the last traceback line.
    cache_hits : tuple of str
        Stages loaded from the cache instead of being computed.
    timings_s : dict of str to float
        Wall time per stage (s).
    """

    study: Study
    out_dir: Path
    report_path: Path | None
    results: dict[str, dict] = field(default_factory=dict)
    arrays: dict[str, Any] = field(default_factory=dict)
    unavailable: dict[str, str] = field(default_factory=dict)
    failed: dict[str, str] = field(default_factory=dict)
    cache_hits: tuple[str, ...] = ()
    timings_s: dict[str, float] = field(default_factory=dict)

    @property
    def ok(self) -> bool:
        """True when no stage failed."""
        return not self.failed

    def to_dataframe(self):
        """One row per stage: status, cache hit, time."""
        import pandas as pd

        rows = []
        for s in STAGES:
            if s in self.failed:
                status = "failed"
            elif s in self.unavailable:
                status = "not available"
            elif s in self.results or s == "report" and self.report_path is not None:
                status = "cached" if s in self.cache_hits else "computed"
            else:
                status = "not run"
            rows.append({"stage": s, "status": status,
                         "time_s": self.timings_s.get(s, float("nan")),
                         "note": self.failed.get(s, self.unavailable.get(s, ""))})
        return pd.DataFrame(rows)


def _file_hashes(study: Study) -> dict[str, str]:
    from ..report import file_sha256

    return {str(p.name): file_sha256(p) for p in study.input_files}


def run(
    study_path: str | Path,
    out_dir: str | Path,
    *,
    use_cache: bool = True,
    progress: bool | None = None,
    report: bool = True,
) -> StudyResult:
    """Run the study in ``study_path`` and write its report to ``out_dir``.

    Parameters
    ----------
    study_path : path
        Study TOML (schema in :mod:`mvtk.study._config`).
    out_dir : path
        Output folder: ``index.html``, ``tables/*.csv``, ``cache/`` (stage results keyed
        by a hash of their inputs; a stage whose inputs did not change is loaded).
    use_cache : bool
        Set False to recompute every stage.
    progress : bool, optional
        Show a tqdm progress bar; default only when stderr is a terminal.
    report : bool
        Write the HTML report.

    Returns
    -------
    StudyResult

    Raises
    ------
    ConfigError
        Invalid study file (raised before any stage runs).
    """
    import mvtk

    study = load_study(study_path)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    cache = StageCache(out / "cache", enabled=use_cache)
    hashes = _file_hashes(study)
    version = mvtk.__version__
    results: dict[str, dict] = {}
    arrays: dict[str, Any] = {}
    keys: dict[str, str] = {}
    unavailable: dict[str, str] = {}
    failed: dict[str, str] = {}
    timings: dict[str, float] = {}
    cfg = study.config

    from tqdm.auto import tqdm

    show = sys.stderr.isatty() if progress is None else progress
    bar = tqdm(total=len(STAGES), desc="mvtk run", unit="stage", disable=not show,
               leave=False)

    def do(name: str, needs: tuple[str, ...], configured: bool, key_parts: list,
           compute: Callable[[], tuple[dict, Any]]) -> None:
        bar.set_postfix_str(name)
        t0 = time.perf_counter()
        try:
            if not configured:
                unavailable[name] = "not configured in the study file"
                return
            missing = [n for n in needs if n not in results]
            if missing:
                unavailable[name] = f"needs the stage(s) {missing}, which did not complete"
                return
            key = stage_key(name, version, code_hash(*_CODE[name]), key_parts,
                            [keys[n] for n in needs])
            try:
                res, ds = cache.get(name, key, compute)
            except ImportError as err:
                unavailable[name] = f"the API this stage needs is not available ({err})"
                return
            except ConfigError:
                raise
            except Exception as err:  # noqa: BLE001 - recorded, shown in the report
                tb = traceback.extract_tb(err.__traceback__)[-1]
                failed[name] = (f"{type(err).__name__}: {err} "
                                f"(at {Path(tb.filename).name}:{tb.lineno})")
                return
            keys[name] = key
            results[name] = res
            if ds is not None:
                arrays[name] = ds
        finally:
            timings[name] = time.perf_counter() - t0
            bar.update(1)

    from . import _stages as st

    meas = cfg.get("measurements", {})
    meas_hashes = {p.name: hashes[p.name] for p in study.measurement_files.values()}
    # keyed by file content, not by the path spelling in the study file
    meas_key = {k: {kk: vv for kk, vv in v.items() if kk != "file"} for k, v in meas.items()}
    do("ingest", (), bool(meas), [meas_hashes, meas_key], lambda: st.ingest(study))
    do("fe", (), True, [hashes[study.structure_file.name], cfg.get("fe", {})],
       lambda: st.fe_nominal(study))
    do("updating", ("fe",), "updating" in cfg, [cfg.get("updating", {})],
       lambda: st.updating(study))

    def _description() -> dict:
        """The updated structure when updating ran, else the nominal one."""
        from ..fe import load_structure

        return (results["updating"]["description"] if "updating" in results
                else load_structure(study.structure_file))

    # Monte Carlo on the updated structure; no later stage depends on it (its key is in
    # no other stage's key, so changing [uncertainty] reruns only this stage)
    unc_needs = ("fe",) + (("updating",) if "updating" in cfg else ())
    do("uncertainty", unc_needs, "uncertainty" in cfg, [cfg.get("uncertainty", {})],
       lambda: st.uncertainty(study, _description()))

    # damping pairs identified modes with the (updated) FE model's effective masses
    dmp_needs = ("ingest", "fe") + (("updating",) if "updating" in cfg else ())
    do("damping", dmp_needs, "damping" in cfg, [cfg.get("damping", {})],
       lambda: st.damping(study, arrays["ingest"], _description()))
    # the SE is built from the updated model when updating ran, else from the nominal one
    def _reduction():
        md = results.get("damping", {}).get("model_damping")
        return st.reduction(study, _description(), md)

    red_needs = ("fe",) + (("updating",) if "updating" in cfg else ()) + (
        ("damping",) if "damping" in cfg else ())
    do("reduction", red_needs, "reduction" in cfg,
       [cfg.get("reduction", {}), cfg.get("control", {}).get("actuator_nodes"),
        cfg.get("control", {}).get("sensor_node")], _reduction)

    def _control():
        if "reduction" not in arrays:
            raise ConfigError("control needs the SE plant; [control] and [damping] must be set")
        fn1 = results.get("updating", {}).get("fn_hz", [None])[0] or results["fe"]["fn_hz"][0]
        return st.control(study, arrays["reduction"], float(fn1))

    do("control", ("reduction",), "control" in cfg, [cfg.get("control", {})], _control)

    report_path = None
    t0 = time.perf_counter()
    if report:
        from ._report import build_report

        partial = StudyResult(study=study, out_dir=out, report_path=None, results=results,
                              arrays=arrays, unavailable=dict(unavailable),
                              failed=dict(failed), cache_hits=tuple(cache.hits),
                              timings_s=dict(timings))
        report_path = build_report(partial, hashes)
    timings["report"] = time.perf_counter() - t0
    bar.update(1)
    bar.close()
    return StudyResult(study=study, out_dir=out, report_path=report_path, results=results,
                       arrays=arrays, unavailable=unavailable, failed=failed,
                       cache_hits=tuple(cache.hits), timings_s=timings)
