"""A roving-hammer test written as one CSV file per hit point, with a known truth.

A simply supported beam sampled at 32 points (node k at x = k/33 L); the modal model has
five modes ``fn = 40 k^2 Hz`` (40, 160, 360, 640, 1000 Hz) with shapes ``sin(k pi x/L)``
and unit modal mass; the accelerometer stays at node 7, the hammer moves over the 32
nodes. Each file holds 0.3 s (fs = 4096 Hz), a 1.5 ms half-sine hit of 80..120 N at
10 ms and the exact tip acceleration (FFT convolution on an 8 s grid: the linear, not
circular, response) with 0.1 % sensor noise. Mode 1 (zeta 0.8 %) decays to only ~55 %
within the record: an exponential window is needed.

Faults: ``double`` (default node 10) gets a hammer rebound of 40 % of the hit 12 ms
after it; ``clipped`` (default node 20) records a force clipped at 70 % of its peak
(the structure felt the whole pulse; the ADC saturated).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

FS = 4096.0
RECORD_S = 0.3
N_POINTS = 32
SENSOR = 7
FN = 40.0 * np.arange(1, 6) ** 2
ZETA = np.array([0.008, 0.005, 0.004, 0.003, 0.003])
HIT_S = 0.01


def shapes(nodes) -> np.ndarray:
    """Mode shapes (n_modes, len(nodes)) at beam nodes 1..32, unit modal mass."""
    x = np.asarray(nodes, dtype=float) / (N_POINTS + 1)
    return np.sqrt(2.0) * np.sin(np.pi * np.arange(1, FN.size + 1)[:, None] * x[None, :])


def _pulse(t, t0, width, peak):
    return np.where((t >= t0) & (t < t0 + width),
                    peak * np.sin(np.pi * (t - t0) / width), 0.0)


def hit(at: int, rng, *, rebound=False, clip=None):
    """Force (as recorded) and sensor acceleration of one hit at node ``at``."""
    n = int(round(RECORD_S * FS))
    t = np.arange(n) / FS
    peak = rng.uniform(80, 120)
    force = _pulse(t, HIT_S, 1.5e-3, peak)
    if rebound:
        force = force + _pulse(t, HIT_S + 0.012, 1.5e-3, 0.4 * peak)
    n2 = 2**15
    f = np.fft.rfftfreq(n2, 1 / FS)
    w, wn = 2 * np.pi * f, 2 * np.pi * FN
    phi = shapes([SENSOR, at])
    den = wn[:, None] ** 2 - w[None, :] ** 2 + 2j * ZETA[:, None] * wn[:, None] * w[None, :]
    H = -(w**2) * np.sum((phi[:, 0] * phi[:, 1])[:, None] / den, axis=0)
    acc = np.fft.irfft(H * np.fft.rfft(force, n2), n2)[:n]
    acc += 1e-3 * np.max(np.abs(acc)) * rng.standard_normal(n)
    recorded = force if clip is None else np.minimum(force, clip * force.max())
    return t, recorded, acc


def write(folder, rng, *, double: int | None = 10, clipped: int | None = 20) -> list[Path]:
    """Write ``hit_node01.csv`` .. ``hit_node32.csv``; returns their paths."""
    folder = Path(folder)
    paths = []
    for at in range(1, N_POINTS + 1):
        t, force, acc = hit(at, rng, rebound=at == double,
                            clip=0.7 if at == clipped else None)
        p = folder / f"hit_node{at:02d}.csv"
        with open(p, "w", encoding="utf-8") as fh:
            fh.write(f"# roving hammer on a beam, accelerometer fixed at node {SENSOR}\n"
                     f"# node: {at}, {SENSOR}\n# direction: +z, +z\n"
                     "# quantity: force, acceleration\n"
                     "time [s],hammer [N],accelerometer [m/s^2]\n")
            np.savetxt(fh, np.column_stack([t, force, acc]), fmt="%.9g", delimiter=",")
        paths.append(p)
    return paths


def write_fe_test(folder, model, modes, points, sensor, *, zeta=0.01, fs=2048.0,
                  record_s=2.0, f_max_hz=None, seed=0, stem="hit",
                  direction="uz") -> list[Path]:
    """A roving-hammer test of an FE model's modes, one CSV file per hammer point.

    The specimen's modal model: the ``modes`` of ``model`` (mass-normalised shapes from
    :func:`mvtk.fe.modal_analysis`) below ``f_max_hz``, all with damping ``zeta``. The
    hammer hits the mesh nodes ``points`` (0-based node indices, test nodes 1..n in that
    order) along the global ``direction`` (``"uz"``: test direction ``+z``), the
    accelerometer stays at mesh node ``sensor``; the modal constant of mode r for hit j
    is ``phi_r(j) phi_r(sensor)`` (reciprocity of the FE modes at the mesh nodes). One
    hit per file (``mvtk.testing.impact_test``: exact linear convolution), 0.1 % noise
    on both channels. Also writes ``geometry.csv`` (node, x, y, z of the hit nodes).
    Returns the paths of the hit files.
    """
    from mvtk.fe import DOF_NAMES
    from mvtk.testing import impact_test

    folder = Path(folder)
    fn = np.asarray(modes.fn_hz, dtype=float)
    keep = fn < (f_max_hz if f_max_hz is not None else 0.45 * fs)
    u = model.expand(modes.shapes)[:, DOF_NAMES.index(direction), :][:, keep]
    d = "+" + direction[1]
    s_node = 1 + list(points).index(sensor) if sensor in list(points) else len(points) + 1
    (folder / "geometry.csv").write_text("node,x,y,z\n" + "".join(
        f"{k + 1},{x:.12g},{y:.12g},{z:.12g}\n"
        for k, (x, y, z) in enumerate(model.nodes[list(points)])), encoding="utf-8")
    files = []
    for k, p in enumerate(points):
        c = u[p] * u[sensor]
        c = np.where(np.abs(c) > 1e-9 * np.abs(c).max(), c, 0.0)
        th = impact_test(fn[keep], zeta, fs, record_s, 1, np.random.default_rng(seed + k),
                         modal_constants=c)
        v = th.values.copy()
        # noise on both channels: a noiseless sampled half-sine has an exact zero at the
        # Nyquist line, where mvtk.modal.frf_matrix refuses the H1 ratio
        v += 1e-3 * v.std(axis=1, keepdims=True) * np.random.default_rng(
            10_000 + seed + k).standard_normal(v.shape)
        path = folder / f"{stem}_{k + 1:02d}.csv"
        with open(path, "w", encoding="utf-8") as fh:
            fh.write(f"# roving hammer at node {k + 1}, accelerometer at node {s_node}\n"
                     f"# node: {k + 1}, {s_node}\n# direction: {d}, {d}\n"
                     "# quantity: force, acceleration\ntime [s],hammer [N],accel [m/s^2]\n")
            np.savetxt(fh, np.column_stack([th["time"].values, v[0], v[1]]), fmt="%.10g",
                       delimiter=",")
        files.append(path)
    return files


def write_decay(path, fn_hz, *, zeta=0.01, fs=2048.0, record_s=3.0, amplitude=5.0,
                seed=0) -> Path:
    """A free decay of one mode (``mvtk.testing.sdof_free_decay``, acceleration in
    m/s^2) with 0.5 % of ``amplitude`` white noise, written as a CSV file."""
    from mvtk.testing import sdof_free_decay

    d = sdof_free_decay(float(fn_hz), zeta, fs, record_s, amplitude=amplitude,
                        quantity="acceleration", units="m/s^2")
    x = d.values[0] + 5e-3 * amplitude * np.random.default_rng(seed).standard_normal(
        d.sizes["time"])
    path = Path(path)
    with open(path, "w", encoding="utf-8") as fh:
        fh.write("# free decay of one mode\n# quantity: acceleration\n"
                 "time [s],accel [m/s^2]\n")
        np.savetxt(fh, np.column_stack([d["time"].values, x]), fmt="%.10g", delimiter=",")
    return path


def cylinder_deck(path: Path, radius=0.6, length=0.5, arc_deg=70.0, nx=20, na=24) -> Path:
    """A cylindrical steel panel as a Nastran deck: CQUAD4, 1.2 mm PSHELL, MAT1, every
    edge simply supported (SPC1 123)."""
    arc = np.radians(arc_deg)
    out, nid, k = ["SOL 103\nCEND\nBEGIN BULK\n"], {}, 1
    for i in range(nx + 1):
        for j in range(na + 1):
            th = -arc / 2 + arc * j / na
            out.append(f"GRID,{k},,{length * i / nx:.9g},{radius * np.sin(th):.9g},"
                       f"{radius * np.cos(th):.9g}\n")
            nid[i, j] = k
            k += 1
    e = 1
    for i in range(nx):
        for j in range(na):
            out.append(f"CQUAD4,{e},1,{nid[i, j]},{nid[i + 1, j]},{nid[i + 1, j + 1]},"
                       f"{nid[i, j + 1]}\n")
            e += 1
    out.append("PSHELL,1,7,1.2-3,7\nMAT1,7,2.06+11,,0.29,7850.\n")
    edge = sorted({nid[i, j] for i in range(nx + 1) for j in range(na + 1)
                   if i in (0, nx) or j in (0, na)})
    out += [f"SPC1,1,123,{n}\n" for n in edge]
    out.append("ENDDATA\n")
    path.write_text("".join(out))
    return path


def add_noise_and_double_hit(path: Path, rng, *, noise=0.01, double_at_s=None):
    """1 % white noise on both channels of a roving_hammer CSV; optionally the whole
    record added again ``double_at_s`` later at half its size (a double hit)."""
    lines = path.read_text().splitlines()
    d = np.loadtxt(lines[5:], delimiter=",")
    if double_at_s is not None:
        n0 = int(round(double_at_s / (d[1, 0] - d[0, 0])))
        d[n0:, 1:] += 0.5 * d[:-n0, 1:].copy()
    d[:, 1:] += noise * d[:, 1:].std(axis=0) * rng.standard_normal(d[:, 1:].shape)
    path.write_text("\n".join(lines[:5] + [f"{t:.10g},{a:.10g},{b:.10g}" for t, a, b in d])
                    + "\n")


def write_nastran_panel_test(root: Path):
    """A newcomer's own Nastran deck and roving-hammer test in ``root``: a cylindrical
    panel (:func:`cylinder_deck`, ``panel.bdf``), 4 x 4 hammer points, the sensor at
    point 6, 0.5 s records (an exponential window is needed), zeta 0.5 %, 1 % noise,
    point 6 hit twice (``hit_06b.csv``, a second file), point 11 with a double hit
    0.25 s after the first. Returns ``(deck, fe_fn_hz, model, hit_files)``; the test
    geometry is ``root / "test" / "geometry.csv"``."""
    import warnings

    from mvtk.fe import modal_analysis
    from mvtk.fe._structure import build_model, resolve_mesh_file

    deck = cylinder_deck(root / "panel.bdf")
    model = build_model(resolve_mesh_file({"structure": {"type": "mesh"},
                                           "mesh": {"file": deck.name}}, root))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        modes = modal_analysis(model, 12)
    pts = []
    for x in (0.1, 0.2, 0.3, 0.4):
        for th in np.radians([-25, -8, 8, 25]):
            at = [x, 0.6 * np.sin(th), 0.6 * np.cos(th)]
            pts.append(int(np.argmin(np.linalg.norm(model.nodes - at, axis=1))))
    test = root / "test"
    test.mkdir()
    write_fe_test(test, model, modes, pts, pts[5], zeta=0.005, fs=2048.0,
                     record_s=0.5, f_max_hz=560.0, seed=7)
    again = root / "again"
    again.mkdir()
    second = write_fe_test(again, model, modes, [pts[5]], pts[5], zeta=0.005,
                              fs=2048.0, record_s=0.5, f_max_hz=560.0, seed=1234)[0]
    text = second.read_text().replace("node 1, accelerometer at node 1",
                                      "node 6, accelerometer at node 6")
    (test / "hit_06b.csv").write_text(text.replace("# node: 1, 1", "# node: 6, 6"))
    rng = np.random.default_rng(99)
    for p in sorted(test.glob("hit_*.csv")):
        add_noise_and_double_hit(p, rng, double_at_s=0.25 if p.name == "hit_11.csv"
                                  else None)
    return deck, np.asarray(modes.fn_hz), model, sorted(test.glob("hit_*.csv"))
