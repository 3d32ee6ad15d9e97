"""Parameter studies and Monte Carlo: in-process vs cluster, closed-form scatter, errors."""

from __future__ import annotations

import copy
import warnings

import numpy as np
import pytest

import mvtk.fe
import mvtk.updating
from mvtk.errors import ConfigError, DataRepairWarning, ParameterError
from mvtk.scale import (
    DISTRIBUTION_KINDS,
    MonteCarloResult,
    draw_samples,
    monte_carlo,
    parameter_study,
    plot_fn_histogram,
)
from mvtk.updating import with_values

STRIP = {
    "name": "aluminium cantilever strip",
    "materials": {"al": {"E": 70e9, "nu": 0.3, "rho": 2700.0}},
    "structure": {"type": "plate", "length": 0.3, "width": 0.02,
                  "layers": [{"material": "al", "thickness": 3e-3}]},
    "mesh": {"nx": 8, "ny": 2},
    "boundary": {"clamp": "x0"},
}


def test_parameter_study_in_process_equals_direct_modal_analysis():
    samples = {"materials.al.E": [60e9, 80e9], "structure.layers.0.thickness": [2e-3, 4e-3]}
    ds = parameter_study(STRIP, samples, n_modes=3)
    assert ds["fn_hz"].dims == ("sample", "mode")
    assert list(ds["mode"].values) == [1, 2, 3]
    np.testing.assert_array_equal(ds["materials.al.E"].values, [60e9, 80e9])
    for i in range(2):
        vals = {p: samples[p][i] for p in samples}
        direct = mvtk.fe.modal_analysis(mvtk.fe.build_model(with_values(STRIP, vals)), 3)
        # K without its round-off entries vs modal_analysis' K: equal to the
        # factorisation's round-off on mode 1 (1.1e-10 with SuperLU, block Lanczos)
        np.testing.assert_allclose(ds["fn_hz"].values[i], direct.fn_hz, rtol=1e-9)
    assert ds.attrs["scheduler"] == "in-process" and ds.attrs["n_failed"] == 0
    assert STRIP["materials"]["al"]["E"] == 70e9  # the description is not modified


def test_parameter_study_gives_modal_analysis_frequencies_on_rebuilt_models():
    """The study solves samples after the first without modal_analysis' mode typing
    and without K's round-off entries; on an elastic clamp and over thickness, modulus
    and density scatter the frequencies are modal_analysis' to the eigen solver's
    round-off: the dropped entries are below 1e-15 of the diagonal (the physical ones
    above 1e-6), and a different factorisation order moves the first eigenvalue of this
    thin strip by up to 5e-10 (measured)."""
    desc = copy.deepcopy(STRIP)
    desc["boundary"]["clamp_stiffness"] = 500.0
    rng = np.random.default_rng(11)
    samples = {"materials.al.E": rng.normal(70e9, 3e9, 5),
               "materials.al.rho": rng.normal(2700, 50, 5),
               "structure.layers.0.thickness": rng.normal(3e-3, 1e-4, 5),
               "boundary.clamp_stiffness": rng.uniform(100.0, 1000.0, 5)}
    ds = parameter_study(desc, samples, n_modes=4)
    for i in range(5):
        vals = {p: float(samples[p][i]) for p in samples}
        direct = mvtk.fe.modal_analysis(mvtk.fe.build_model(with_values(desc, vals)), 4)
        np.testing.assert_allclose(ds["fn_hz"].values[i], direct.fn_hz, rtol=2e-9)


def test_parameter_study_of_a_free_structure_keeps_the_rigid_body_modes():
    """A free-free strip (singular K) goes through modal_analysis for every sample:
    six rigid-body modes at 0 Hz, then the elastic ones, as modal_analysis reports."""
    desc = copy.deepcopy(STRIP)
    del desc["boundary"]["clamp"]
    samples = {"materials.al.E": [65e9, 75e9, 70e9]}
    ds = parameter_study(desc, samples, n_modes=8)
    for i, e in enumerate(samples["materials.al.E"]):
        direct = mvtk.fe.modal_analysis(
            mvtk.fe.build_model(with_values(desc, {"materials.al.E": e})), 8)
        assert np.sum(direct.fn_hz == 0.0) == 6
        np.testing.assert_array_equal(ds["fn_hz"].values[i], direct.fn_hz)


