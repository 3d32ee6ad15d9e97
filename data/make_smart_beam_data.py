"""Make the SYNTHETIC smart-beam measurement files in ``data/smart_beam/``.

Everything written here is SYNTHETIC: simulated by this script, not measured. The file
names start with ``SYNTHETIC_`` and every header says so.

The "truth" structure
---------------------
The paper (Ghareeb & Schmidt, smart beam; see ``/work/shared/PHYSICS.md`` section 1)
measured f1 = 13.26 Hz and f2 = 41.14 Hz with Rayleigh damping identified from
zeta1 = 5.84e-4 and zeta2 = 1.32e-3 (alpha = 0.02955 1/s, beta = 9.77e-6 s). The truth
structure of this script has exactly those two frequencies and that damping. It differs
from the nominal model ``data/structures/smart_beam.toml`` (ideal clamp, steel
E = 210 GPa: 14.25 / 42.18 Hz) the way a real specimen differs from its drawing:

- the clamp is compliant: with the nominal mvtk FE model, a rotational clamp stiffness
  of 383 N m/rad per metre of clamped edge together with a steel modulus of 212.6 GPa
  (+1.2 %) reproduces 13.26 / 41.14 Hz to 1e-8 (least squares on
  ``boundary.clamp_stiffness`` and ``materials.steel.E`` with :func:`mvtk.fe.build_model`;
  an ideal clamp cannot: with any E, f2/f1 stays 2.96 instead of 3.10); the rounded
  values used here (383.3, 212.57 GPa) give 13.25994 / 41.13998 Hz. These two numbers
  are what the study's model updating should find;
- its modes are those of the mvtk FE model of the structure file with these two values
  (:func:`truth_model`): 13.26, 41.14, 78.56 (bending 2), 139.0 (torsion 2), 172.9,
  225.6 (bending 3), 287.2 / 287.6 Hz, ... (the file headers list them).

The response is computed by modal superposition of the lowest 12 FE modes of the truth
model (:func:`truth_modes`, up to about 510 Hz): for mode i, natural frequency
``fn_hz``, damping ratio from the paper's Rayleigh pair (every mode), and the
mass-normalised uz mode-shape values at the FE nodes nearest to the impact point
(``phi_force``), the tip sensor (``phi_sensor``) and the laser point (``phi_tip``), in
1/sqrt(kg), so the force-to-sensor participation of mode i is
``phi_force * phi_sensor``. The modal values are rounded (frequencies to 8 significant
digits, shapes to 1e-7) because the iterative eigensolver varies in the last digits.

The three tests
---------------
1. Impact test (``SYNTHETIC_smart_beam_impact.*``): 3 hammer hits 128 s apart (the
   first at 2 s, 388 s in all) (a half-sine pulse of 1.5 ms and about 5 N at
   (170, 110) mm), force and tip acceleration at (180, 20) mm, simulated at 2048 Hz,
   with sensor noise, an 8th-order Butterworth anti-aliasing filter at 50 Hz applied
   to both channels (like a DAQ's analogue filter) and decimation to 128 Hz. 128 s
   records give 1/128 Hz lines: about two lines across the mode-1 half-power band,
   which the damping estimators must flag. Modes 1-2 come from this test.
2. Free decay (``SYNTHETIC_smart_beam_decay.*``): 150 s of tip displacement (laser) and
   tip acceleration after the beam is released from a forced vibration in mode 1
   (2 mm tip amplitude; mode 2 left over at 1 % of the mode-1 modal amplitude,
   invisible to the laser on the centre line), same noise / filter / decimation.
3. Broadband impact test (``SYNTHETIC_smart_beam_broadband.*``): 3 hits 8 s apart
   with a hard tip (0.5 ms half-sine), same points and noise, simulated at 20 kHz,
   8th-order anti-aliasing filter at 400 Hz, decimated to 1250 Hz (1/fs = 8e-4 s is
   exact in the UFF header's 5-digit abscissa increment). 8 s records give 0.125 Hz
   lines, enough for the higher modes (their half-power bands are 0.4-1.6 Hz wide);
   the study identifies modes 3, 4 and 6 from it (for the Chowdhury pair).

Formats: CSV with a ``#`` comment header (what, units, sampling rate, seed) and one
column per channel; UFF 58b (binary, float64 ordinates, one record per channel) written
with pyuff. Total size is about 5.4 MB (broadband test 1.8 MB).

Run ``python data/make_smart_beam_data.py`` (seed 20261122; the output is reproducible
bit for bit for a given numpy/scipy version).
"""

