"""Comparisons against references: pass/fail checks and error tables (pandas)."""

from ._checks import Check, check_table, frequency_table

__all__ = ["Check", "check_table", "frequency_table"]
