"""Run a whole study: ingest -> FE -> damping -> updating -> SE -> controllers -> report."""

from __future__ import annotations

import contextlib
import importlib
import math
import os
import sys
import time
import traceback
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .._interrupt import check_interrupt
from .._process import die_with_parent
from ..errors import ConfigError, MvtkError, OutputError
from ._cache import OutputLock, ReadTracker, StageCache, TrackedStudy, code_hash, stage_key
from ._config import Study, load_study

__all__ = ["StudyResult", "run", "STAGES", "STAGE_NEEDS", "check_output_dir"]

#: Subpackages whose source is part of each stage's cache key.
_CODE = {
    "ingest": ("io", "study/_stages.py"),
    "modal": ("io", "modal", "plot", "study/_ema.py"),
    "correlation": ("fe", "correlation", "plot", "study/_ema.py"),
    "fe": ("fe", "reduction", "study/_stages.py"),
    "damping": ("signal", "damping", "fe", "reduction", "study/_stages.py"),
    "updating": ("fe", "updating", "correlation", "study/_stages.py", "study/_ema.py",
                 "study/_updating.py"),
    "uncertainty": ("fe", "updating", "scale", "study/_stages.py"),
    "reduction": ("fe", "reduction", "control", "study/_stages.py"),
    "control": ("control", "study/_stages.py"),
}

#: Stage names in execution order.
STAGES = ("ingest", "modal", "fe", "updating", "correlation", "uncertainty", "damping",
          "reduction", "control", "report")

#: Upstream stages whose results each stage consumes (when they are configured).
STAGE_NEEDS = {
    "ingest": (),
    "modal": (),
    "fe": (),
    "updating": ("modal",),
    "correlation": ("fe", "updating", "modal"),
    "uncertainty": ("fe", "updating"),
    "damping": ("ingest", "fe", "updating"),
    "reduction": ("fe", "updating", "damping"),
    "control": ("fe", "updating", "reduction"),
}
#: The section that configures each stage (None: always configured).
_SECTION = {"ingest": "measurements", "modal": "modal", "correlation": "modal",
            "fe": None, "updating": "updating",
            "uncertainty": "uncertainty", "damping": "damping", "reduction": "reduction",
            "control": "control"}
#: Stages that must complete for a stage to run even when their section is absent.
_HARD = {"correlation": ("fe", "modal"), "uncertainty": ("fe",), "damping": ("ingest", "fe"),
         "reduction": ("fe",),
         "control": ("fe", "reduction")}


def check_output_dir(out: str | Path) -> Path:
    """Create ``out`` if needed and prove it is a writable folder, before any work starts.

    Raises
    ------
    ConfigError
        ``out`` or its ``cache`` entry is a file, or the folder cannot be created or
        written; the message names the path.
    """
    out = Path(out)
    if out.exists() and not out.is_dir():
        raise ConfigError(f"--out {str(out)!r} is a file, expected a folder")
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise ConfigError(f"cannot create the output folder {str(out)!r}: "
                          f"{err.strerror or err}") from None
    cache = out / "cache"
    if cache.exists() and not cache.is_dir():
        raise ConfigError(f"{str(cache)!r} is a file; the stage cache needs this name for a "
                          "folder: remove or rename it, or use another --out")
    probe = out / f".mvtk-write-test-{os.getpid()}"
    try:
        probe.write_bytes(b"")
        probe.unlink()
    except OSError as err:
        raise ConfigError(f"the output folder {str(out)!r} is not writable: "
                          f"{err.strerror or err}") from None
    return out


def _refuse_inputs_in_folder(folder, inputs) -> None:
    """Refuse an output folder whose written files would replace an input.

    The files a run writes into ``folder`` are ``index.html``, ``report.pdf``,
    ``manifest.json`` and everything below ``tables/`` and ``cache/``.

    Raises
    ------
    OutputError
        An input file is, or lies where, one of those outputs goes.
    """
    from .._atomic import same_file

    out = Path(folder)
    written = [out / n for n in ("index.html", "report.pdf", "manifest.json")]
    subdirs = [(out / d).resolve() for d in ("tables", "cache")]
    for src in inputs:
        src = Path(src)
        real = src.resolve()
        if any(same_file(src, w) for w in written) or any(
                real.is_relative_to(d) for d in subdirs):
            raise OutputError(f"the output folder {str(folder)!r} would overwrite the input file "
                              f"{str(src)!r} (a run writes index.html, report.pdf, "
                              "manifest.json, tables/ and cache/ there): give another "
                              "output folder")


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
    cpu_s : dict of str to float
        CPU time (``time.process_time``) per stage (s): of the main process, or of the
        worker process for a stage computed in one.
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
    cpu_s: dict[str, float] = field(default_factory=dict)

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