from __future__ import annotations

import argparse
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy import signal

SEED = 20261122
FS_SIM = 2048.0  # Hz, simulation rate of the long tests
DECIMATE = 16  # -> 128 Hz stored
FS_OUT = FS_SIM / DECIMATE
AA_CUTOFF_HZ = 50.0
AA_ORDER = 8
# short broadband impact test (higher modes for the Chowdhury pair)
FS_SIM_BB = 20000.0  # Hz
DECIMATE_BB = 16  # -> 1250 Hz stored (1/fs = 8e-4 s exactly in the UFF header)
FS_OUT_BB = FS_SIM_BB / DECIMATE_BB
AA_CUTOFF_BB_HZ = 400.0
N_HITS_BB, RECORD_BB_S, PULSE_BB_S = 3, 8.0, 0.5e-3
SCAN_FMAX_HZ = 400.0  # scan-test FRFs are exported from 0 to this frequency

# Rayleigh pair of the paper's measured damping (PHYSICS.md section 2)
ZETA1, F1 = 5.84e-4, 13.26
ZETA2, F2 = 1.32e-3, 41.14

# The SYNTHETIC specimen. It is NOT the nominal model with two other parameter values
# (that would be an "inverse crime": updating would recover them exactly). It differs from
# the nominal structure file in ways no parameter of the study's model describes:
STRUCTURE = Path(__file__).resolve().parent / "structures" / "smart_beam.toml"
SPECIMEN = {
    # finer mesh than the nominal 5 mm (discretisation error of the study model)
    "element_size_m": 0.0025,
    # steel sheet thickness at the upper end of a 0.5 mm sheet's tolerance (+1.6 %)
    "steel_thickness_m": 0.508e-3,
    # patch bonded 0.3 mm further from the clamp than drawn, with a thicker bond line
    "patch_offset_x_m": 0.3e-3,
    "bond_thickness_m": 40e-6,
    # the tip accelerometer and its cable share (nominal model: massless sensor)
    "sensor_mass_kg": 1.0e-3,
    # a clamp that is stiffer at its two bolts than between them: rotational stiffness
    # 0.35 + two Gaussian bumps (sigma 12 mm) at the bolts, scaled to the mean below
    "clamp_bolts_y_m": (0.0333, 0.0998),
    "clamp_bolt_sigma_m": 0.012,
    "clamp_floor": 0.35,
    # steel modulus and mean clamp stiffness (N m/rad per m): chosen so that the
    # specimen's first two modes are the paper's measured 13.26 / 41.14 Hz (fitted once
    # with scipy.optimize.least_squares on this model; tests/study checks it)
    "steel_E_Pa": 216.3e9,
    "clamp_stiffness_mean": 430.8,
}
N_TRUTH_MODES = 12  # FE modes superposed (up to about 510 Hz)
IMPACT_XY = (0.170, 0.110)  # m
SENSOR_XY = (0.180, 0.020)  # m (tip sensor, off the centre line so torsion is seen)
TIP_XY = (0.180, 0.0665)  # m (laser on the tip centre line for the free decay)
# scanning-laser (roving response) test: a 4 x 3 grid + the driving point, +z velocity
SCAN_X = (0.060, 0.100, 0.140, 0.180)
SCAN_Y = (0.010, 0.0665, 0.123)


def scan_points() -> list[tuple[int, float, float]]:
    """Test nodes of the scan test: (node label, x, y) in m; node 101 is the driving point."""
    pts = [(100 + 1 + i, IMPACT_XY[0], IMPACT_XY[1]) for i in range(1)]
    k = 1
    for x in SCAN_X:
        for y in SCAN_Y:
            k += 1
            pts.append((100 + k, x, y))
    return pts