def test_monte_carlo_scatter_matches_the_closed_form():
    """f ~ sqrt(E / rho) for a fixed geometry: every mode scales exactly, so
    CoV(f1) = CoV(sqrt(E)) of the drawn samples, = CoV(E) / 2 to first order."""
    n = 40
    mc = monte_carlo(STRIP, {"materials.al.E": ("lognormal", (70e9, 3.5e9))}, n,
                     np.random.default_rng(5), n_modes=2)
    assert isinstance(mc, MonteCarloResult)
    e = mc.samples["materials.al.E"].values
    fn = mc.fn_hz
    nominal = mvtk.fe.modal_analysis(mvtk.fe.build_model(STRIP), 2).fn_hz
    np.testing.assert_allclose(fn, nominal * np.sqrt(e / 70e9)[:, None], rtol=1e-7)
    tab = mc.to_dataframe()
    assert list(tab.columns) == ["mode", "n", "mean_hz", "std_hz", "cov", "min_hz", "p5_hz",
                                 "p50_hz", "p95_hz", "max_hz"]
    cov_sqrt_e = np.std(np.sqrt(e), ddof=1) / np.mean(np.sqrt(e))
    np.testing.assert_allclose(tab["cov"], cov_sqrt_e, rtol=1e-6)
    cov_e = np.std(e, ddof=1) / np.mean(e)
    np.testing.assert_allclose(tab["cov"], cov_e / 2, rtol=0.02)  # small-scatter limit
    np.testing.assert_allclose(tab["p50_hz"], np.median(fn, axis=0))
    assert (tab["n"] == n).all()
    # density scatter: f ~ 1 / sqrt(rho)
    mc_rho = monte_carlo(STRIP, {"materials.al.rho": ("uniform", (2600.0, 2800.0))}, 6,
                         np.random.default_rng(1), n_modes=1)
    rho = mc_rho.samples["materials.al.rho"].values
    np.testing.assert_allclose(mc_rho.fn_hz[:, 0], nominal[0] * np.sqrt(2700.0 / rho),
                               rtol=1e-7)


def test_monte_carlo_is_reproducible_from_the_generator():
    dist = {"materials.al.E": ("normal", (70e9, 1e9))}
    a = monte_carlo(STRIP, dist, 3, np.random.default_rng(9), n_modes=1)
    b = monte_carlo(STRIP, dist, 3, np.random.default_rng(9), n_modes=1)
    np.testing.assert_allclose(a.fn_hz, b.fn_hz, rtol=1e-10)  # ARPACK round-off
    assert list(a.parameters_dataframe().columns) == ["materials.al.E"]


def test_draw_samples_moments(rng):
    df = draw_samples({"a": ("normal", (5.0, 2.0)), "b": ("lognormal", (3.0, 0.6)),
                       "c": ("uniform", (-1.0, 1.0))}, 40_000, rng)
    tol = 5 / np.sqrt(40_000)
    assert abs(df["a"].mean() - 5.0) < 2.0 * tol and abs(df["a"].std() / 2.0 - 1) < tol
    assert abs(df["b"].mean() / 3.0 - 1) < 0.2 * tol * 3 and abs(df["b"].std() / 0.6 - 1) < 2 * tol
    assert (df["b"] > 0).all()
    assert df["c"].min() >= -1 and df["c"].max() < 1 and abs(df["c"].mean()) < tol
    assert set(DISTRIBUTION_KINDS) == {"normal", "lognormal", "uniform"}


@pytest.mark.parametrize(
    "dist, n, rng, match",
    [({"x": ("normal", (1.0, 0.1))}, 5, 42, "rng: expected a numpy.random.Generator"),
     ({"x": ("normal", (1.0, 0.1))}, 1, None, "n: expected an integer >= 2 samples, got 1"),
     ({}, 5, None, "distributions: expected a non-empty dict"),
     ({"x": ("weibull", (1.0, 2.0))}, 5, None, "unknown kind 'weibull'; expected one of normal"),
     ({"x": ("normal", 1.0)}, 5, None, r"expected \(kind, \(p1, p2\)\)"),
     ({"x": ("normal", (1.0, -0.1))}, 5, None, "normal needs a finite mean and std > 0"),
     ({"x": ("lognormal", (-1.0, 0.1))}, 5, None, "lognormal needs mean > 0, got -1.0"),
     ({"x": ("uniform", (2.0, 1.0))}, 5, None, "uniform needs low < high")],
)
def test_draw_samples_bad_inputs(dist, n, rng, match):
    rng = np.random.default_rng(0) if rng is None else rng
    with pytest.raises(ParameterError, match=match):
        draw_samples(dist, n, rng)


