"""Histogram figure of Monte-Carlo natural frequencies: :mod:`mvtk.plot._histogram`."""

from ..plot._histogram import plot_fn_histogram

__all__ = ["plot_fn_histogram"]