@dataclass(frozen=True)
class Mode:
    """One truth mode: frequency (Hz), damping ratio, shape values (1/sqrt(kg))."""

    name: str
    fn_hz: float
    zeta: float
    phi_force: float
    phi_sensor: float
    phi_tip: float
    phi_scan: tuple[float, ...] = ()


def rayleigh_pair(f1: float = F1, z1: float = ZETA1, f2: float = F2, z2: float = ZETA2):
    """Two-mode Rayleigh alpha (1/s), beta (s) (PHYSICS.md section 2 closed form)."""
    w1, w2 = 2 * np.pi * f1, 2 * np.pi * f2
    alpha = 2 * w1 * w2 * (z1 * w2 - z2 * w1) / (w2**2 - w1**2)
    beta = 2 * (z2 * w2 - z1 * w1) / (w2**2 - w1**2)
    return alpha, beta


def rayleigh_zeta(fn_hz: float, alpha: float, beta: float) -> float:
    w = 2 * np.pi * fn_hz
    return alpha / (2 * w) + beta * w / 2


def clamp_profile(y: np.ndarray, spec: dict = SPECIMEN) -> np.ndarray:
    """Relative rotational clamp stiffness along the clamped edge (mean 1 per unit length)."""
    y = np.asarray(y, dtype=float)
    return spec["clamp_floor"] + sum(
        np.exp(-0.5 * ((y - b) / spec["clamp_bolt_sigma_m"]) ** 2) for b in spec["clamp_bolts_y_m"])


def specimen_description(spec: dict = SPECIMEN) -> dict:
    """Structure description of the specimen: what the structure TOML CAN express."""
    from mvtk.fe import load_structure, set_by_path

    d = load_structure(STRUCTURE)
    d = set_by_path(d, "materials.steel.E", spec["steel_E_Pa"])
    d = set_by_path(d, "boundary.clamp_stiffness", spec["clamp_stiffness_mean"], create=True)
    d = set_by_path(d, "mesh.element_size", spec["element_size_m"])
    d = set_by_path(d, "structure.layers.0.thickness", spec["steel_thickness_m"])
    patch = dict(d["patches"][0])
    patch["x0"] += spec["patch_offset_x_m"]
    patch["x1"] += spec["patch_offset_x_m"]
    layers = [dict(layer) for layer in patch["layers"]]
    layers[0]["thickness"] = spec["bond_thickness_m"]
    patch["layers"] = layers
    d["patches"] = [patch, *d["patches"][1:]]
    return d


def truth_model(spec: dict = SPECIMEN):
    """The SYNTHETIC specimen's FE model (see :data:`SPECIMEN`).

    :func:`specimen_description` plus what a structure file of the nominal model cannot
    express: the clamp's rotational stiffness redistributed along the edge by
    :func:`clamp_profile` (same mean per metre) and the sensor's point mass on ux, uy, uz.
    """
    import dataclasses

    import scipy.sparse as sp

    from mvtk.fe import build_model

    m = build_model(specimen_description(spec))
    nodes = m.node_set("x0")
    y = m.nodes[nodes, 1]
    order = np.argsort(y)
    nodes, y = nodes[order], y[order]
    trib = np.zeros_like(y)
    trib[:-1] += np.diff(y) / 2
    trib[1:] += np.diff(y) / 2
    w = clamp_profile(y, spec)
    w = w / (np.sum(w * trib) / np.sum(trib))
    rows = np.array([m.dof_index(n, "ry") for n in nodes])
    dk = spec["clamp_stiffness_mean"] * (w - 1.0) * trib
    K = m.K + sp.csr_matrix((dk, (rows, rows)), shape=m.K.shape)
    sensor = m.nearest_node([SENSOR_XY[0], SENSOR_XY[1], 0.0])
    rows = [m.dof_index(sensor, c) for c in ("ux", "uy", "uz")]
    M = m.M + sp.csr_matrix((np.full(3, spec["sensor_mass_kg"]), (rows, rows)), shape=m.M.shape)
    return dataclasses.replace(m, K=sp.csr_matrix(K), M=sp.csr_matrix(M),
                               name="SYNTHETIC smart-beam specimen")


