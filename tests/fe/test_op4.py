"""Nastran OUTPUT4 reader (mvtk.fe.read_op4) on pyNastran's OP4 test files.

External truth: the values pyNastran's tests assert for these files
(pyNastran/op4/test/op4_unit_tests.py, BSD-3; files and licence in tests/fe/data/op4):
EYE10 = I(10) with form 6, EYE5CD = (-1 + 1j) I(5) with form 6, NULL = 0(3 x 3) with
form 6, binary KGG == ASCII KGG. Further: the nine matrices are the same in the six
ASCII/binary, dense/sparse/BIGMAT files, and the free plate's KGG is
symmetric with exactly six rigid-body modes.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from mvtk.errors import FormatError
from mvtk.fe import Op4Matrix, read_matrices, read_op4

DATA = Path(__file__).parent / "data" / "op4"
MAT_FILES = ["mat_t_dn", "mat_t_s1", "mat_t_s2", "mat_b_dn", "mat_b_s1", "mat_b_s2"]
NAMES = {"EYE10", "EYE5CD", "LOW", "NULL", "RND1RS", "RND1RD", "RND1CS", "RND1CD", "STRINGS"}


@pytest.mark.parametrize("stem", MAT_FILES)
def test_values_asserted_by_pynastran(stem):
    mats = read_op4(DATA / f"{stem}.op4")
    assert set(mats) == NAMES and all(isinstance(m, Op4Matrix) for m in mats.values())
    eye = mats["EYE10"]
    assert eye.form == 6 and eye.form_name == "symmetric"
    np.testing.assert_array_equal(eye.toarray(), np.eye(10))
    assert mats["EYE5CD"].form == 6
    np.testing.assert_array_equal(mats["EYE5CD"].toarray(), (-1 + 1j) * np.eye(5))
    assert mats["NULL"].form == 6
    np.testing.assert_array_equal(mats["NULL"].toarray(), np.zeros((3, 3)))
    # LOW: 5 x 7 with column j holding j below the diagonal band (columns 5 empty)
    low = mats["LOW"].toarray()
    assert low.shape == (5, 7) and low[4, 3] == 4.0 and low[1, 0] == 1.0
    assert not low[:, 4].any()


def test_all_layouts_give_the_same_matrices():
    ref = read_op4(DATA / "mat_t_dn.op4")
    for stem in MAT_FILES[1:]:
        mats = read_op4(DATA / f"{stem}.op4")
        for name, m in ref.items():
            single = name.endswith(("RS", "CS")) or name == "STRINGS"
            # single-precision binary values are float32 roundings of the ASCII ones
            np.testing.assert_allclose(mats[name].toarray(), m.toarray(),
                                       rtol=1e-7 if single else 1e-15, err_msg=f"{stem} {name}")
            assert mats[name].form == m.form


def test_nastran_plate_stiffness_binary_and_ascii():
    kb = read_op4(DATA / "testplate_kgg.op4")["KGG"]
    ka = read_op4(DATA / "testplate_kgg_ascii.op4")["KGG"]
    assert kb.matrix.shape == (726, 726) and kb.form == 6
    # the ASCII file prints 10 significant digits (E16.9)
    assert abs(kb.matrix - ka.matrix).max() <= 1e-9 * abs(kb.matrix).max()
    K = kb.matrix
    assert abs(K - K.T).max() == 0.0
    # free plate: six rigid-body modes, then a gap of nine decades
    from scipy.sparse.linalg import eigsh

    scale = K.diagonal().max()
    w = np.sort(eigsh(K.tocsc(), 8, sigma=-1e-6 * scale, which="LM",
                      return_eigenvectors=False))
    assert np.all(np.abs(w[:6]) < 1e-14 * scale)
    assert w[6] > 1e-9 * scale


def test_op4_through_read_matrices(tmp_path):
    dofs = np.column_stack([np.repeat(np.arange(1, 122), 6), np.tile(np.arange(1, 7), 121)])
    src = DATA / "testplate_kgg.op4"
    model = read_matrices(src, f"{src}:KGG", dofs)  # M = K: only a reading check
    assert model.n_dof == 726 and model.n_nodes == 121
    assert abs(model.K - read_op4(src)["KGG"].matrix).max() == 0.0
    with pytest.raises(FormatError, match=r"holds the matrices \[.*'EYE10'.*\]; name the K "
                                          r"matrix as 'mat_t_dn.op4:NAME'"):
        read_matrices(DATA / "mat_t_dn.op4", DATA / "mat_t_dn.op4", dofs[:10])
    with pytest.raises(FormatError, match="no matrix 'KAA'; found"):
        read_matrices(f"{DATA / 'mat_t_dn.op4'}:KAA", src, dofs)
    with pytest.raises(FormatError, match="matrix 'EYE5CD' is complex"):
        read_matrices(f"{DATA / 'mat_t_dn.op4'}:EYE5CD", src, dofs)


def test_bad_op4_files(tmp_path):
    with pytest.raises(FormatError, match="OP4 file .*missing.op4' not found"):
        read_op4(tmp_path / "missing.op4")
    good = (DATA / "mat_t_dn.op4").read_text().splitlines(keepends=True)
    bad = tmp_path / "bad.op4"
    bad.write_text("".join(good[:5]))
    with pytest.raises(FormatError, match=r"bad.op4: matrix 'EYE10' ends without its "
                                          r"terminating record \(column 11\)"):
        read_op4(bad)
    bad.write_text("      10      10       6       7EYE10   1P,3E23.16\n")
    with pytest.raises(FormatError, match=r"bad.op4 line 1: matrix 'EYE10': type 7 is not"):
        read_op4(bad)
    bad.write_text("not an op4 file\n")
    with pytest.raises(FormatError, match=r"bad.op4 line 1: expected a matrix header"):
        read_op4(bad)
    rows = list(good)
    rows[1] = "       1      11       1\n"  # row 11 of a 10-row matrix
    bad.write_text("".join(rows))
    with pytest.raises(FormatError, match=r"bad.op4 line 2: matrix 'EYE10' column 1: rows "
                                          r"11..11 outside 1..10"):
        read_op4(bad)
    rows = list(good)
    rows[4] = " 1.0000000000000000E+00 2.0E+00\n"  # two numbers where NW = 1
    bad.write_text("".join(rows))
    with pytest.raises(FormatError, match=r"line 4: matrix 'EYE10' column 2: NW = 1 but 2"):
        read_op4(bad)
    binary = (DATA / "mat_b_dn.op4").read_bytes()
    bad.write_bytes(binary[:100])
    with pytest.raises(FormatError, match=r"bad.op4 record \d+: broken record markers"):
        read_op4(bad)
    bad.write_bytes(b"\x01\x02\x03\x04\xff\xfe" * 10)
    with pytest.raises(FormatError, match="not a 32-bit binary OP4 file"):
        read_op4(bad)


def test_big_endian_binary(tmp_path):
    """The little-endian dense binary file rewritten big-endian reads the same."""
    import struct

    data = (DATA / "mat_b_dn.op4").read_bytes()
    out, pos, typ = bytearray(), 0, 2
    while pos < len(data):
        (n,) = struct.unpack("<i", data[pos:pos + 4])
        rec = data[pos + 4:pos + 4 + n]
        if n == 24:  # header: NCOL NROW FORM TYPE + 8-character name
            ints = struct.unpack("<4i", rec[:16])
            typ = ints[3]
            body = struct.pack(">4i", *ints) + rec[16:]
        else:  # ICOL IROW NW + values
            fmt = "d" if typ in (2, 4) else "f"
            vals = np.frombuffer(rec[12:], "<" + fmt)
            body = struct.pack(">3i", *struct.unpack("<3i", rec[:12])) + vals.astype(
                ">" + fmt).tobytes()
        out += struct.pack(">i", n) + body + struct.pack(">i", n)
        pos += n + 8
    (tmp_path / "be.op4").write_bytes(bytes(out))
    big, little = read_op4(tmp_path / "be.op4"), read_op4(DATA / "mat_b_dn.op4")
    assert list(big) == list(little)
    for name in little:
        np.testing.assert_array_equal(big[name].toarray(), little[name].toarray())
