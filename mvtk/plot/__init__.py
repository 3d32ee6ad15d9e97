"""Figures (the only subpackage importing matplotlib, lazily, with figures built off pyplot)."""

from ._animation import mesh_edges, mode_animation_html
from ._correlation import plot_mac, plot_paired_shapes, plot_test_on_mesh
from ._figures import (
    figure_to_png,
    minmax_decimate,
    plot_decay,
    plot_frf,
    plot_mode_shapes,
    plot_spectra,
    plot_time_responses,
)
from ._histogram import plot_fn_histogram
from ._modal import plot_automac, plot_frf_synthesis, plot_modal_uncertainty, plot_stabilisation

__all__ = [
    "figure_to_png",
    "minmax_decimate",
    "plot_frf",
    "plot_decay",
    "plot_mode_shapes",
    "plot_time_responses",
    "plot_spectra",
    "plot_mac",
    "plot_paired_shapes",
    "plot_test_on_mesh",
    "plot_stabilisation",
    "plot_frf_synthesis",
    "plot_automac",
    "plot_modal_uncertainty",
    "plot_fn_histogram",
    "mesh_edges",
    "mode_animation_html",
]
