"""Nothing lost: every writer replaces its file in one step, and a failed write leaves
the previous file byte-identical (the SQLite/git rule: temporary file in the same folder,
fsync, rename).

The failures are real ones: the file-size limit of the process (``RLIMIT_FSIZE``, what
``ulimit -f`` sets) in a subprocess, so the writer's own I/O (h5py, pyuff, pandas, a
child process) hits ``EFBIG`` exactly as on a full disk.
"""

from __future__ import annotations

import errno
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from mvtk._atomic import atomic_path, refuse_input, same_file, write_bytes, write_text
from mvtk.errors import OutputError

ROOT = Path(__file__).resolve().parents[1]

pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="POSIX file-size limit")


def test_write_replaces_in_one_step_and_keeps_the_mode(tmp_path):
    target = tmp_path / "a.txt"
    target.write_text("old")
    os.chmod(target, 0o640)
    write_text(target, "new content")
    assert target.read_text() == "new content"
    assert (target.stat().st_mode & 0o777) == 0o640
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.txt"]  # no temporary left


def test_exception_in_writer_keeps_previous_file(tmp_path):
    target = tmp_path / "a.bin"
    target.write_bytes(b"previous")
    with pytest.raises(RuntimeError), atomic_path(target) as tmp:
        tmp.write_bytes(b"half")
        raise RuntimeError("writer failed")
    assert target.read_bytes() == b"previous"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.bin"]


@pytest.mark.parametrize("code, cause", [(errno.ENOSPC, "disk full"),
                                         (errno.EACCES, "permission denied"),
                                         (errno.EFBIG, "file-size limit")])
def test_os_error_names_file_and_cause(tmp_path, monkeypatch, code, cause):
    target = tmp_path / "t.toml"
    target.write_text("name = 'kept'\n")

    def failing_fsync(fd):  # the device reports the error when the data is flushed
        raise OSError(code, os.strerror(code))

    monkeypatch.setattr(os, "fsync", failing_fsync)
    with pytest.raises(OutputError) as info:
        write_bytes(target, b"x" * 100)
    monkeypatch.undo()
    msg = str(info.value)
    assert str(target) in msg and cause in msg and "unchanged" in msg
    assert target.read_text() == "name = 'kept'\n"


def test_same_file_follows_symlinks_and_hard_links(tmp_path):
    a = tmp_path / "a.csv"
    a.write_text("x")
    (tmp_path / "sym.csv").symlink_to(a)
    os.link(a, tmp_path / "hard.csv")
    assert same_file(tmp_path / "sym.csv", a)
    assert same_file(tmp_path / "hard.csv", a)
    assert same_file(tmp_path / "sub" / ".." / "a.csv", a) or not (tmp_path / "sub").exists()
    assert not same_file(tmp_path / "new.nc", a)
    with pytest.raises(OutputError, match="hard.csv.*is the input file"):
        refuse_input(tmp_path / "hard.csv", [a], "--out")