def truth_modes(n_modes: int = N_TRUTH_MODES) -> list[Mode]:
    """The specimen's lowest FE modes with the paper's Rayleigh damping.

    Mass-normalised shape values (uz, 1/sqrt(kg)) at the FE nodes nearest to the impact
    point, the tip sensor, the laser point and the scan points; each mode's sign is
    chosen so that its value at the sensor is >= 0 (output independent of the
    eigensolver's sign choice).
    """
    from mvtk.fe import modal_analysis

    model = truth_model()
    res = modal_analysis(model, n_modes)
    alpha, beta = rayleigh_pair()

    def row(x, y):
        return model.dof_index(model.nearest_node([x, y, 0.0]), "uz")

    rows = {"force": row(*IMPACT_XY), "sensor": row(*SENSOR_XY), "tip": row(*TIP_XY)}
    scan_rows = [row(x, y) for _, x, y in scan_points()]

    # the iterative eigensolver differs from run to run in the last digits: frequencies
    # to 8 significant digits and shape values (order 1-10 1/sqrt(kg)) to 1e-7 make the
    # files reproducible bit for bit (and set the numerical zeros of torsion modes on
    # the centre line to 0)
    def sig8(x: float) -> float:
        return float(f"{x:.8g}")

    def shape(x: float) -> float:
        return round(x, 7) + 0.0

    modes = []
    for i, fn in enumerate(res.fn_hz):
        phi = res.shapes[:, i]
        sign = 1.0 if phi[rows["sensor"]] >= 0 else -1.0
        fn = sig8(float(fn))
        modes.append(Mode(f"mode {i + 1} ({res.mode_type[i]})", fn,
                          rayleigh_zeta(fn, alpha, beta),
                          shape(sign * float(phi[rows["force"]])),
                          shape(sign * float(phi[rows["sensor"]])),
                          shape(sign * float(phi[rows["tip"]])),
                          tuple(shape(sign * float(phi[r])) for r in scan_rows)))
    return modes


def _modal_filter(mode: Mode, quantity: str, dt: float):
    """Discrete (b, a) from force to ``quantity`` of one mode (first-order hold)."""
    w = 2 * np.pi * mode.fn_hz
    den = [1.0, 2 * mode.zeta * w, w**2]
    num = {"acceleration": [1.0, 0.0, 0.0], "velocity": [1.0, 0.0],
           "displacement": [0.0, 0.0, 1.0]}[quantity]
    b, a, _ = signal.cont2discrete((num, den), dt, method="foh")
    return np.ravel(b), np.ravel(a)


def _anti_alias_and_decimate(x: np.ndarray, fs_sim: float = FS_SIM,
                             cutoff_hz: float = AA_CUTOFF_HZ,
                             decimate: int = DECIMATE) -> np.ndarray:
    sos = signal.butter(AA_ORDER, cutoff_hz, fs=fs_sim, output="sos")
    return signal.sosfilt(sos, x)[::decimate]


def impact_test(rng: np.random.Generator, modes: list[Mode], n_hits: int = 3,
                record_s: float = 128.0, fs_sim: float = FS_SIM,
                cutoff_hz: float = AA_CUTOFF_HZ, decimate: int = DECIMATE,
                pulse_s: float = 1.5e-3):
    """Force (N) and tip acceleration (m/s^2) at ``fs_sim / decimate``, SYNTHETIC."""
    n = int(round((n_hits * record_s + 4.0) * fs_sim))
    dt = 1.0 / fs_sim
    force = np.zeros(n)
    pulse_t = np.arange(int(round(pulse_s * fs_sim)) + 1) * dt
    hit_times = []
    for k in range(n_hits):
        t0 = k * record_s + 2.0 + rng.uniform(-0.05, 0.05)
        i0 = int(round(t0 * fs_sim))
        amp = 5.0 * rng.uniform(0.8, 1.2)
        force[i0:i0 + pulse_t.size] += amp * np.sin(np.pi * pulse_t / pulse_t[-1])
        hit_times.append(i0 * dt)
    acc = np.zeros(n)
    for m in modes:
        b, a = _modal_filter(m, "acceleration", dt)
        acc += m.phi_force * m.phi_sensor * signal.lfilter(b, a, force)
    force_meas = force + rng.normal(0.0, 0.005, n)  # N, hammer noise
    acc_meas = acc + rng.normal(0.0, 0.01, n)  # m/s^2, accelerometer noise
    return (_anti_alias_and_decimate(force_meas, fs_sim, cutoff_hz, decimate),
            _anti_alias_and_decimate(acc_meas, fs_sim, cutoff_hz, decimate),
            np.array(hit_times))