def test_parameter_study_bad_inputs():
    with pytest.raises(ParameterError, match=r"1-D arrays of one common length.*\(2,\).*\(3,\)"):
        parameter_study(STRIP, {"materials.al.E": [1e9, 2e9], "materials.al.rho": [1, 2, 3]})
    with pytest.raises(ParameterError, match=r"non-finite values at \(sample, path\) \[\(1, "):
        parameter_study(STRIP, {"materials.al.E": [1e9, np.nan]})
    with pytest.raises(ParameterError, match="expected a dict {path: array} or a pandas"):
        parameter_study(STRIP, [1e9, 2e9])
    with pytest.raises(ParameterError, match="need at least one path and one sample"):
        parameter_study(STRIP, {})
    with pytest.raises(ConfigError, match="materials.steel"):
        parameter_study(STRIP, {"materials.steel.E": [1e9]})
    with pytest.raises(ParameterError, match="on_error must be 'raise' or 'nan'"):
        parameter_study(STRIP, {"materials.al.E": [1e9]}, on_error="skip")
    with pytest.raises(ParameterError, match="n_modes must be an integer >= 1, got 0"):
        parameter_study(STRIP, {"materials.al.E": [1e9]}, n_modes=0)
    with pytest.raises(ParameterError, match="description: expected a structure dict"):
        parameter_study(3, {"materials.al.E": [1e9]})
    with pytest.raises(ParameterError, match="client: expected None, 'local', a scheduler"):
        parameter_study(STRIP, {"materials.al.E": [1e9]}, client=3.5)
    with pytest.raises(ParameterError, match=r"percentiles must lie in \[0, 100\]"):
        monte_carlo(STRIP, {"materials.al.E": ("normal", (70e9, 1e9))}, 3,
                    np.random.default_rng(0), percentiles=(5, 150))


def test_failing_sample_raises_with_its_values_or_becomes_nan():
    samples = {"materials.al.E": [70e9, -1e9, 71e9]}
    with pytest.raises(ConfigError, match=r"sample 1 \(materials.al.E=-1000000000.0\) failed"):
        parameter_study(STRIP, samples, n_modes=1)
    with pytest.warns(DataRepairWarning, match=r"1 of 3 samples failed .*sample 1: ConfigError"):
        ds = parameter_study(STRIP, samples, n_modes=1, on_error="nan")
    assert np.isnan(ds["fn_hz"].values[1]).all() and np.isfinite(ds["fn_hz"].values[[0, 2]]).all()
    assert ds["error"].values[1].startswith("ConfigError") and ds["error"].values[0] == ""
    mc = MonteCarloResult(samples=ds, distributions={"materials.al.E": ("normal", (1, 1))})
    assert mc.to_dataframe()["n"].tolist() == [2]


def test_histogram_figure():
    pytest.importorskip("matplotlib")
    mc = monte_carlo(STRIP, {"materials.al.E": ("normal", (70e9, 2e9))}, 8,
                     np.random.default_rng(2), n_modes=2)
    fig = plot_fn_histogram(mc, bins=5)
    assert len(fig.axes) == 2
    assert fig.axes[1].get_title().startswith("mode 2: ")
    assert sum(p.get_height() for p in fig.axes[0].patches) == 8
    fig.savefig(__import__("io").BytesIO(), format="png")
    with pytest.raises(ParameterError, match=r"modes must be 1-based numbers in 1..2, got \[3\]"):
        plot_fn_histogram(mc, modes=[3])
    with pytest.raises(ParameterError, match="expected a MonteCarloResult, got dict"):
        plot_fn_histogram({})


@pytest.fixture(scope="module")
def two_worker_client():
    distributed = pytest.importorskip("dask.distributed")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        # two worker threads in this process, talking TCP over loopback
        cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False,
                                           protocol="tcp", host="127.0.0.1",
                                           dashboard_address=":0")
    client = distributed.Client(cluster)
    yield client
    client.close()
    cluster.close()


def test_cluster_of_two_workers_gives_the_in_process_numbers(two_worker_client, tmp_path, rng):
    import mvtk.io
    import mvtk.scale
    import mvtk.signal

    client = two_worker_client
    assert len(client.nthreads()) == 2
    dist = {"materials.al.E": ("normal", (70e9, 2e9)), "materials.al.rho": ("normal", (2700, 30))}
    local = monte_carlo(STRIP, dist, 8, np.random.default_rng(3), n_modes=2)
    on_cluster = monte_carlo(STRIP, dist, 8, np.random.default_rng(3), n_modes=2,
                             client=client, batch_size=3)
    np.testing.assert_allclose(on_cluster.fn_hz, local.fn_hz, rtol=1e-10)
    assert on_cluster.samples.attrs["scheduler"].startswith("tcp://127.0.0.1:")
    # connecting by scheduler address (what a remote cluster looks like)
    by_address = parameter_study(STRIP, local.parameters_dataframe(), n_modes=2,
                                 client=client.scheduler.address)
    np.testing.assert_allclose(by_address["fn_hz"].values, local.fn_hz, rtol=1e-10)
    # a failing sample on the cluster raises the mvtk error class with its values
    with pytest.raises(ConfigError, match=r"sample 0 \(materials.al.E=-1.0\) failed"):
        parameter_study(STRIP, {"materials.al.E": [-1.0]}, n_modes=1, client=client)
    # campaign + psd computed on the cluster (the default scheduler inside the client)
    x = rng.standard_normal((2, 3, 5000))
    for i in range(2):
        mvtk.io.write(mvtk.io.time_history(x[i], 500.0, channels=["a", "b", "c"], units="V"),
                      tmp_path / f"r{i}.nc")
    ds = mvtk.scale.open_campaign(tmp_path, chunks=1200)
    p = mvtk.scale.psd(ds, nperseg=256)
    for i in range(2):
        ref = mvtk.signal.psd(mvtk.io.read(tmp_path / f"r{i}.nc"), nperseg=256)
        np.testing.assert_allclose(p.isel(record=i).values, ref.values, rtol=1e-10)


