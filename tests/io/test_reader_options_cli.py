"""The reader options shared by ``mvtk read``, ``mvtk damping`` and ``mvtk modal``.

view_0.hdf5 (swept-sine plate test, PROVENANCE.md) stores no units: every command must
say which flag supplies them, and accept them through that flag.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from mvtk.cli import main

UNITS = ["--units", "N", "m/s^2", "V", "--quantity", "force", "acceleration", "voltage"]


def _view0(shared_data):
    src = shared_data / "hdf5" / "view_0.hdf5"
    if not src.is_file():
        pytest.skip(f"{src} not found")
    return str(src)


@pytest.mark.shared_data
@pytest.mark.parametrize("command", ["read", "damping", "modal"])
def test_missing_units_names_the_flag(shared_data, command, capsys):
    code = main([command, _view0(shared_data)])
    err = capsys.readouterr().err
    assert code == 2
    assert "view_0.hdf5" in err and "no units" in err and "--units" in err
    assert "Traceback" not in err


@pytest.mark.shared_data
def test_read_takes_units_and_quantities(shared_data, capsys):
    assert main(["read", _view0(shared_data), *UNITS]) == 0
    out = capsys.readouterr().out
    assert "force: force [N]" in out and "acc: acceleration [m/s^2]" in out
    assert "trigger: voltage [V]" in out


@pytest.mark.shared_data
def test_modal_takes_reader_options(shared_data, capsys):
    # H1 of the 60..500 Hz sweep; PROVENANCE lists H1 peaks near 77, 127, 265, 350 Hz
    code = main(["modal", _view0(shared_data), *UNITS, "--fmin", "60", "--fmax", "500",
                 "--json"])
    out = capsys.readouterr().out
    assert code == 0
    fn = np.array([m["fn_hz"] for m in json.loads(out)["modes"] if m["reliable"]])
    for peak in (77.0, 127.0, 265.0, 350.0):
        assert np.min(np.abs(fn - peak)) / peak < 0.015, (peak, fn)


def test_named_flags_win_over_set(capsys):
    import argparse

    from mvtk.cli._common import add_reader_options, reader_options

    p = argparse.ArgumentParser()
    add_reader_options(p)
    args = p.parse_args(["--set", "units=[\"V\"]", "--units", "N", "--fs", "100",
                         "--variable", "x", "--format", "mat"])
    assert reader_options(args) == {"units": ["N"], "fs": 100.0, "data": "x",
                                    "format": "mat"}
