"""The sub-commands of ``mvtk``: name, module and one-line help.

``mvtk --help`` and ``mvtk --version`` are answered from this table alone; a command's
module (and the library it calls) is imported only when that command runs.
"""

from __future__ import annotations

from typing import NamedTuple

__all__ = ["COMMANDS", "Command"]


class Command(NamedTuple):
    name: str
    module: str
    help: str


#: Sub-commands in the order of ``mvtk --help``.
COMMANDS = {c.name: c for c in (
    Command("run", "mvtk.cli.run",
            'run a validation study (TOML) and write the HTML report'),
    Command("init", "mvtk.cli.init",
            'write a first study TOML (and structure TOML) from your files'),
    Command("read", "mvtk.cli.read",
            'read a measurement file (CSV, UFF, MAT, HDF5, netCDF, TDMS, WAV) and describe it'),
    Command("damping", "mvtk.cli.damping",
            'natural frequencies and damping ratios from a measurement file'),
    Command("modes", "mvtk.cli.modes",
            'natural frequencies of a structure TOML'),
    Command("update", "mvtk.cli.update",
            'update FE model parameters to measured natural frequencies'),
    Command("reduce", "mvtk.cli.reduce",
            'Craig-Bampton super element and FE-vs-SE tables of a study TOML'),
    Command("control", "mvtk.cli.control",
            "compare the controllers of a study's [control] section on its SE plant"),
    Command("modal", "mvtk.cli.modal",
            'experimental/operational modal analysis (pLSCF+LSFD, SSI-cov)'),
    Command("correlate", "mvtk.cli.correlate",
            'map a test geometry onto an FE model; MAC, pairing and COMAC'),
    Command("report", "mvtk.cli.report",
            "show a written report's verdict; --pdf prints it to PDF"),
)}
