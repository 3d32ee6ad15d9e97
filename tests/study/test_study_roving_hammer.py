"""A roving-hammer test from time-history files through the study's [modal] section.

The lab's data: one CSV file per hammer position (force at that node, the fixed
accelerometer at the chain's tip), as a DAQ exports them. The truth is the 4-DOF chain's
exact poles and mode shapes (mvtk.modal.exact_modes, state-space eigenproblem).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from mvtk.errors import ConfigError
from mvtk.modal import exact_frf, exact_modes
from mvtk.study import load_study, run

ROOT = Path(__file__).resolve().parents[2]
STRUCTURE = ROOT / "data" / "structures" / "smart_beam.toml"
FS, N = 512.0, 8192          # 16 s per hit; mode 1 (17.5 Hz, zeta 0.3 %) decays 40 dB
SENSOR = 3                   # accelerometer at the free end (node 4)


def _chain(n=4, m=1.0, k=1e5, alpha=0.5, beta=1e-5):
    M = np.eye(n) * m
    K = np.zeros((n, n))
    for i in range(n):
        K[i, i] = 2 * k if i < n - 1 else k
        if i:
            K[i, i - 1] = K[i - 1, i] = -k
    return M, alpha * M + beta * K, K


def _hit(M, C, K, at: int, rng) -> tuple[np.ndarray, np.ndarray]:
    """Force (half-sine, 4 ms, 100 N at 0.1 s) and the tip acceleration, noise 0.1 %."""
    t = np.arange(N) / FS
    force = np.where((t >= 0.1) & (t < 0.104), 100 * np.sin(np.pi * (t - 0.1) / 0.004), 0.0)
    n2 = 4 * N  # zero padding: the linear (not circular) response
    f = np.fft.rfftfreq(n2, 1 / FS)
    H = exact_frf(M, C, K, f, [SENSOR], [at], frf_type="accelerance").values[0, 0]
    acc = np.fft.irfft(H * np.fft.rfft(force, n2), n2)[:N]
    acc += 1e-3 * acc.std() * rng.standard_normal(N)
    return force, acc


def _write_sets(folder: Path, rng) -> tuple[list[str], tuple]:
    M, C, K = _chain()
    names = []
    for at in range(4):
        force, acc = _hit(M, C, K, at, rng)
        p = folder / f"hit_node{at + 1}.csv"
        with open(p, "w", encoding="utf-8") as fh:
            fh.write("# roving hammer on a 4-mass chain, accelerometer fixed at node 4\n"
                     f"# node: {at + 1}, 4\n# direction: +z, +z\n"
                     "# quantity: force, acceleration\n"
                     "time [s],hammer [N],tip [m/s^2]\n")
            np.savetxt(fh, np.column_stack([np.arange(N) / FS, force, acc]), fmt="%.9g",
                       delimiter=",")
        names.append(p.name)
    (folder / "geometry.csv").write_text(
        "node,x,y,z\n" + "".join(f"{i},{0.1 * i},0,0\n" for i in range(1, 5)),
        encoding="utf-8")
    return names, (M, C, K)


def _study(folder: Path, sets: list[str], extra: str = "") -> Path:
    p = folder / "study.toml"
    p.write_text(
        f'[structure]\nfile = "{STRUCTURE.as_posix()}"\n[modal]\n'
        f"sets = {sets!r}\n".replace("'", '"')
        + 'geometry = "geometry.csv"\nfmin_hz = 5.0\nfmax_hz = 120.0\n' + extra,
        encoding="utf-8")
    return p


@pytest.mark.slow
def test_roving_hammer_sets_identify_the_chain(tmp_path):
    rng = np.random.default_rng(3)
    sets, (M, C, K) = _write_sets(tmp_path, rng)
    res = run(_study(tmp_path, sets), tmp_path / "out", stages=["modal"], progress=False,
              report=False)
    assert not res.failed, res.failed
    mod = res.results["modal"]
    assert mod["n_responses"] == 4 and mod["n_references"] == 1
    assert "reciprocity" in mod["note"]
    poles, phi = exact_modes(M, C, K)
    fn_true = np.abs(poles) / (2 * np.pi)
    zeta_true = -poles.real / np.abs(poles)
    table = mod["table"]
    fn = np.array(table["fn_hz"])
    assert len(fn) == 4 and all(table["reliable"])
    np.testing.assert_allclose(fn, fn_true, rtol=1e-5)  # found: 2e-7
    # found: 3.2e-3 on mode 1 (17.5 Hz, 0.28 %, 13 lines per half-power bandwidth) with
    # the maximum-likelihood refinement's continuous-time model on these truncated,
    # nearly noise-free impact records (2.7 of its predicted std); 1e-4 on modes 2-4
    np.testing.assert_allclose(table["zeta"], zeta_true, rtol=5e-3)
    assert np.all(np.abs(np.array(table["zeta"]) - zeta_true)
                  < 4 * np.array(table["zeta_std"]) + 1e-4 * zeta_true)
    # the shapes at the hammer points are the chain's mode shapes (reciprocity)
    shapes = res.arrays["modal"]["shapes"]
    assert list(shapes["node"].values) == [1, 2, 3, 4]
    for k in range(4):
        a, b = shapes.values[k], np.real(phi[k] / phi[k][np.argmax(np.abs(phi[k]))])
        mac = abs(a @ b) ** 2 / ((a @ a) * (b @ b))
        assert mac > 0.999, (k, mac)


def test_modal_needs_file_or_sets(tmp_path):
    (tmp_path / "a.csv").write_text("x\n", encoding="utf-8")
    p = _study(tmp_path, ["a.csv"], 'file = "a.csv"\n')
    with pytest.raises(ConfigError, match=r"\[modal\]: give exactly one of "
                       r"\['file', 'sets'\], got \['file', 'sets'\]"):
        load_study(p)
    p = _study(tmp_path, ["missing.csv"])
    with pytest.raises(ConfigError, match=r"modal\.sets\[0\]: 'missing\.csv' not found"):
        load_study(p)


@pytest.mark.slow
def test_init_recognises_a_roving_hammer_test(tmp_path, capsys):
    from mvtk.cli import main

    _write_sets(tmp_path, np.random.default_rng(3))
    hits = sorted(str(p) for p in tmp_path.glob("hit_node*.csv"))
    assert main(["init", str(tmp_path / "s"), "--measurements", *hits,
                 "--geometry", str(tmp_path / "geometry.csv")]) == 0
    out = capsys.readouterr().out
    assert out.count("roving set") == 3 and "hit_node1.csv: impact" in out
    study = load_study(tmp_path / "s" / "study.toml")
    mo = study.config["modal"]
    assert [Path(s).name for s in mo["sets"]] == [Path(h).name for h in hits]
    assert mo["geometry"].endswith("geometry.csv") and mo["fmax_hz"] > 95.0
    res = run(study.path, tmp_path / "s" / "out", stages=["modal"], progress=False,
              report=False)
    assert not res.failed, res.failed
    assert len(res.results["modal"]["table"]["fn_hz"]) == 4


def test_missing_geometry_of_csv_sets_is_a_clear_refusal(tmp_path):
    from mvtk.study._ema import geometry_of

    class _Study:  # the two methods geometry_of uses
        def has_extra_file(self, name):
            return False

        def extra_file(self, name):
            return tmp_path / "hit_node1.csv"

    (tmp_path / "hit_node1.csv").write_text("time [s],hammer [N]\n0,1\n", encoding="utf-8")
    import xarray as xr

    shapes = xr.DataArray(np.ones((1, 1)), dims=("mode", "dof"),
                          coords={"dof": ["1+z"], "node": ("dof", [1]),
                                  "direction": ("dof", ["+z"])})
    with pytest.raises(ConfigError, match=r"modal\.geometry: not given, and hit_node1\.csv "
                       r"holds no test geometry .*expected geometry = "):
        geometry_of(_Study(), {"shapes": shapes})


def test_multipoint_measurement_keys_are_checked(tmp_path):
    for name in ("a.csv", "geometry.csv"):
        (tmp_path / name).write_text("x\n", encoding="utf-8")
    mp = '[measurements.day2]\nkind = "multi-point"\n'
    p = _study(tmp_path, ["a.csv"], mp + 'sets = ["missing.csv"]\n')
    with pytest.raises(ConfigError, match=r"measurements\.day2\.sets\[0\]: 'missing\.csv' "
                       "not found"):
        load_study(p)
    p = _study(tmp_path, ["a.csv"], mp + 'sets = ["a.csv"]\nfmin_hz = 200.0\n')
    with pytest.raises(ConfigError, match=r"measurements\.day2: expected fmin_hz < fmax_hz, "
                       r"got 200\.0 and 120\.0 Hz"):
        load_study(p)
    p = _study(tmp_path, ["a.csv"], mp + 'sets = ["a.csv"]\nfile = "a.csv"\n')
    with pytest.raises(ConfigError, match=r"measurements\.day2\]: give exactly one of"):
        load_study(p)
    p = _study(tmp_path, ["a.csv"], mp.replace("day2", "decay") + 'sets = ["a.csv"]\n')
    with pytest.raises(ConfigError, match="a multi-point test needs a name of its own"):
        load_study(p)
    q = tmp_path / "no_modal.toml"
    q.write_text(f'[structure]\nfile = "{STRUCTURE.as_posix()}"\n' + mp
                 + 'sets = ["a.csv"]\nfmin_hz = 1.0\nfmax_hz = 2.0\n', encoding="utf-8")
    with pytest.raises(ConfigError, match=r"measurements\.day2: a multi-point measurement "
                       r"needs a \[modal\] section"):
        load_study(q)
    study = load_study(_study(tmp_path, ["a.csv"], mp + 'sets = ["a.csv", "a.csv"]\n'))
    assert "day2" not in study.measurement_files      # not a single-record test
    assert [k for k in study.extra_files if "day2" in k] == [
        "multipoint[day2].set_1", "multipoint[day2].set_2"]
