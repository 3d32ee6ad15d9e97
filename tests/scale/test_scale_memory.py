"""A campaign larger than the workers' memory budget is processed without a memory error."""

from __future__ import annotations

import tempfile
import warnings
from pathlib import Path

import numpy as np
import pytest

distributed = pytest.importorskip("dask.distributed")

import mvtk.io  # noqa: E402
import mvtk.scale  # noqa: E402
import mvtk.signal  # noqa: E402

N_FILES, N_CH, N_T = 10, 8, 2**20  # 10 x 64 MiB = 640 MiB of float64 samples
LIMIT = 350 * 2**20  # per worker; the whole campaign is about twice the cluster's budget


@pytest.mark.slow
def test_campaign_twice_the_memory_budget(rng):
    with tempfile.TemporaryDirectory(prefix="mvtk_scale_mem_") as tmp:
        folder = Path(tmp)
        for i in range(N_FILES):
            x = rng.standard_normal((N_CH, N_T))
            th = mvtk.io.time_history(x, 1024.0, channels=[f"c{k}" for k in range(N_CH)],
                                      units="m/s^2")
            mvtk.io.write(th, folder / f"rec{i:02d}.nc")
            if i == 3:
                first = th
        size = sum(p.stat().st_size for p in folder.iterdir())
        assert size > 1.8 * LIMIT
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            cluster = distributed.LocalCluster(
                n_workers=1, threads_per_worker=1, processes=True, memory_limit=LIMIT,
                dashboard_address=":0", host="127.0.0.1",
            )
        with cluster, distributed.Client(cluster) as client:
            pid_before = client.run(lambda: __import__("os").getpid())
            ds = mvtk.scale.open_campaign(folder / "*.nc", chunks=2**16)
            assert ds["time_history"].nbytes > 1.8 * LIMIT
            p = mvtk.scale.psd(ds, nperseg=2048)
            # the worker was never killed and restarted for exceeding its limit
            assert client.run(lambda: __import__("os").getpid()) == pid_before
            worker = next(iter(client.scheduler_info()["workers"].values()))
            assert worker["memory_limit"] == LIMIT
        assert p.sizes["record"] == N_FILES and np.isfinite(p.values).all()
        ref = mvtk.signal.psd(first, nperseg=2048)
        np.testing.assert_allclose(p.isel(record=3).values, ref.values, rtol=1e-10)