def free_decay(rng: np.random.Generator, modes: list[Mode], duration_s: float = 150.0,
               tip_amplitude: float = 2e-3, pre_roll_s: float = 2.0):
    """Tip displacement (m) and acceleration (m/s^2) of a release from mode 1, SYNTHETIC.

    The closed-form decay is evaluated from ``-pre_roll_s`` so that the causal
    anti-aliasing filter has settled when the stored record starts at t = 0.
    """
    t = (np.arange(int(round((duration_s + pre_roll_s) * FS_SIM))) / FS_SIM) - pre_roll_s
    disp = np.zeros_like(t)
    acc = np.zeros_like(t)
    q1 = tip_amplitude / modes[0].phi_tip  # modal amplitude of mode 1 (sqrt(kg) m)
    # mode 1, and mode 2 (torsion 1) left over at 1 % of the mode-1 modal amplitude
    amplitudes = {0: q1, 1: 0.01 * q1}
    for i, m in enumerate(modes):
        q0 = amplitudes.get(i, 0.0)
        if q0 == 0.0:
            continue
        w = 2 * np.pi * m.fn_hz
        wd = w * np.sqrt(1 - m.zeta**2)
        q = np.exp(-m.zeta * w * t) * (np.cos(wd * t) + m.zeta * w / wd * np.sin(wd * t))
        # exact second derivative of q for the free decay: q'' = -2 z w q' - w^2 q
        qd = -np.exp(-m.zeta * w * t) * (w**2 / wd) * np.sin(wd * t)
        qdd = -2 * m.zeta * w * qd - w**2 * q
        disp += q0 * m.phi_tip * q
        acc += q0 * m.phi_sensor * qdd
    disp_meas = disp + rng.normal(0.0, 2e-6, t.size)  # m, laser noise
    acc_meas = acc + rng.normal(0.0, 0.01, t.size)  # m/s^2
    n0 = int(round(pre_roll_s * FS_OUT))
    return (_anti_alias_and_decimate(disp_meas)[n0:], _anti_alias_and_decimate(acc_meas)[n0:])


def _csv(path: Path, header: list[str], columns: dict[str, np.ndarray],
         quantity: list[str], node: list[int], fs: float = FS_OUT) -> None:
    """CSV: '#' metadata lines, per-channel quantity/node rows, 'name [unit]' header."""
    n = len(next(iter(columns.values())))
    time = np.arange(n) / fs
    data = np.column_stack([time, *columns.values()])
    lines = [f"# {h}" for h in header]
    lines.append("# quantity: " + ", ".join(quantity))
    lines.append("# node: " + ", ".join(str(k) for k in node))
    lines.append(",".join(["time [s]", *columns]))
    with path.open("w", encoding="utf-8", newline="\n") as fh:
        fh.write("\n".join(lines) + "\n")
        np.savetxt(fh, data, delimiter=",", fmt=["%.7f"] + ["%.5e"] * len(columns))