def _configured(cfg: dict, stage: str) -> bool:
    sec = _SECTION[stage]
    return sec is None or bool(cfg.get(sec))


def stages_for(cfg: dict, wanted) -> list[str]:
    """``wanted`` stages plus every configured upstream stage they need, in run order."""
    todo: set[str] = set()

    def add(s: str) -> None:
        if s in todo:
            return
        todo.add(s)
        for n in STAGE_NEEDS[s]:
            if _configured(cfg, n) or n in _HARD.get(s, ()):
                add(n)

    for s in wanted:
        if s not in STAGE_NEEDS:
            raise ConfigError(f"unknown stage {s!r}; expected some of {list(STAGE_NEEDS)}")
        add(s)
    return [s for s in STAGES if s in todo]


def run(
    study_path: str | Path | Study,
    out_dir: str | Path,
    *,
    use_cache: bool = True,
    progress: bool | None = None,
    report: bool = True,
    stages=None,
    lock_timeout_s: float | None = None,
    on_wait: Callable[[str], None] | None = None,
    parallel: bool = True,
) -> StudyResult:
    """Run the study in ``study_path`` and write its report to ``out_dir``.

    Parameters
    ----------
    study_path : path or Study
        Study TOML (schema: :data:`mvtk.study.SCHEMA`), or a loaded study.
    out_dir : path
        Output folder: ``index.html``, ``tables/*.csv``, ``cache/`` (stage results keyed
        by what each stage read; a stage whose inputs did not change is loaded). Checked
        (created, writable, no file named ``cache``) before any stage runs, and locked
        for the run: a concurrent run into the same folder waits.
    use_cache : bool
        Set False to recompute every stage.
    progress : bool, optional
        Show a tqdm progress bar; default only when stderr is a terminal.
    report : bool
        Write the HTML report (only when every stage is run).
    stages : sequence of str, optional
        Run only these stages and the configured upstream stages they need (the views of
        ``mvtk update``, ``reduce``, ``control``); default all.
    lock_timeout_s : float, optional
        Wait at most this long for another run holding ``out_dir`` (default: no limit).
    on_wait : callable, optional
        Called with a message if the run has to wait for the lock.
    parallel : bool
        Compute the ``ingest`` stage (the measurement files; only ``damping`` needs
        it) and the Monte-Carlo ``uncertainty`` stage (only the report needs it) in
        forked worker processes while the main process runs the other stages, so a
        two-core machine runs both at once. Results are identical; ignored where
        ``fork`` is unavailable (Windows: every stage runs in process).

    Returns
    -------
    StudyResult

    Raises
    ------
    ConfigError
        Invalid study file or output folder (raised before any stage runs).
    OutputError
        A file the run would write into ``out_dir`` is one of the study's inputs.
    OutputBusyError
        ``lock_timeout_s`` elapsed while another run held the folder.
    """
    study = study_path if isinstance(study_path, Study) else load_study(study_path)
    from ._init import PLACEHOLDER_MARK, placeholder_structure

    wanted = stages_for(study.config, STAGE_NEEDS if stages is None else stages)
    needs_fe = stages is None or any(s not in ("ingest", "modal") for s in wanted)
    if (needs_fe and study.structure_file is not None
            and placeholder_structure(study.structure_file)):
        raise ConfigError(
            f"{study.structure_file}: this is the placeholder structure `mvtk init` wrote "
            f"(line {PLACEHOLDER_MARK!r}); edit it to your structure (geometry, materials, "
            "layers, mesh, supports) and delete that line, or give your own with "
            "`mvtk init --structure FILE`")
    _refuse_inputs_in_folder(out_dir, study.input_files)
    out = check_output_dir(out_dir)
    with OutputLock(out, timeout_s=lock_timeout_s, on_wait=on_wait) as lock:
        return _run_locked(study, out, use_cache=use_cache, progress=progress,
                           report=report, stages=stages, parallel=parallel,
                           lock_fd=lock.fileno())


