"""Figures of a report rendered in forked processes while the page is being built.

Rendering (layout, ticks, text, rasterising) is most of a report's time and each figure
is independent, so :class:`FigureRenderer` forks one short-lived process per figure as
soon as the figure is added, up to ``workers`` at a time. The child inherits the figure
as it is at that moment (copy-on-write), renders it and sends the bytes back through a
pipe; the main process meanwhile builds the next figures and tables. The bytes are the
same as an in-process render (:func:`render_figure` is called either way).

Where ``fork`` is unavailable (Windows, macOS spawn default is not used: only a real
``fork`` start method qualifies) or ``workers`` is 0, figures are rendered in process.
A child dies with its parent (``PR_SET_PDEATHSIG`` on Linux, the helper of
:mod:`mvtk.study._run`), ignores Ctrl-C (the main process ends it), and any child that
fails or vanishes is replaced by an in-process render, so a failure is reported with
its real traceback.
"""

from __future__ import annotations

import contextlib
import io
import os
import weakref
from typing import Any

from ..errors import ParameterError

__all__ = ["FigureRenderer", "render_figure", "default_workers", "SVG_KEEP_BYTES"]

#: ``image_format="auto"`` keeps an SVG up to this size (bytes) without rendering a PNG
#: to compare: at 100 dpi the report's line plots are 30-70 kB as PNG.
SVG_KEEP_BYTES = 100_000
#: PNG resolution of report figures (dots per inch; figures are 7 in wide -> 700 px).
PNG_DPI = 100
#: zlib level of report PNGs, as for the study's figures: level 1 encodes in about 70 %
#: of the time of PIL's default level for files 5-8 % larger, the same pixels.
PNG_COMPRESS_LEVEL = 1
#: SVG element ids are hashed with this salt instead of a random one, so a figure's SVG
#: is the same bytes on every render (reproducible pages, comparable parallel renders).
SVG_HASHSALT = "mvtk-report"
_PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def default_workers() -> int:
    """Render processes to use: ``MVTK_REPORT_WORKERS`` if set, else the usable CPUs.

    ``0`` renders every figure in process (no fork).
    """
    env = os.environ.get("MVTK_REPORT_WORKERS", "").strip()
    if env:
        try:
            n = int(env)
        except ValueError:
            raise ParameterError(f"MVTK_REPORT_WORKERS must be an integer >= 0, got "
                                 f"{env!r}") from None
        if n < 0:
            raise ParameterError(f"MVTK_REPORT_WORKERS must be an integer >= 0, got {n}")
        return n
    try:
        return len(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        return os.cpu_count() or 1


def _can_fork() -> bool:
    import multiprocessing as mp

    return "fork" in mp.get_all_start_methods()


def _is_raster(figure: Any) -> bool:
    """True for figures that are fields rather than lines: images or filled contours.

    Their SVG holds thousands of polygons (or an embedded raster) and is always larger
    than the PNG, so ``"auto"`` renders them as PNG directly.
    """
    from matplotlib.contour import ContourSet

    if figure.images:
        return True
    for ax in figure.axes:
        if ax.images:
            return True
        if any(isinstance(c, ContourSet) and c.filled for c in ax.collections):
            return True
    return False


def check_figure(figure: Any, image_format: str) -> None:
    """Raise :class:`ParameterError` unless ``figure`` can be rendered as asked."""
    if isinstance(figure, bytes | bytearray):
        return
    if not hasattr(figure, "savefig") and not callable(figure):
        raise ParameterError(
            "a report figure must be PNG/SVG bytes, a matplotlib Figure or a function "
            f"returning one, got {type(figure).__name__}"
        )
    if image_format not in ("auto", "png", "svg"):
        raise ParameterError(f"image_format must be 'auto', 'png' or 'svg', got "
                             f"{image_format!r}")


def render_figure(figure: Any, image_format: str = "auto") -> tuple[str, bytes]:
    """(mime type, bytes) of a figure.

    Parameters
    ----------
    figure : matplotlib Figure, bytes or callable
        PNG or SVG bytes are checked and returned as they are; a callable (e.g. a
        ``functools.partial`` of a plot function) is called to build the figure.
    image_format : {"auto", "png", "svg"}
        ``auto``: PNG for a figure holding raster images or filled contours (an SVG
        would be larger); otherwise an SVG of at most :data:`SVG_KEEP_BYTES` (line
        plots: sharp at any zoom, selectable text); only a larger SVG is rendered as
        PNG too, and the smaller kept.
    """
    if isinstance(figure, bytes | bytearray):
        data = bytes(figure)
        if data.startswith(_PNG_MAGIC):
            return "image/png", data
        head = data[:400].lstrip()
        if head.startswith(b"<?xml") or head.startswith(b"<svg"):
            if b"<svg" not in data[:2000]:
                raise ParameterError("figure bytes look like XML but contain no <svg> element")
            return "image/svg+xml", data
        raise ParameterError("figure bytes are not a PNG image (missing PNG signature) "
                             "nor an SVG document")
    check_figure(figure, image_format)
    if not hasattr(figure, "savefig"):
        figure = figure()
        if not hasattr(figure, "savefig"):
            raise ParameterError(f"a report figure function must return a matplotlib "
                                 f"Figure, got {type(figure).__name__}")
    import matplotlib

    out = {}
    engine = figure.get_layout_engine()
    if image_format != "auto":
        formats: tuple[str, ...] = (image_format,)
    elif _is_raster(figure):
        formats = ("png",)
    else:
        formats = ("svg", "png")
    try:
        for fmt in formats:
            buf = io.BytesIO()
            if fmt == "png":
                figure.savefig(buf, format="png", dpi=PNG_DPI,
                               pil_kwargs={"compress_level": PNG_COMPRESS_LEVEL})
            else:
                # text as <text> (not glyph paths): smaller, selectable, searchable
                with matplotlib.rc_context({"svg.fonttype": "none",
                                            "svg.hashsalt": SVG_HASHSALT}):
                    figure.savefig(buf, format="svg", metadata={"Date": None})
            out[fmt] = buf.getvalue()
            if fmt == "svg" and image_format == "auto" and len(out[fmt]) <= SVG_KEEP_BYTES:
                break
            if engine is not None:
                # the second format reuses the layout of the first (the layout engine
                # is half of the render time); restored below
                figure.set_layout_engine("none")
    finally:
        if engine is not None:
            figure.set_layout_engine(engine)
    fmt = min(out, key=lambda k: len(out[k]))
    return ("image/png" if fmt == "png" else "image/svg+xml"), out[fmt]


def _cost(job: _Job) -> int:
    """Rough relative render cost of a job (axes drawn), to start the longest first;
    a figure still to be built counts as one axes."""
    return len(getattr(job.figure, "axes", (None,)))


def _worker(conn, jobs, order, counter, parent_pid) -> None:
    """Render process: take the next job from ``counter`` until none is left, then send
    the list of ``(i, "ok", mime, bytes)`` / ``(i, "error", text)`` in one message.

    The results are sent at the end, not one by one: a send blocks once the pipe's
    buffer (64 kB, less than one figure) is full, and the main process reads only when
    it has no figure left to render itself.
    """
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)   # Ctrl-C: the parent ends this process
    from .._process import die_with_parent

    die_with_parent()
    if os.getppid() != parent_pid:   # the parent died before prctl took effect
        os._exit(1)
    out = []
    try:
        while (k := _next(counter)) < len(order):
            i = order[k]
            try:
                out.append((i, "ok", *render_figure(jobs[i].figure, jobs[i].image_format)))
            except Exception as err:  # noqa: BLE001 - the parent renders it again
                out.append((i, "error", f"{type(err).__name__}: {err}"))
        conn.send(out)
    finally:
        with contextlib.suppress(OSError):
            conn.close()