def test_description_is_not_mutated_by_a_study():
    before = copy.deepcopy(STRIP)
    parameter_study(STRIP, {"materials.al.E": [50e9]}, n_modes=1)
    assert STRIP == before


def test_jacobian_columns_in_process_and_on_the_cluster(two_worker_client):
    import mvtk.updating
    from mvtk.scale import eigen_sensitivity

    params = ["materials.al.E", "materials.al.rho", "structure.layers.0.thickness"]
    ref = mvtk.updating.eigen_sensitivity(STRIP, params, builder=mvtk.fe.build_model,
                                          n_modes=3)
    for client in (None, two_worker_client):
        out = eigen_sensitivity(STRIP, params, n_modes=3, client=client)
        assert out.paths == tuple(params)
        np.testing.assert_allclose(out.fn_hz, ref.fn_hz, rtol=1e-10)
        # to 1e-6 of each column's largest entry (eigenvector round-off on tiny entries)
        scale = np.abs(ref.d_fn_hz).max(axis=0)
        np.testing.assert_allclose(out.d_fn_hz / scale, ref.d_fn_hz / scale, atol=1e-6)
    # closed form: f ~ sqrt(E / rho) * h  ->  normalised sensitivities 1/2, -1/2, 1
    np.testing.assert_allclose(out.normalised[:, :2], [[0.5, -0.5]] * 3, atol=2e-5)
    # f1 ~ h in the thin (Kirchhoff) limit; transverse shear (L/h = 100) takes ~0.1 %
    np.testing.assert_allclose(out.normalised[0, 2], 1.0, rtol=3e-3)


def test_jacobian_rejects_a_remeshing_parameter():
    from mvtk.errors import DimensionError
    from mvtk.scale import eigen_sensitivity

    with pytest.raises(DimensionError, match="perturbing 'materials.al.E' changed the model's "):
        eigen_sensitivity(STRIP, ["materials.al.E"], n_modes=2, builder=_remeshing_builder)


def _remeshing_builder(description):
    """A builder whose mesh depends on E (as a geometry parameter's mesh would)."""
    finer = description["materials"]["al"]["E"] > 70e9
    return mvtk.fe.build_model(mvtk.fe.set_by_path(description, "mesh.nx", 9 if finer else 8))


@pytest.mark.slow
def test_client_local_starts_and_closes_a_process_cluster():
    pytest.importorskip("dask.distributed")
    samples = {"materials.al.E": [65e9, 75e9, 72e9]}
    ref = parameter_study(STRIP, samples, n_modes=2)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # port-in-use notices of the dashboard
        out = parameter_study(STRIP, samples, n_modes=2, client="local", n_workers=2)
    np.testing.assert_allclose(out["fn_hz"].values, ref["fn_hz"].values, rtol=1e-10)
    assert out.attrs["scheduler"].startswith("tcp://")


def test_reduced_path_on_the_cluster_gives_the_in_process_numbers(two_worker_client):
    """Every worker builds the same reduced basis (deterministic set-up), so a study on
    the cluster and in process agree to round-off and take the same paths."""
    from mvtk.scale._reduced import clear_cache

    rng = np.random.default_rng(8)
    samples = {"materials.al.E": rng.normal(70e9, 2e9, 16),
               "structure.layers.0.thickness": rng.normal(3e-3, 5e-5, 16)}
    clear_cache()
    local = parameter_study(STRIP, samples, n_modes=2)
    clear_cache()
    remote = parameter_study(STRIP, samples, n_modes=2, client=two_worker_client,
                             batch_size=5)
    assert local.attrs["method"] == remote.attrs["method"] == "reduced"
    assert list(remote["path"].values) == list(local["path"].values)
    assert local.attrs["reduced_note"] == "" and "reduced" in set(local["path"].values)
    np.testing.assert_allclose(remote["fn_hz"].values, local["fn_hz"].values, rtol=1e-12)