#: Stages computed in a forked worker process while the main process runs other stages:
#: ``ingest`` (only ``damping`` needs it) and ``fe`` (the nominal model; ``updating``
#: does not need it) beside ``modal`` and ``updating``; ``uncertainty`` and
#: ``correlation`` (only the report needs them) beside ``damping`` to ``control``.
_BACKGROUND = ("ingest", "fe", "uncertainty", "correlation")
#: Modules a worker stage imports that the main process needs later too (the modal
#: stage reads with mvtk.io, the report plots with mvtk.scale): imported before the fork,
#: so the import is paid once, not in the worker and again in the main process.
_PRELOAD = {"ingest": ("mvtk.io", "mvtk.signal", "mvtk.damping"),
            "fe": ("mvtk.fe",),
            "uncertainty": ("mvtk.scale", "mvtk.updating"),
            "correlation": ("mvtk.correlation", "mvtk.plot", "matplotlib.pyplot")}


class _ChildError(Exception):
    """A stage that failed in the worker process, with the message the report shows."""

    def __init__(self, message: str) -> None:
        super().__init__(message)
        self.message = message


def _child_main(conn, compute, study, parent_pid, close_fds) -> None:
    """Worker process: run ``compute`` on a fresh tracker and send its outcome.

    The worker must not outlive a killed run: it dies with its parent, and it closes
    its copies of the output folder's lock and of the pipe's read end, so that neither
    the lock nor a blocked send keeps a rerun waiting.
    """
    import pickle
    import signal

    from ._cache import to_jsonable

    # Ctrl-C goes to the main process, which ends this one (SIGINT was blocked across
    # the fork, so a Ctrl-C in that window is discarded here, never a traceback)
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    with contextlib.suppress(AttributeError, OSError, ValueError):
        signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})
    die_with_parent()
    if os.getppid() != parent_pid:   # the parent died before prctl took effect
        os._exit(1)
    for fd in close_fds:
        with contextlib.suppress(OSError):
            os.close(fd)
    tracker = ReadTracker(study)
    t0, c0 = time.perf_counter(), time.process_time()
    try:
        res, ds = compute(TrackedStudy(study, tracker))
        msg = ("ok", to_jsonable(res), ds, dict(tracker.reads),
               time.perf_counter() - t0, time.process_time() - c0)
    except BaseException as err:  # noqa: BLE001 - reported by the main process
        if isinstance(err, MvtkError | ImportError):
            try:
                pickle.loads(pickle.dumps(err))
                msg = ("raise", err)
            except Exception:  # noqa: BLE001 - an exception that does not pickle
                msg = ("error", str(err))
        else:
            tb = traceback.extract_tb(err.__traceback__)[-1]
            msg = ("error", f"internal error {type(err).__name__}: {err} "
                            f"(at {Path(tb.filename).name}:{tb.lineno}); please report it")
    conn.send(msg)
    conn.close()


class _Background:
    """One stage computed in a forked process; :meth:`result` is its ``compute``."""

    def __init__(self, compute, study, lock_fd: int | None = None) -> None:
        import multiprocessing as mp

        ctx = mp.get_context("fork")
        self._recv, send = ctx.Pipe(duplex=False)
        close = [self._recv.fileno()] + ([] if lock_fd is None else [lock_fd])
        self._proc = ctx.Process(target=_child_main,
                                 args=(send, compute, study, os.getpid(), close),
                                 daemon=True)
        self._start_without_sigint()
        send.close()
        self.wall_s = self.cpu_s = float("nan")

    def _start_without_sigint(self) -> None:
        """Fork with SIGINT blocked: the child ignores it before it can arrive; in this
        process a Ctrl-C pressed meanwhile is delivered once the mask is restored."""
        import signal

        try:
            old = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
        except (AttributeError, OSError, ValueError):   # no POSIX masks here
            self._proc.start()
            return
        try:
            self._proc.start()
        finally:
            signal.pthread_sigmask(signal.SIG_SETMASK, old)

    def result(self, s: TrackedStudy):
        try:
            msg = self._recv.recv()
        except EOFError:
            raise _ChildError(f"the worker process ended without a result (exit code "
                              f"{self._proc.exitcode})") from None
        finally:
            self.close()
        if msg[0] == "raise":
            raise msg[1]
        if msg[0] == "error":
            raise _ChildError(msg[1])
        _, res, ds, reads, self.wall_s, self.cpu_s = msg
        s._tracker.reads.update(reads)
        return res, ds

    def close(self) -> None:
        """Wait for the process to end (it ends after sending its result)."""
        self._recv.close()
        self._proc.join(timeout=5.0)
        self.abort()

    def abort(self) -> None:
        """End the process now if it still runs (an interrupted or failed run)."""
        if self._proc.is_alive():
            self._proc.kill()
        self._proc.join()


