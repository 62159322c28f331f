"""Sweeps on a Dask cluster started here (loopback only): the same results as the local pool, and
workers that reload a mission whose file changed between two sweeps (the cache is keyed on content)."""

import _require
import pytest
from click.testing import CliRunner

from thymio_bt.cli import main
from thymio_bt.run.sweep import LocalPool, sweep

distributed = _require.module("distributed")


@pytest.fixture(scope="module")
def cluster():
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1", dashboard_address=None
    ) as local:
        yield local


def test_a_dask_sweep_gives_the_local_pools_results(cluster):
    from thymio_bt.run.distributed import DaskExecutor

    with distributed.Client(cluster) as client:
        on_dask = sweep("missions/maze_bonus.yaml", runs=6, executor=DaskExecutor(client))
    local = sweep("missions/maze_bonus.yaml", runs=6, executor=LocalPool(1))
    assert on_dask.results == [
        {**r, "wall_time": d["wall_time"]} for r, d in zip(local.results, on_dask.results, strict=True)
    ]
    assert on_dask.success_rate == 1.0


def test_workers_read_a_mission_again_when_its_file_changes(cluster, tmp_path):
    from thymio_bt.run.distributed import DaskExecutor

    path = tmp_path / "m.yaml"
    path.write_text("maze: arena\nstart: centre\ntree:\n  MoveDistance: {distance: 10cm}\n")
    with distributed.Client(cluster) as client:
        first = sweep(path, runs=4, executor=DaskExecutor(client))
        path.write_text("maze: arena\nstart: centre\ntree:\n  MoveDistance: {distance: 20cm}\n")  # same path
        second = sweep(path, runs=4, executor=DaskExecutor(client))
    assert {round(r["final_pose"]["x"], 1) for r in first.results} == {0.7}
    assert {round(r["final_pose"]["x"], 1) for r in second.results} == {0.8}


def test_the_cli_sweeps_on_a_dask_scheduler(cluster):
    result = CliRunner().invoke(
        main, ["sweep", "missions/square.yaml", "--runs", "4", "--dask", cluster.scheduler_address]
    )
    assert result.exit_code == 0 and "4/4 succeeded" in result.output


def test_an_unreachable_scheduler_is_a_user_error():
    result = CliRunner().invoke(main, ["sweep", "missions/square.yaml", "--runs", "2", "--dask", "tcp://127.0.0.1:9"])
    assert result.exit_code == 2 and "cannot reach the scheduler" in result.output