def _uff(path: Path, title: str, channels: list[dict], fs: float = FS_OUT) -> None:
    import pyuff

    if path.exists():
        path.unlink()
    uff = pyuff.UFF(str(path))
    sets = []
    for ch in channels:
        data = np.asarray(ch["data"], dtype=float)
        dset = pyuff.prepare_58(
            binary=1, id1=f"SYNTHETIC {title}", id2=ch["name"],
            id3=f"simulated by data/make_smart_beam_data.py (seed {SEED})",
            id4="NOT A MEASUREMENT", id5="mvtk example data",
            func_type=1, rsp_node=ch["node"], rsp_dir=3, ref_node=ch["ref_node"], ref_dir=3,
            data=data, x=np.arange(data.size) / fs,
            ordinate_spec_data_type=ch["spec_data_type"], abscissa_spec_data_type=17,
            ordinate_len_unit_exp=0 if ch["units"] == "N" else 1,
            ordinate_force_unit_exp=1 if ch["units"] == "N" else 0,
            orddenom_spec_data_type=0, z_axis_spec_data_type=0,
            ordinate_axis_units_lab=ch["units"], abscissa_axis_units_lab="s",
            rsp_ent_name="beam", ref_ent_name="beam", ver_num=0, load_case_id=0,
            ord_data_type=4, abscissa_spacing=1, abscissa_min=0.0, abscissa_inc=1.0 / fs,
            z_axis_value=0.0, orddenom_len_unit_exp=0, orddenom_force_unit_exp=0,
            orddenom_temp_unit_exp=0, orddenom_axis_units_lab="NONE",
            z_axis_len_unit_exp=0, z_axis_force_unit_exp=0, z_axis_temp_unit_exp=0,
            z_axis_axis_units_lab="NONE", abscissa_len_unit_exp=0, abscissa_force_unit_exp=0,
            abscissa_temp_unit_exp=0, ordinate_temp_unit_exp=0,
        )
        sets.append(dset)
    # pyuff 2.5.8 always writes 58b ordinates as float64 (its writer ignores
    # ord_data_type 2), so the file declares double precision (ord_data_type 4).
    uff.write_sets(sets, mode="add", force_double=True)


def scan_test(rng: np.random.Generator, modes: list[Mode], n_hits: int = 3,
              record_s: float = RECORD_BB_S):
    """Roving-response (scanning laser) test: mobility FRFs at the scan points, SYNTHETIC.

    For each scan point, ``n_hits`` hammer hits (0.5 ms, about 5 N) at the driving point
    and the +z velocity there, simulated at 20 kHz with sensor noise, anti-aliasing at
    400 Hz and decimation to 1250 Hz, then an H1 impact FRF (one record per hit, force
    window 20 ms) by :func:`mvtk.signal.frf` with explicit settings, kept from 0 to
    400 Hz: what a vibrometer's software exports.
    """
    import mvtk.io
    import mvtk.signal

    dt = 1.0 / FS_SIM_BB
    spacing = record_s + 1.0  # s between hits: every record holds one hit only
    n = int(round((n_hits * spacing + 4.0) * FS_SIM_BB))
    pulse_t = np.arange(int(round(PULSE_BB_S * FS_SIM_BB)) + 1) * dt
    frfs, coherences = [], []
    for j, _ in enumerate(scan_points()):
        force = np.zeros(n)
        for k in range(n_hits):
            i0 = int(round((k * spacing + 2.0 + rng.uniform(-0.05, 0.05)) * FS_SIM_BB))
            force[i0:i0 + pulse_t.size] += 5.0 * rng.uniform(0.8, 1.2) * np.sin(
                np.pi * pulse_t / pulse_t[-1])
        vel = np.zeros(n)
        for m in modes:
            b, a = _modal_filter(m, "velocity", dt)
            vel += m.phi_force * m.phi_scan[j] * signal.lfilter(b, a, force)
        f_meas = _anti_alias_and_decimate(force + rng.normal(0.0, 0.005, n), FS_SIM_BB,
                                          AA_CUTOFF_BB_HZ, DECIMATE_BB)
        v_meas = _anti_alias_and_decimate(vel + rng.normal(0.0, 2e-5, n), FS_SIM_BB,
                                          AA_CUTOFF_BB_HZ, DECIMATE_BB)
        th = mvtk.io.time_history(np.vstack([f_meas, v_meas]), fs=FS_OUT_BB,
                                  channels=["force", "velocity"],
                                  quantity=["force", "velocity"], units=["N", "m/s"])
        res = mvtk.signal.frf(th, reference="force", response="velocity", excitation="impact",
                              nperseg=int(round(record_s * FS_OUT_BB)), force_window_s=0.02,
                              pretrigger=int(round(0.01 * FS_OUT_BB)))
        keep = res["frf"]["frequency"].values <= SCAN_FMAX_HZ
        frfs.append(np.asarray(res["frf"].values[0, 0, keep]))
        coherences.append(np.asarray(res["coherence"].values[0, 0, keep]))
        freq = res["frf"]["frequency"].values[keep]
    return freq, np.array(frfs), np.array(coherences)


