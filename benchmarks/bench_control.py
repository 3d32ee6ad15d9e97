"""Closed-loop simulation speed: n-mode cantilever plant (2n states) + controller states,
5 s at a 10 kHz output rate (50 001 samples), paper scenario (release from mode 1).

Run: .venv/bin/python benchmarks/bench_control.py [--modes 20 40] [--repeat 3]

Prints the best-of-``repeat`` wall time per controller and, for the linear loops, the
ratio to scipy.signal.lsim (zero-order hold) on the same closed-loop state space (and to
python-control's forced_response when installed).

Then the LQR figure of issue 17 item 7 (``--lqr-modes``, default 40 modes = 80 plant
states): the LQR gain plus the closed-loop simulation (5 s at 10 kHz from the paper's
release), wall and CPU time, next to python-control on the same plant in the same
script (``control.lqr`` + ``control.initial_response`` of the same closed loop), with
the gain agreement ``max |K_mvtk - K_control| / max |K_control|`` and the stability
verdict and margins of the loop (target: under 0.5 s).
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


def run_lqr(n_modes: int, repeat: int, t_end: float, fs: float) -> dict:
    """LQR gain + closed-loop simulation on an n-mode plant, mvtk vs python-control."""
    import scipy.linalg

    plant = mc.cantilever_modal_plant(n_modes)
    x0 = mc.release_state(plant, 1, "tip", 1e-3)
    ctrl = mc.LQR(R=1e-9)
    mc.simulate(plant, ctrl, t_end=0.01, fs_out=fs, initial=x0)  # imports, warm caches

    def mvtk_run():  # the LQR gain is computed inside (realize), once
        return mc.simulate(plant, ctrl, t_end=t_end, fs_out=fs, initial=x0)

    def cpu_best(fn):
        walls, cpus, out = [], [], None
        for _ in range(repeat):
            c0, w0 = time.process_time(), time.perf_counter()
            out = fn()
            walls.append(time.perf_counter() - w0)
            cpus.append(time.process_time() - c0)
        return min(walls), min(cpus), out

    w_m, c_m, ds = cpu_best(mvtk_run)
    K = ctrl.gain_matrix(plant)
    print(f"\nLQR on a {n_modes}-mode cantilever ({2 * n_modes} states), gain + {t_end:g} s "
          f"closed loop at {fs:g} Hz, best of {repeat}")
    print(f"  mvtk            wall {w_m:7.3f} s  cpu {c_m:7.3f} s  (target < 0.5 s: "
          f"{'met' if w_m < 0.5 else 'NOT met'})")
    out = {"n_states": 2 * n_modes, "mvtk_wall_s": w_m, "mvtk_cpu_s": c_m}
    try:
        import control
    except ImportError:
        print("  python-control not installed: no peer ratio")
        return out
    ss = plant.to_state_space()
    Q = scipy.linalg.block_diag(plant.K, plant.M)
    t = ds.time.values

    def control_run():
        k, _, _ = control.lqr(ss.A, ss.B, Q, np.array([[ctrl.R]]))
        cl = control.ss(ss.A - ss.B @ k, ss.B, ss.C, 0)
        return k, control.initial_response(cl, T=t, X0=x0)

    w_c, c_c, (Kc, resp) = cpu_best(control_run)
    agree = float(np.max(np.abs(K - Kc)) / np.max(np.abs(Kc)))
    y_c = np.asarray(resp.outputs)[0]
    y_m = ds.outputs.sel(output="tip").values
    dy = float(np.max(np.abs(y_m - y_c)) / np.max(np.abs(y_c)))
    print(f"  python-control  wall {w_c:7.3f} s  cpu {c_c:7.3f} s")
    print(f"  ratio control/mvtk: wall {w_c / w_m:.2f}x, cpu {c_c / c_m:.2f}x; gain agreement "
          f"{agree:.1e}; tip response agreement {dy:.1e}")
    summary = mc.stability_summary(plant, ctrl)
    print(f"  verdict {summary['verdict']}, max Re pole {summary['max_real_pole']:.4g} 1/s, "
          f"phase margin {summary['phase_margin_deg']:.1f} deg, gain margin "
          f"{summary['gain_margin_db']:.3g} dB")
    out.update(control_wall_s=w_c, control_cpu_s=c_c, ratio_wall=w_c / w_m,
               gain_agreement=agree)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--modes", type=int, nargs="+", default=[20])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--t-end", type=float, default=5.0)
    ap.add_argument("--fs", type=float, default=10_000.0)
    ap.add_argument("--no-lsoda", action="store_true",
                    help="skip the (slow, stiff) LSODA run of the Lyapunov law")
    ap.add_argument("--lqr-modes", type=int, default=40,
                    help="modes of the LQR speed case (2 states each; 0 skips it)")
    ap.add_argument("--lqr-only", action="store_true", help="run only the LQR speed case")
    args = ap.parse_args()
    if not args.lqr_only:
        for n in args.modes:
            run(n, args.repeat, args.t_end, args.fs, lsoda=not args.no_lsoda)
    if args.lqr_modes:
        run_lqr(args.lqr_modes, args.repeat, args.t_end, args.fs)


if __name__ == "__main__":
    main()
