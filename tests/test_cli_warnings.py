"""Warnings that escape a command are one line for the user, not Python's source dump."""

from __future__ import annotations

import warnings

from mvtk.cli import main
from mvtk.errors import AccuracyWarning


def test_escaping_warning_is_one_plain_line(monkeypatch, capsys):
    import mvtk.cli.modes as fe_cli

    def run(args):
        warnings.warn("half_power: |H| deviates by 8.3 %\nfrom a single-mode curve",
                      AccuracyWarning, stacklevel=1)
        return 0

    monkeypatch.setattr(fe_cli, "run", run)
    with warnings.catch_warnings():
        warnings.simplefilter("always")
        assert main(["modes", "x.toml"]) == 0
    err = capsys.readouterr().err
    assert err == ("mvtk modes: AccuracyWarning: half_power: |H| deviates by 8.3 % from a "
                   "single-mode curve\n")
    # the display is restored after the command
    assert warnings.showwarning.__module__ == "warnings"