def _scan_uff(path: Path, freq: np.ndarray, frfs: np.ndarray, coherence: np.ndarray) -> None:
    """Test geometry (UFF 15) and mobility FRFs (UFF 58, complex, m/s per N) + coherence."""
    import pyuff

    if path.exists():
        path.unlink()
    uff = pyuff.UFF(str(path))
    pts = scan_points()
    uff.write_sets(pyuff.prepare_15(
        node_nums=[p[0] for p in pts], def_cs=[0] * len(pts), disp_cs=[0] * len(pts),
        color=[1] * len(pts), x=[p[1] for p in pts], y=[p[2] for p in pts],
        z=[0.0] * len(pts)), mode="add")
    df = float(freq[1] - freq[0])
    sets = []
    for (label, _, _), h, coh in zip(pts, frfs, coherence):
        for func_type, data, ord_type, spec in ((4, h, 6, 11), (6, coh, 4, 0)):
            sets.append(pyuff.prepare_58(
                binary=1, id1=f"SYNTHETIC scan test, {'H1' if func_type == 4 else 'coherence'}",
                id2=f"point {label} +z / driving point 101 +z",
                id3=f"simulated by data/make_smart_beam_data.py (seed {SEED})",
                id4="NOT A MEASUREMENT", id5="mvtk example data",
                func_type=func_type, rsp_node=label, rsp_dir=3, ref_node=101, ref_dir=3,
                data=np.asarray(data), x=freq, ordinate_spec_data_type=spec,
                abscissa_spec_data_type=18, ordinate_len_unit_exp=1 if spec else 0,
                ordinate_force_unit_exp=0, orddenom_spec_data_type=13 if spec else 0,
                orddenom_force_unit_exp=1 if spec else 0, z_axis_spec_data_type=0,
                ordinate_axis_units_lab="m/s" if spec else "NONE",
                orddenom_axis_units_lab="N" if spec else "NONE",
                abscissa_axis_units_lab="Hz", rsp_ent_name="beam", ref_ent_name="beam",
                ver_num=0, load_case_id=0, ord_data_type=ord_type, abscissa_spacing=1,
                abscissa_min=0.0, abscissa_inc=df, z_axis_value=0.0,
                orddenom_len_unit_exp=0, orddenom_temp_unit_exp=0,
                z_axis_len_unit_exp=0, z_axis_force_unit_exp=0, z_axis_temp_unit_exp=0,
                z_axis_axis_units_lab="NONE", abscissa_len_unit_exp=0,
                abscissa_force_unit_exp=0, abscissa_temp_unit_exp=0, ordinate_temp_unit_exp=0,
            ))
    uff.write_sets(sets, mode="add", force_double=True)


