"""benchmarks/_summary.py: the markdown table of reports/bench.json for the README."""

import importlib.util
import json
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _summary_module():
    spec = importlib.util.spec_from_file_location("_bench_summary",
                                                  ROOT / "benchmarks" / "_summary.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


SUMMARY = {
    "created_utc": "2026-12-01T21:00:00Z", "python": "3.11.7", "cpu_count": 2,
    "benchmarks": {
        "fe": {"returncode": 0, "load_avg_1min_before": 3.7,
               "sparse_backend": "cholmod (sksparse-minimal 1.0.2, OpenBLAS 0.3.21)",
               "figures": {"n_dof": 49140, "median_total_s": 1.234567, "limit_ratio": 1.4,
                           "fn_hz": [0.43, 1.06], "rounds": 3},
               "peer": "OpenSeesPy ShellMITC4 eigen",
               "ratios": {"median_wall": 16.5, "median_cpu": 19.4}},
        "study": {"returncode": 0, "load_avg_1min_before": 0.5,
                  "figures": {"cold_s": 9.5, "warm_s": 0.8, "target_cold_s": 10.0,
                              "stages_s": {"fe": 0.2}},
                  "peer": "pandas | to_html", "ratios": {"x": float("nan")}},
        "io": {"returncode": 1, "wall_s": 2.0, "stdout_tail": ["io ratio 1.3"]},
        "damping": {"returncode": 0, "stdout_tail": ["half-power 2 ms"]},
    },
}


def test_markdown_table_rows_and_headline_figures():
    md = _summary_module().markdown_table(SUMMARY)
    lines = md.strip().splitlines()
    assert lines[0].startswith("Benchmarks of 2026-12-01T21:00:00Z (Python 3.11.7, 2 cores")
    # the backend the figures were made with
    assert "sparse factorisation cholmod (sksparse-minimal 1.0.2, OpenBLAS 0.3.21)" in lines[0]
    assert lines[2] == "| benchmark | figures | peer | ratios | load |"
    rows = {ln.split("|")[1].strip(): ln for ln in lines[4:]}
    assert set(rows) == {"fe", "study", "io", "damping"}
    # headline figures in the order of HEADLINE, 3 significant digits, lists left out
    assert "n_dof 49,140, median_total_s 1.23, limit_ratio 1.4 |" in rows["fe"]
    assert "median_wall 16.5, median_cpu 19.4" in rows["fe"] and "| 3.7 |" in rows["fe"]
    # a nested dict is not a figure; a '|' in a cell is escaped; NaN shown as n/a
    assert "stages_s" not in rows["study"] and "pandas \\| to_html" in rows["study"]
    assert "x n/a" in rows["study"]
    assert "FAILED (return code 1)" in rows["io"]
    assert "half-power 2 ms" in rows["damping"]          # no JSON: last output line


def test_markdown_cli(tmp_path):
    path = tmp_path / "bench.json"
    path.write_text(json.dumps(SUMMARY))
    proc = subprocess.run([sys.executable, str(ROOT / "benchmarks" / "_summary.py"),
                           "--markdown", "--out", str(path)], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout == _summary_module().markdown_table(SUMMARY)


def test_markdown_cli_missing_or_bad_file(tmp_path):
    missing = tmp_path / "none.json"
    proc = subprocess.run([sys.executable, str(ROOT / "benchmarks" / "_summary.py"),
                           "--markdown", "--out", str(missing)], capture_output=True, text=True)
    assert proc.returncode == 1 and f"{missing} does not exist" in proc.stderr
    bad = tmp_path / "bad.json"
    bad.write_text("{not json")
    proc = subprocess.run([sys.executable, str(ROOT / "benchmarks" / "_summary.py"),
                           "--markdown", "--out", str(bad)], capture_output=True, text=True)
    assert proc.returncode == 1 and "is not a JSON summary" in proc.stderr
