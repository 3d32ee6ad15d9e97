"""Comparisons against references: pass/fail checks, error tables (pandas), and the
registry of validation cases (mvtk against published benchmarks, closed forms, peers and
real files) that the test suite asserts and the documentation publishes."""

from ._cases import ValidationCase, run_validation, shared_data_dir, validation_cases
from ._checks import Check, check_table, frequency_table

__all__ = ["Check", "check_table", "frequency_table", "ValidationCase", "validation_cases",
           "run_validation", "shared_data_dir"]