def _can_fork() -> bool:
    import multiprocessing as mp

    return "fork" in mp.get_all_start_methods()


def _run_locked(study: Study, out: Path, *, use_cache, progress, report, stages,
                parallel=True, lock_fd=None):
    import mvtk

    cache = StageCache(out / "cache", enabled=use_cache)
    cache.clean_temporaries()
    hashes = _file_hashes(study)
    version = mvtk.__version__
    results: dict[str, dict] = {}
    arrays: dict[str, Any] = {}
    unavailable: dict[str, str] = {}
    failed: dict[str, str] = {}
    timings: dict[str, float] = {}
    cpu: dict[str, float] = {}
    cfg = study.config
    selected = stages_for(cfg, STAGE_NEEDS if stages is None else stages)
    report = report and stages is None

    from tqdm.auto import tqdm

    show = sys.stderr.isatty() if progress is None else progress
    bar = tqdm(total=len(selected) + int(report), desc="mvtk run", unit="stage",
               disable=not show, leave=False)

    def key_of(name: str) -> tuple[str | None, str]:
        """(cache key, "") of a stage that can run, else (None, why not)."""
        if not _configured(cfg, name):
            return None, "not configured in the study file"
        needs = [n for n in STAGE_NEEDS[name]
                 if _configured(cfg, n) or n in _HARD.get(name, ())]
        missing = [n for n in needs if n not in results]
        if missing:
            return None, f"needs the stage(s) {missing}, which did not complete"
        return stage_key(name, version, code_hash(*_CODE[name]),
                         {n: cache.keys[n] for n in needs}), ""

    background: dict[str, _Background] = {}

    def start(name: str, compute: Callable[[TrackedStudy], tuple[dict, Any]]) -> None:
        """Start a stage in a worker process now, if it is to be computed (not cached)."""
        if not (parallel and name in _BACKGROUND and name in selected and _can_fork()):
            return
        key, _ = key_of(name)
        if key is None or cache.peek(name, key, ReadTracker(study)):
            return
        for module in _PRELOAD.get(name, ()):
            importlib.import_module(module)
        background[name] = _Background(compute, study, lock_fd)

    def do(name: str, compute: Callable[[TrackedStudy], tuple[dict, Any]]) -> None:
        if name not in selected:
            return
        check_interrupt()
        bar.set_postfix_str(name)
        t0, c0 = time.perf_counter(), time.process_time()
        try:
            key, why = key_of(name)
            if key is None:
                unavailable[name] = why
                return
            if name in background:
                compute = background[name].result
            tracker = ReadTracker(study)
            try:
                res, ds = cache.get(name, key, lambda: compute(TrackedStudy(study, tracker)),
                                    tracker)
            except MvtkError as err:
                check_interrupt()  # an interrupt that library code turned into an error
                failed[name] = str(err)
                return
            except ImportError as err:
                unavailable[name] = f"the API this stage needs is not available ({err})"
                return
            except (KeyboardInterrupt, SystemExit):
                raise
            except _ChildError as err:
                failed[name] = err.message
                return
            except Exception as err:  # noqa: BLE001 - recorded, shown in the report
                check_interrupt()
                tb = traceback.extract_tb(err.__traceback__)[-1]
                failed[name] = (f"internal error {type(err).__name__}: {err} "
                                f"(at {Path(tb.filename).name}:{tb.lineno}); please report it")
                return
            check_interrupt()  # one that was swallowed (weakref callback, bare except)
            results[name] = res
            if ds is not None:
                arrays[name] = ds
        finally:
            timings[name] = time.perf_counter() - t0
            cpu[name] = time.process_time() - c0
            if name in background and math.isfinite(background[name].wall_s):
                timings[name] = background[name].wall_s   # its own time, in parallel
                cpu[name] = background[name].cpu_s
            if name in selected:
                bar.update(1)

    from .._blas import blas_limits as _blas_limits
    from . import _ema
    from . import _stages as st

    # one BLAS thread per process: the study's matrices are small (threads only add
    # synchronisation), and the worker processes already use the second core; set
    # before any worker is forked, so they inherit it
    blas = _blas_limits()
    blas.__enter__()
    try:
        # the measurement files are read in a worker process while the main one
        # identifies the multi-point test, solves the FE model and updates it; only the
        # damping stage needs them
        start("ingest", st.ingest)
        if "ingest" not in background:
            do("ingest", st.ingest)
        start("fe", st.fe_nominal)
        if "fe" not in background:
            do("fe", st.fe_nominal)
        do("modal", _ema.modal)
        do("updating", lambda s: st.updating(s, arrays.get("modal"), results.get("modal")))
        if "fe" in background:
            do("fe", st.fe_nominal)

        def _description(s: TrackedStudy) -> dict:
            """The updated structure when updating ran, else the nominal one."""
            if "updating" in results:
                return results["updating"]["description"]
            return s.description()

        def _uncertainty(s: TrackedStudy):
            return st.uncertainty(s, _description(s))

        # the identified shapes against the updated model: MAC, COMAC, non-target predictions
        def _correlation(s: TrackedStudy):
            return _ema.correlation(s, arrays["modal"], _description(s),
                                    len(results["fe"]["fn_hz"]),
                                    results.get("updating", {}).get("targets_hz"))

        start("uncertainty", _uncertainty)
        start("correlation", _correlation)
        if "correlation" not in background:
            do("correlation", _correlation)

        # Monte Carlo on the updated structure; no later stage depends on it (when it
        # runs in the worker process, its result is collected after the control stage)
        if "uncertainty" not in background:
            do("uncertainty", _uncertainty)
        if "ingest" in background:
            do("ingest", st.ingest)
        # damping pairs identified modes with the (updated) FE model's effective masses
        def _known_fn_hz():
            """Lowest frequencies (Hz) of the updated model, else of the nominal one."""
            f = results.get("updating", {}).get("fn_hz")
            return results.get("fe", {}).get("fn_hz") if f is None else f

        do("damping", lambda s: st.damping(s, arrays["ingest"], _description(s),
                                           _known_fn_hz()))
        # the SE is built from the updated model when updating ran, else from the nominal one
        do("reduction", lambda s: st.reduction(
            s, _description(s), results.get("damping", {}).get("model_damping")))

        def _control(s: TrackedStudy):
            if "reduction" not in arrays:
                raise ConfigError("control needs the SE plant: the [control] section needs "
                                  "[damping] (the Rayleigh pair of the plant) and [reduction]")
            fn1 = results.get("updating", {}).get("fn_hz", [None])[0] or results["fe"]["fn_hz"][0]
            return st.control(s, arrays["reduction"], float(fn1))

        do("control", _control)
        if "correlation" in background:
            do("correlation", _correlation)
        if "uncertainty" in background:
            do("uncertainty", _uncertainty)

    finally:
        for bg in background.values():
            bg.abort()
        blas.__exit__(None, None, None)

    timings = {s: timings[s] for s in STAGES if s in timings}
    cpu = {s: cpu[s] for s in STAGES if s in cpu}
    # in pipeline order, whichever process computed or loaded a stage first
    hits = tuple(s for s in STAGES if s in cache.hits)
    report_path = None
    t0, c0 = time.perf_counter(), time.process_time()
    if report:
        from ._report import build_report

        partial = StudyResult(study=study, out_dir=out, report_path=None, results=results,
                              arrays=arrays, unavailable=dict(unavailable),
                              failed=dict(failed), cache_hits=hits,
                              timings_s=dict(timings))
        report_path = build_report(partial, hashes)
        from ._manifest import write_manifest

        write_manifest(out, report_path)   # last: it vouches for what was written
    timings["report"] = time.perf_counter() - t0
    cpu["report"] = time.process_time() - c0
    if report:
        bar.update(1)
    bar.close()
    return StudyResult(study=study, out_dir=out, report_path=report_path, results=results,
                       arrays=arrays, unavailable=unavailable, failed=failed,
                       cache_hits=hits, timings_s=timings, cpu_s=cpu)
