"""Closed-loop simulation speed: n-mode cantilever plant (2n states) + controller states,
5 s at a 10 kHz output rate (50 001 samples), paper scenario (release from mode 1).

Run: .venv/bin/python benchmarks/bench_control.py [--modes 20 40] [--repeat 3]

Prints the best-of-``repeat`` wall time per controller and, for the linear loops, the
ratio to scipy.signal.lsim (zero-order hold) on the same closed-loop state space (and to
python-control's forced_response when installed).
"""

from __future__ import annotations

import argparse
import time

import numpy as np
import scipy.signal

import mvtk.control as mc

F1 = 13.26


def best(fn, repeat):
    times = []
    out = None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return min(times), out


def run(n_modes: int, repeat: int, t_end: float, fs: float, lsoda: bool = True) -> None:
    plant = mc.cantilever_modal_plant(n_modes)
    x0 = mc.release_state(plant, 1, "tip", 1e-3)
    sc = mc.Scenario(output="tip", t_end=t_end, fs_out=fs)
    peak = mc._compare.switching_peak(plant, sc)
    bound = mc.srf_gain_limit(F1, 1.3 * F1, 0.5)
    ctrls = {
        "PPF": mc.PPF([(F1, 0.5, 0.1)], sensor="tip"),
        "SRF": mc.SRF([(1.3 * F1, 0.5, 0.16 * bound)], sensor="tip"),
        "VelocityFeedback": mc.VelocityFeedback(1e-3, sensor="patch_rotation"),
        "LQR": mc.LQR(R=1e-9),
        "PPF saturated 2 V (sampled)": mc.PPF([(F1, 0.5, 0.1)], sensor="tip", u_max=2.0),
        "Lyapunov velocity (sampled)": mc.LyapunovBangBang(u_max=0.5,
                                                           boundary_layer=0.5 * peak),
        "Lyapunov velocity (LSODA)": mc.LyapunovBangBang(u_max=0.5,
                                                         boundary_layer=0.5 * peak),
    }
    if not lsoda:
        del ctrls["Lyapunov velocity (LSODA)"]
    n_t = int(round(t_end * fs)) + 1
    print(f"\n{n_modes}-mode cantilever ({2 * n_modes} plant states), {t_end:g} s at "
          f"{fs:g} Hz output ({n_t} samples), best of {repeat}")
    print(f"{'controller':32s} {'states':>6s} {'mvtk s':>8s} {'lsim s':>8s} {'ratio':>7s} "
          f"{'ctrl s':>8s} {'max |dy|/|y|':>13s}")
    try:
        import control
    except ImportError:
        control = None
    for name, ctrl in ctrls.items():
        method = "LSODA" if "LSODA" in name else "auto"
        t_mvtk, ds = best(lambda c=ctrl, m=method: mc.simulate(
            plant, c, t_end=t_end, fs_out=fs, initial=x0, method=m), 1 if method == "LSODA"
            else repeat)
        n_states = ds.sizes["state"]
        line = f"{name:32s} {n_states:6d} {t_mvtk:8.3f}"
        law = ctrl.realize(plant)
        if law.is_linear:
            cl = mc.closed_loop(plant, ctrl)
            t = ds.time.values
            U = np.zeros((t.size, cl.n_inputs))
            X0 = np.concatenate([x0, np.zeros(cl.n_states - x0.size)])
            sys = cl.to_scipy()
            t_lsim, (_, y, _) = best(
                lambda s=sys, u=U, tt=t, x=X0: scipy.signal.lsim(s, u, tt, X0=x, interp=False),
                repeat)
            err = np.max(np.abs(ds.outputs.values[0] - y[:, 0])) / np.max(np.abs(y[:, 0]))
            line += f" {t_lsim:8.3f} {t_mvtk / t_lsim:7.2f}"
            if control is not None:
                csys = cl.to_control()
                t_ctl, _ = best(lambda s=csys, tt=t, x=X0: control.initial_response(
                    s, T=tt, X0=x), repeat)
                line += f" {t_ctl:8.3f}"
            else:
                line += f" {'-':>8s}"
            line += f" {err:13.2e}"
        else:
            line += f" {'-':>8s} {'-':>7s} {'-':>8s} {'-':>13s}"
        print(line)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--modes", type=int, nargs="+", default=[20])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--t-end", type=float, default=5.0)
    ap.add_argument("--fs", type=float, default=10_000.0)
    ap.add_argument("--no-lsoda", action="store_true",
                    help="skip the (slow, stiff) LSODA run of the Lyapunov law")
    args = ap.parse_args()
    for n in args.modes:
        run(n, args.repeat, args.t_end, args.fs, lsoda=not args.no_lsoda)


if __name__ == "__main__":
    main()