# Every writer under a 1 kB file-size limit: each new file is larger, each must fail
# with OutputError naming the file, and each previous file must be byte-identical.
_SCRIPT = textwrap.dedent(r"""
    import hashlib, json, os, resource, sys, warnings
    from pathlib import Path
    import numpy as np, pandas as pd, xarray as xr
    warnings.simplefilter("ignore")
    sys.path.insert(0, {root!r})
    from mvtk.errors import OutputError
    out = Path(sys.argv[1])
    ROOT = Path({root!r})

    import mvtk.io as mio
    from mvtk.modal import identify
    from mvtk.modal._export import write_frf_uff, write_modes_uff
    from mvtk.modal._frf import as_frf_matrix
    from mvtk.report import Report
    from mvtk.report._pdf import to_pdf
    from mvtk.study._cache import StageCache, _atomic_write_bytes
    from mvtk.study._init import init_study
    from mvtk.correlation import read_test_geometry
    from mvtk.fe import build_model, modal_analysis, write_uff

    scan = ROOT / "data" / "smart_beam" / "SYNTHETIC_smart_beam_scan.uff"
    h = as_frf_matrix(mio.read(scan))
    modes = identify(h, 5, 150)
    ds = mio.read(ROOT / "data" / "smart_beam" / "SYNTHETIC_smart_beam_impact.csv")
    geo = read_test_geometry(ROOT / "data" / "smart_beam" /
                             "SYNTHETIC_smart_beam_scan_geometry.csv")
    model = build_model(ROOT / "data" / "structures" / "plate.toml")
    fe_modes = modal_analysis(model, 3)
    big = pd.DataFrame({{"a": np.arange(20000) * 0.1, "b": np.arange(20000)}})
    rep = Report("big"); sec = rep.section("s"); sec.table(big, "big", "a big table")
    chromium = out / "fake-chromium"
    chromium.write_text("#!/bin/sh\nfor a in \"$@\"; do case $a in --print-to-pdf=*) "
                        "f=${{a#--print-to-pdf=}};; esac; done\n"
                        "printf '%%PDF-' > \"$f\" && head -c 200000 /dev/zero >> \"$f\"\n")
    chromium.chmod(0o755)
    (out / "init").mkdir()
    (out / "cache").mkdir()
    writers = {{
        "netcdf.nc": lambda p: mio.write(ds, p),
        "modes.uff": lambda p: write_modes_uff(modes, p),
        "frf.uff": lambda p: write_frf_uff(modes.synthesised, p),
        "fe.uff": lambda p: write_uff(model, p, fe_modes),
        "geometry.toml": lambda p: geo.to_toml(p) and None,
        "cache.json": lambda p: _atomic_write_bytes(p, b"{{}}" + b" " * 100000),
        "cache/fe.nc": lambda p: StageCache(p.parent)._store("fe", "b", "k", {{}}, {{}}, ds),
        "index.html": lambda p: rep.write(p.parent),
        "report.pdf": lambda p: to_pdf(out / "index.html", p, chromium=str(chromium)),
        "init/study.toml": lambda p: init_study(
            p.parent, overwrite=True, structure=ROOT / "data" / "structures" / "plate.toml",
            name="n" * 70000),
    }}
    sizes = {{}}
    for name in writers:
        p = out / name
        p.write_bytes(b"previous " + name.encode() * 10)
        if name == "index.html":
            (out / "tables").mkdir()
            (out / "tables" / "big.csv").write_bytes(b"previous table")
        if name == "cache/fe.nc":
            (out / "cache" / "fe.json").write_bytes(b"previous cache record")
        if name == "init/study.toml":
            (out / "init" / "structure.toml").write_bytes(b"previous structure")
    before = {{str(p): p.read_bytes() for p in out.rglob("*") if p.is_file()}}
    resource.setrlimit(resource.RLIMIT_FSIZE, (1024, resource.RLIM_INFINITY))
    result = {{}}
    for name, fn in writers.items():
        try:
            fn(out / name)
            result[name] = "written"
        except OutputError as err:
            result[name] = "OutputError: " + str(err)
        except Exception as err:
            result[name] = f"{{type(err).__name__}}: {{err}}"
    resource.setrlimit(resource.RLIMIT_FSIZE, (resource.RLIM_INFINITY,) * 2)
    after = {{str(p): p.read_bytes() for p in out.rglob("*") if p.is_file()}}
    changed = sorted(k for k in before if before[k] != after.get(k))
    extra = sorted(k for k in after if k not in before)
    print(json.dumps({{"result": result, "changed": changed, "extra": extra}}))
""")


def test_every_writer_keeps_the_previous_file_on_a_write_failure(tmp_path):
    import json

    script = tmp_path / "writers.py"
    script.write_text(_SCRIPT.format(root=str(ROOT)))
    work = tmp_path / "out"
    work.mkdir()
    proc = subprocess.run([sys.executable, str(script), str(work)], capture_output=True,
                          text=True, timeout=120, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr[-3000:]
    doc = json.loads(proc.stdout.strip().splitlines()[-1])
    for name, what in doc["result"].items():
        if name == "report.pdf":
            # the fake Chromium dies on the limit: a PdfExportError, previous PDF kept
            assert what.startswith("PdfExportError"), (name, what)
            continue
        assert what.startswith("OutputError"), (name, what)
        assert "could not be written" in what and "unchanged" in what, what
        assert "file-size limit" in what, what
    assert doc["changed"] == [], doc["changed"]
    # no temporary file left behind (the PDF writer's is removed too)
    assert doc["extra"] == [], doc["extra"]


def test_mvtk_read_onto_an_existing_netcdf_under_a_file_size_limit(tmp_path):
    """Formerly a segmentation fault inside h5py with the old file gone."""
    import resource

    src = ROOT / "data" / "smart_beam" / "SYNTHETIC_smart_beam_impact.csv"
    out = tmp_path / "old.nc"
    out.write_bytes(b"the previous netCDF")

    def limit():
        resource.setrlimit(resource.RLIMIT_FSIZE, (65536, resource.RLIM_INFINITY))

    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    proc = subprocess.run([sys.executable, "-m", "mvtk", "read", str(src), "-o", str(out)],
                          capture_output=True, text=True, timeout=120, env=env,
                          preexec_fn=limit)
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr == (f"mvtk read: error: {out}: could not be written: file-size limit "
                           "exceeded (ulimit -f) or file too large; the previous file (if "
                           "any) is unchanged\n")
    assert out.read_bytes() == b"the previous netCDF"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["old.nc"]
