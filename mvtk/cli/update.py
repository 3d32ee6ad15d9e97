"""``mvtk update STUDY.toml``: model updating from the ``[updating]`` section of a study.

The study is read through the one schema of :mod:`mvtk.study` (``data/smart_beam/study.toml``
works as is) and the update runs as the ``updating`` stage of the cached study pipeline
(``--cache DIR`` shares the cache of ``mvtk run --out DIR``)::

    [structure]
    file = "../structures/smart_beam.toml"   # structure TOML, relative to the study
    # (or, without file, the structure tables written inline in the study)

    [updating]
    targets_hz = [13.26, 41.14]              # ascending; or: targets = [{fn_hz = ...}]
    max_iter = 30                            # optional
    # n_modes, regularization, mac_weight, frequency_std: optional solver settings
    # model_form_std = 0.005                 # relative std of the model-form term
    # builder = "package.module:function"    # optional, default mvtk.fe.build_model

    [[updating.parameters]]
    path = "materials.steel.E"
    lower = 150e9
    upper = 260e9

    [[updating.parameters]]
    path = "boundary.clamp_stiffness"
    initial = 2000.0     # a field absent from the structure is created with this value
    lower = 20.0
    upper = 1e6
    log = true           # optional: log-scaled variable

With ``builder`` and an inline structure, every top-level table of the study that is not
a study section is part of the description handed to the builder.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ._commands import COMMANDS

__all__ = ["add_parser", "run_update"]


def _format_tables(summary: dict) -> str:
    import pandas as pd

    def table(records, index):
        df = pd.DataFrame(records)
        return (df.set_index(index) if index in df.columns else df).to_string()

    with pd.option_context("display.width", 160, "display.max_columns", 20):
        parts = [
            f"converged: {summary['success']} ({summary['message']}); evaluations "
            f"{summary['n_evaluations']}, identifiable: {summary['identifiable']}",
            _weighting_line(summary),
            "", "Residuals", table(summary["residuals"], "target"),
            "", "Parameters", table(summary["parameters"], "parameter"),
            "", "Unpaired model modes", table(summary["unpaired_modes"], "mode"),
        ]
    if summary.get("swaps"):
        parts += ["", f"Mode-pairing swaps: {list(summary['swaps'])}"]
    return "\n".join(parts)


def _weighting_line(summary: dict) -> str:
    """How the targets were weighted and what the parameter std stands on."""
    if summary.get("weighting") != "statistical":
        return (f"targets weighted by their weights; parameter std: "
                f"{summary.get('covariance_scaling') or 'none'}")
    mf = summary.get("model_form_std")
    vf = summary.get("variance_factor")
    return (f"targets weighted by 1/std^2 (identification std and a model-form term of "
            f"{100 * (mf or 0):.3g} % of fn); parameter std: "
            f"{summary.get('covariance_scaling')}; variance factor chi^2/(m-n) = "
            + ("n/a" if vf is None else f"{vf:.3g}"))


def run_update(args: argparse.Namespace) -> int:
    """Entry point of ``mvtk update``; returns the exit code (0 ok, 1 not converged)."""
    import tomli_w

    from ._common import check_output_file, json_document, refuse_inputs, run_view, study_inputs

    if args.out is not None:
        check_output_file(args.out, "--out")
        refuse_inputs([("--out", args.out)], study_inputs(args.study))
    overrides = {("updating", "max_iter"): args.max_iter} if args.max_iter is not None else None
    res = run_view(args.study, ["updating"], args.cache, overrides)
    up = res.results["updating"]
    summary = dict(up["summary"])
    if args.out is not None:
        from .._atomic import write_text

        write_text(args.out, tomli_w.dumps(up["description"]))
    if args.json:
        body = {**summary, "warnings": up["warnings"],
                "cached": "updating" in res.cache_hits}
        if args.out is not None:
            body["updated_structure"] = str(args.out)
        sys.stdout.write(json_document("update", args.study, body) + "\n")
    else:
        print(_format_tables(summary))
        for n in up["warnings"]:
            print(f"warning: {n}", file=sys.stderr)
        if args.out is not None:
            print(f"updated structure written to {args.out}")
    return 0 if summary["success"] else 1


def add_parser(subparsers) -> None:
    """Register ``mvtk update`` on an argparse sub-parser collection."""
    from ._common import add_cache_argument

    p = subparsers.add_parser(
        "update",
        help=COMMANDS["update"].help,
        description="Update the structure of STUDY.toml to the targets of its [updating] "
        "section (the updating stage of the study pipeline) and print the residual, "
        "parameter and unpaired-mode tables. Exit status 1 when the update did not "
        "converge.",
    )
    p.add_argument("study", type=Path, help="study TOML with an [updating] table")
    p.add_argument("--json", action="store_true",
                   help="print the result as JSON (schemas/update.schema.json)")
    p.add_argument("--out", type=Path, default=None, help="write the updated structure TOML")
    p.add_argument("--max-iter", type=int, default=None, help="override updating.max_iter")
    add_cache_argument(p)
    p.set_defaults(func=run_update)
