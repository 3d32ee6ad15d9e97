"""Figures (the only subpackage importing matplotlib, lazily, with figures built off pyplot)."""

from ._figures import (
    figure_to_png,
    minmax_decimate,
    plot_decay,
    plot_frf,
    plot_mode_shapes,
    plot_spectra,
    plot_time_responses,
)

__all__ = [
    "figure_to_png",
    "minmax_decimate",
    "plot_frf",
    "plot_decay",
    "plot_mode_shapes",
    "plot_time_responses",
    "plot_spectra",
]