def main(out_dir: Path) -> list[Path]:
    rng = np.random.default_rng(SEED)
    modes = truth_modes()
    out_dir.mkdir(parents=True, exist_ok=True)
    force, acc, hits = impact_test(rng, modes)
    disp_d, acc_d = free_decay(rng, modes)
    force_bb, acc_bb, hits_bb = impact_test(
        rng, modes, n_hits=N_HITS_BB, record_s=RECORD_BB_S, fs_sim=FS_SIM_BB,
        cutoff_hz=AA_CUTOFF_BB_HZ, decimate=DECIMATE_BB, pulse_s=PULSE_BB_S)
    common = [
        "SYNTHETIC DATA - simulated, not measured (mvtk example files)",
        f"generator: data/make_smart_beam_data.py, seed {SEED}",
        "structure: SYNTHETIC specimen (not the nominal model: finer mesh, 0.508 mm steel, "
        "patch +0.3 mm, 40 um bond, 1 g sensor mass, bolted clamp of non-uniform "
        "stiffness), see data/smart_beam/README.md",
    ]
    truth = ("truth modes: " + "; ".join(f"{m.name} {m.fn_hz:.3f} Hz zeta {m.zeta:.3e}"
                                         for m in modes))
    slow = [f"sampling_rate_hz: {FS_OUT:g}",
            f"anti_alias: Butterworth order {AA_ORDER}, {AA_CUTOFF_HZ:g} Hz, both channels",
            truth]
    fast = [f"sampling_rate_hz: {FS_OUT_BB:g}",
            f"anti_alias: Butterworth order {AA_ORDER}, {AA_CUTOFF_BB_HZ:g} Hz, both channels",
            truth]
    impact_channels = ("channels: force (node 1, impact at x=170 mm y=110 mm, +z), "
                       "tip_accel (node 5, tip sensor at x=180 mm y=20 mm, +z)")
    written = []
    p = out_dir / "SYNTHETIC_smart_beam_impact.csv"
    _csv(p, ["SYNTHETIC impact test: 3 hammer hits, records of 128 s", *common, *slow,
             "hit_times_s: " + " ".join(f"{h:.4f}" for h in hits), impact_channels],
         {"force [N]": force, "tip_accel [m/s^2]": acc}, ["force", "acceleration"], [1, 5])
    written.append(p)
    p = out_dir / "SYNTHETIC_smart_beam_decay.csv"
    _csv(p, ["SYNTHETIC free decay from mode 1 (release at t = 0)", *common, *slow,
             "channels: tip_disp (node 6, laser on tip centre x=180 mm y=66.5 mm, +z), "
             "tip_accel (node 5, x=180 mm y=20 mm, +z)"],
         {"tip_disp [m]": disp_d, "tip_accel [m/s^2]": acc_d}, ["displacement", "acceleration"],
         [6, 5])
    written.append(p)
    p = out_dir / "SYNTHETIC_smart_beam_broadband.csv"
    _csv(p, [f"SYNTHETIC broadband impact test: {N_HITS_BB} hammer hits "
             f"({PULSE_BB_S * 1e3:g} ms), records of {RECORD_BB_S:g} s", *common, *fast,
             "hit_times_s: " + " ".join(f"{h:.4f}" for h in hits_bb), impact_channels],
         {"force [N]": force_bb, "tip_accel [m/s^2]": acc_bb}, ["force", "acceleration"],
         [1, 5], fs=FS_OUT_BB)
    written.append(p)
    for name, title, fs, f_, a_ in (("impact", "impact test", FS_OUT, force, acc),
                                    ("broadband", "broadband impact test", FS_OUT_BB,
                                     force_bb, acc_bb)):
        p = out_dir / f"SYNTHETIC_smart_beam_{name}.uff"
        _uff(p, title, [
            {"name": "force", "data": f_, "node": 1, "ref_node": 1, "spec_data_type": 13,
             "units": "N"},
            {"name": "tip acceleration", "data": a_, "node": 5, "ref_node": 1,
             "spec_data_type": 12, "units": "m/s^2"},
        ], fs=fs)
        written.append(p)
    freq, scan, scan_coh = scan_test(rng, modes)
    p = out_dir / "SYNTHETIC_smart_beam_scan.uff"
    _scan_uff(p, freq, scan, scan_coh)
    written.append(p)
    p = out_dir / "SYNTHETIC_smart_beam_scan_geometry.csv"
    with p.open("w", encoding="utf-8", newline="\n") as fh:
        fh.write("# SYNTHETIC scan test geometry: test node labels and positions (m), global "
                 "axes of the FE model; node 101 is the driving point (hammer +z)\n")
        fh.write("node,x,y,z\n")
        for label, x, y in scan_points():
            fh.write(f"{label},{x:.4f},{y:.4f},0.0\n")
    written.append(p)
    p = out_dir / "SYNTHETIC_smart_beam_decay.uff"
    _uff(p, "free decay", [
        {"name": "tip displacement", "data": disp_d, "node": 6, "ref_node": 0,
         "spec_data_type": 8, "units": "m"},
        {"name": "tip acceleration", "data": acc_d, "node": 5, "ref_node": 0,
         "spec_data_type": 12, "units": "m/s^2"},
    ])
    written.append(p)
    return written


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path(__file__).parent / "smart_beam")
    args = parser.parse_args()
    for path in main(args.out):
        print(f"wrote {path} ({path.stat().st_size / 1e6:.2f} MB)")
