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