def _next(counter) -> int:
    """Claim the next job number (shared between the processes)."""
    with counter.get_lock():
        k = counter.value
        counter.value = k + 1
    return k


class _Job:
    """One figure: its result (``mime``, ``data``) once rendered."""

    __slots__ = ("figure", "image_format", "mime", "data")

    def __init__(self, figure: Any, image_format: str) -> None:
        self.figure, self.image_format = figure, image_format
        self.mime: str | None = None
        self.data: bytes | None = None

    @property
    def done(self) -> bool:
        return self.data is not None

    def run(self) -> None:
        self.mime, self.data = render_figure(self.figure, self.image_format)
        self.figure = None


def _kill(procs: list) -> None:
    """End every render process still running (interrupted or abandoned report)."""
    for proc, conn in procs:
        with contextlib.suppress(Exception):
            if proc.is_alive():
                proc.kill()
            proc.join()
        with contextlib.suppress(Exception):
            conn.close()
    procs.clear()


class FigureRenderer:
    """Render figures in up to ``workers`` processes (this one and forked ones).

    Figures are queued by :meth:`submit` and rendered by :meth:`wait`: this process
    forks ``workers - 1`` children (once, so the fork and the matplotlib caches are paid
    once per child, not per figure) and every process takes the next figure, largest
    first, until none is left. Results are the same bytes as an in-process render.

    Parameters
    ----------
    workers : int, optional
        Processes rendering at the same time, this one included (default
        :func:`default_workers`); ``0`` or ``1`` renders in process, at :meth:`submit`.

    Examples
    --------
    >>> from mvtk.plot import plot_frf
    >>> r = FigureRenderer(workers=0)               # render in this process
    >>> job = r.submit(plot_frf([1.0, 2.0, 3.0], [1.0, 3.0, 1.0]), "png")
    >>> r.wait()                                    # every job rendered
    >>> job.mime, job.data[:4]
    ('image/png', b'\x89PNG')
    """

    def __init__(self, workers: int | None = None) -> None:
        n = default_workers() if workers is None else int(workers)
        if n < 0:
            raise ParameterError(f"workers must be >= 0, got {workers}")
        self.workers = n if _can_fork() else 0
        self._pending: list[_Job] = []
        self._procs: list = []
        # children still running when the renderer is dropped (an exception while the
        # figures were rendered) are ended, not left behind
        self._finalizer = weakref.finalize(self, _kill, self._procs)

    def submit(self, figure: Any, image_format: str = "auto") -> _Job:
        """Queue ``figure`` (rendered by :meth:`wait`; do not change it in between).

        Bytes, and every figure when ``workers`` is 0 or 1, are rendered now.
        """
        check_figure(figure, image_format)
        job = _Job(figure, image_format)
        if self.workers <= 1 or isinstance(figure, bytes | bytearray):
            job.run()
        else:
            self._pending.append(job)
        return job

    def wait(self) -> None:
        """Render every queued figure."""
        jobs, self._pending = self._pending, []
        if not jobs:
            return
        n_children = min(self.workers, len(jobs)) - 1
        if n_children < 1:
            for job in jobs:
                job.run()
            return
        import multiprocessing as mp

        order = sorted(range(len(jobs)), key=lambda i: -_cost(jobs[i]))
        ctx = mp.get_context("fork")
        counter = ctx.Value("i", 0)
        try:
            for _ in range(n_children):
                recv, send = ctx.Pipe(duplex=False)
                proc = ctx.Process(target=_worker,
                                   args=(send, jobs, order, counter, os.getpid()),
                                   daemon=True)
                try:
                    proc.start()
                except OSError:   # cannot fork (memory, process limit): fewer helpers
                    recv.close()
                    send.close()
                    break
                send.close()
                self._procs.append((proc, recv))
            # this process takes its share too
            while (k := _next(counter)) < len(order):
                jobs[order[k]].run()
            for proc, conn in list(self._procs):
                try:
                    results = conn.recv()
                except (EOFError, OSError):
                    results = []    # the child ended early: its jobs are rendered below
                for i, status, *rest in results:
                    if status == "ok":
                        jobs[i].mime, jobs[i].data = rest
                        jobs[i].figure = None
                conn.close()
                proc.join(timeout=5.0)
                if proc.is_alive():
                    proc.kill()
                    proc.join()
                self._procs.remove((proc, conn))
        finally:
            _kill(self._procs)
        # a child that failed on a figure (or died) leaves it undone: render it here,
        # so a real error is raised with its traceback
        for job in jobs:
            if not job.done:
                job.run()
