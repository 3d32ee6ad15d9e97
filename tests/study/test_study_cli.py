"""CLI hygiene: one-line errors naming the path (exit 2), Ctrl-C (130), output paths
checked before the work, ``python -m mvtk``, JSON output against the JSON Schemas."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from study_text import with_absolute_paths

from mvtk.cli import main

ROOT = Path(__file__).resolve().parents[2]
STUDY = ROOT / "data" / "smart_beam" / "study.toml"
DECAY = ROOT / "data" / "smart_beam" / "SYNTHETIC_smart_beam_decay.csv"
STRUCTURE = ROOT / "data" / "structures" / "smart_beam.toml"


def _env():
    return {**os.environ, "PYTHONPATH": str(ROOT) + os.pathsep + os.environ.get(
        "PYTHONPATH", "")}


def _one_error_line(capsys, prefix: str) -> str:
    err = capsys.readouterr().err
    assert err.startswith(f"mvtk {prefix}: error: "), err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    return err


def test_python_dash_m_mvtk():
    """Issue 16: `python -m mvtk` did not work."""
    out = subprocess.run([sys.executable, "-m", "mvtk", "--version"], capture_output=True,
                         text=True, env=_env(), timeout=60)
    assert out.returncode == 0 and out.stdout.startswith("mvtk ")


@pytest.mark.parametrize(("argv", "prefix", "needle"), [
    (["damping", "/nonexistent/file.csv", "--fn", "10"], "damping", "/nonexistent/file.csv"),
    (["modes", "{tmp}"], "modes", "is a directory"),
    (["reduce", "{tmp}"], "reduce", "is a directory"),
    (["control", "{tmp}/absent.toml"], "control", "absent.toml' not found"),
    (["update", "{tmp}/absent.toml"], "update", "absent.toml' not found"),
    (["run", "{tmp}/absent.toml", "--out", "{tmp}/o"], "run", "absent.toml' not found"),
])
def test_missing_inputs_are_one_line(tmp_path, capsys, argv, prefix, needle):
    """Issue 16: raw tracebacks for a nonexistent file or a directory as input."""
    argv = [a.replace("{tmp}", str(tmp_path)) for a in argv]
    assert main(argv) == 2
    assert needle in _one_error_line(capsys, prefix)


def test_symlink_loop_is_one_line(tmp_path, capsys):
    (tmp_path / "a").symlink_to(tmp_path / "b")
    (tmp_path / "b").symlink_to(tmp_path / "a")
    assert main(["damping", str(tmp_path / "a"), "--fn", "10"]) == 2
    assert str(tmp_path / "a") in _one_error_line(capsys, "damping")


def test_latin1_structure_for_modes(tmp_path, capsys):
    """Issue 16: a structure TOML with a Latin-1 comment gave a raw traceback."""
    p = tmp_path / "beam.toml"
    p.write_bytes(b"# r\xe9glage\n" + STRUCTURE.read_bytes())
    assert main(["modes", str(p)]) == 2
    err = _one_error_line(capsys, "modes")
    assert str(p) in err and "byte 0xe9 at offset 3 (line 1, column 4)" in err


def test_utf16_study_is_read(tmp_path, capsys):
    """Issue 16: a UTF-16 study file gave a raw traceback; it is now read (here it then
    stops on a deliberate unknown key, showing the text was decoded)."""
    text = STUDY.read_text(encoding="utf-8").replace("n_modes = 6", "n_mode = 6")
    text = with_absolute_paths(text)
    p = tmp_path / "study.toml"
    p.write_bytes("\ufeff".encode("utf-16-le") + text.encode("utf-16-le"))
    assert main(["reduce", str(p)]) == 2
    assert "unknown key 'n_mode' in [fe] (did you mean 'n_modes'?)" in _one_error_line(
        capsys, "reduce")


@pytest.mark.parametrize(("argv", "prefix", "needle"), [
    (["read", str(DECAY), "-o", "/nonexistent/dir/x.nc"], "read",
     "--output '/nonexistent/dir/x.nc': the folder '/nonexistent/dir' does not exist"),
    (["read", str(DECAY), "-o", "{tmp}"], "read", "is a folder, expected a file name"),
    (["update", str(STUDY), "--out", "/nonexistent/u.toml"], "update",
     "--out '/nonexistent/u.toml': the folder '/nonexistent' does not exist"),
    (["run", str(STUDY), "--out", "{tmp}/file.txt"], "run",
     "is a file, expected a folder"),
    (["run", str(STUDY), "--out", "/proc/mvtk-out"], "run",
     "cannot create the output folder '/proc/mvtk-out'"),
    (["run", str(STUDY), "--out", "{tmp}/withcache"], "run",
     "cache' is a file; the stage cache needs this name for a folder"),
    (["control", str(STUDY), "--cache", "{tmp}/file.txt"], "control",
     "is a file, expected a folder"),
])
def test_output_paths_checked_before_the_work(tmp_path, capsys, monkeypatch, argv, prefix,
                                              needle):
    """Issue 16: -o/--out into a bad path failed only after the work was done."""
    import mvtk.io
    import mvtk.study._run as run_mod

    def no_work(*a, **k):
        raise AssertionError("the work started before the output path was checked")

    monkeypatch.setattr(mvtk.io, "read", no_work)
    monkeypatch.setattr(run_mod, "_run_locked", no_work)
    (tmp_path / "file.txt").write_text("x")
    (tmp_path / "withcache").mkdir()
    (tmp_path / "withcache" / "cache").write_text("x")
    argv = [a.replace("{tmp}", str(tmp_path)) for a in argv]
    assert main(argv) == 2
    assert needle in _one_error_line(capsys, prefix)


@pytest.mark.skipif(os.geteuid() == 0, reason="root can write into read-only folders")
def test_read_only_output_folder(tmp_path, capsys):  # pragma: no cover - not root in CI
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o500)
    try:
        assert main(["run", str(STUDY), "--out", str(ro)]) == 2
        assert "is not writable" in _one_error_line(capsys, "run")
    finally:
        ro.chmod(0o700)


def test_keyboard_interrupt_is_exit_130(capsys, monkeypatch):
    import mvtk.cli.modes as fe_cli

    def interrupted(args):
        raise KeyboardInterrupt

    monkeypatch.setattr(fe_cli, "run", interrupted)
    assert main(["modes", str(STRUCTURE)]) == 130
    assert capsys.readouterr().err == "mvtk modes: interrupted\n"


@pytest.mark.slow
def test_sigint_during_a_run(tmp_path):
    """Issue 16: Ctrl-C gave a traceback."""
    proc = subprocess.Popen([sys.executable, "-m", "mvtk", "run", str(STUDY), "--out",
                             str(tmp_path / "o"), "--quiet"], env=_env(),
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    # interrupted once the stages are running (the cache folder appears)
    t0 = time.monotonic()
    while not (tmp_path / "o" / "cache").exists() and time.monotonic() - t0 < 60:
        time.sleep(0.1)
    time.sleep(0.5)
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=120)
    # exit status 130, not death by SIGINT after the message (see
    # test_interrupt_inside_exec_code_still_exits_130)
    assert proc.returncode == 130, err
    assert err.strip().splitlines()[-1] == "mvtk run: interrupted"
    assert "Traceback" not in err


@pytest.mark.slow
def test_every_study_command_accepts_the_project_study(tmp_path, capsys):
    """Issue 16: `mvtk reduce` and `mvtk control` refused data/smart_beam/study.toml
    (plant_modes, actuator_limit_v, patch, control_rate_hz unknown), `control` after
    running every stage. All four commands now read it through the one schema."""
    jsonschema = pytest.importorskip("jsonschema")
    cache = tmp_path / "out"
    for command in ("control", "reduce", "update"):
        assert main([command, str(STUDY), "--cache", str(cache), "--json"]) == 0
        doc = json.loads(capsys.readouterr().out)
        schema = json.loads((ROOT / "schemas" / f"{command}.schema.json").read_text())
        jsonschema.validate(doc, schema, cls=jsonschema.Draft202012Validator)
        assert doc["schema_version"] == f"mvtk.{command}/1"
    assert doc["cached"] is True  # update: served from the cache control filled
    # and `mvtk run` into the same folder reuses those stages
    from mvtk.study import run

    res = run(STUDY, cache, progress=False, report=False)
    assert {"ingest", "fe", "updating", "damping", "reduction", "control"} <= set(
        res.cache_hits)
