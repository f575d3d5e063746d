"""The same study through a Dask cluster gives the same rows as on local processes."""

import json
import os
from pathlib import Path

import numpy as np
import pytest

from groupfit.cli import main
from groupfit.sweep.store import StudyStore

distributed = pytest.importorskip("dask.distributed")

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "datasets" / "synthetic_cycle.csv"
STUDY = """
[data]
path = "{data}"
[grid]
p = [0, 2, 3]
objective = ["sae"]
search = ["exact", "ga"]
sensors = ["all", {{select = "lasso", k = 2}}]
[ga]
seed = [1]
max_generations = [25]
"""


def rows_by_hash(db):
    with StudyStore(db) as store:
        return {row["run_hash"]: row for row in store.rows()}


@pytest.mark.slow
def test_dask_cluster_rows_equal_local_rows(tmp_path):
    config = tmp_path / "study.toml"
    config.write_text(STUDY.format(data=DATA.as_posix()), encoding="utf-8")
    local_db, dask_db = tmp_path / "local.sqlite", tmp_path / "dask.sqlite"
    assert main(["sweep", str(config), "--db", str(local_db), "--workers", "2", "--quiet"]) == 0

    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        status = main(
            [
                "sweep",
                str(config),
                "--db",
                str(dask_db),
                "--scheduler",
                cluster.scheduler_address,
                "--quiet",
                "--json",
                str(tmp_path / "dask.json"),
            ]
        )
        assert status == 0
        result = json.loads((tmp_path / "dask.json").read_text())
        assert result["executor"] == "dask" and result["failed"] == 0 and result["done"] == result["total"] == 10
        workers = set(cluster.scheduler_info["workers"])

    local, remote = rows_by_hash(local_db), rows_by_hash(dask_db)
    assert set(local) == set(remote) and len(local) == 10
    for run_hash, row in remote.items():
        assert row["status"] == "done"
        assert row["breaks"] == local[run_hash]["breaks"]
        assert row["sensors"] == local[run_hash]["sensors"]
        assert row["objective"] == pytest.approx(local[run_hash]["objective"], rel=1e-12)
        np.testing.assert_allclose(row["coefficients"], local[run_hash]["coefficients"], rtol=1e-9)
    # the runs ran on the cluster's worker processes, not in this one
    pids = {row["worker"].split(":")[1] for row in remote.values()}
    assert str(os.getpid()) not in pids and len(workers) == 2
