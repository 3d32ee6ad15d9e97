"""A fast variant of the smart-beam study (coarse mesh, short records) for robustness tests.

Same sections and keys as ``data/smart_beam/study.toml`` (so every stage runs), with a
coarse mesh, 4 Monte-Carlo samples, a 1.5 s control simulation at 200 Hz (the
loose CoV tolerance fits 3 samples); the paths are made absolute so the copy works anywhere.
"""

from __future__ import annotations

from pathlib import Path

from study_text import with_absolute_paths

ROOT = Path(__file__).resolve().parents[2]
STUDY = ROOT / "data" / "smart_beam" / "study.toml"
STRUCTURE = ROOT / "data" / "structures" / "smart_beam.toml"

_REPLACE = (
    ('file = "../structures/smart_beam.toml"', 'file = "beam.toml"'),
    ("n_samples = 40 ", "n_samples = 3 "),
    ("t_end_s = 6.0", "t_end_s = 1.5"),
    ("fs_out = 500.0", "fs_out = 200.0"),
    ("uncertainty_cov_rel = 0.20", "uncertainty_cov_rel = 0.90"),
)


def write_fast_study(folder: Path, replace: dict[str, str] | None = None) -> Path:
    """Write ``study.toml`` + ``beam.toml`` into ``folder``; ``replace`` = more text
    replacements ``{old: new}`` of the study text."""
    folder.mkdir(parents=True, exist_ok=True)
    beam = STRUCTURE.read_text(encoding="utf-8")
    assert "element_size = 0.005" in beam
    (folder / "beam.toml").write_text(beam.replace("element_size = 0.005",
                                                   "element_size = 0.015"), encoding="utf-8")
    text = STUDY.read_text(encoding="utf-8")
    for old, new in (*_REPLACE, *(replace or {}).items()):
        assert old in text, old
        text = text.replace(old, new)
    text = with_absolute_paths(text)
    path = folder / "study.toml"
    path.write_text(text, encoding="utf-8")
    return path
