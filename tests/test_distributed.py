"""Sweeps on a Dask cluster started here (loopback only): the same results as the local pool, and
workers that reload a mission whose file changed between two sweeps (the cache is keyed on content)."""

from pathlib import Path

import _require
import pytest
from click.testing import CliRunner

from thymio_bt.cli import main
from thymio_bt.run.sweep import LocalPool, sweep

ROOT = Path(__file__).resolve().parents[1]

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
        on_dask = sweep(f"{ROOT}/missions/maze_bonus.yaml", runs=6, executor=DaskExecutor(client))
    local = sweep(f"{ROOT}/missions/maze_bonus.yaml", runs=6, executor=LocalPool(1))
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
        main, ["sweep", f"{ROOT}/missions/square.yaml", "--runs", "4", "--dask", cluster.scheduler_address]
    )
    assert result.exit_code == 0 and "4/4 succeeded" in result.output


def test_an_unreachable_scheduler_is_a_user_error():
    result = CliRunner().invoke(
        main, ["sweep", f"{ROOT}/missions/square.yaml", "--runs", "2", "--dask", "tcp://127.0.0.1:9"]
    )
    assert result.exit_code == 2 and "cannot reach the scheduler" in result.output


def test_the_cli_grades_on_a_dask_scheduler_as_it_does_locally(cluster, tmp_path):
    """Each student's runs on a worker, still in a child process under the limits: the same grades."""
    subs = [f"{ROOT}/examples/class/ada", f"{ROOT}/examples/class/dana", f"{ROOT}/examples/class/eve"]
    outs = {}
    for where, extra in (("dask", ["--dask", cluster.scheduler_address]), ("local", ["--workers", "1"])):
        outs[where] = tmp_path / f"{where}.json"
        result = CliRunner().invoke(main, ["grade", "course_part1_2", *subs, "--out", str(outs[where]), *extra])
        assert result.exit_code == 0, result.output
    import json

    dask, local = (json.loads(outs[w].read_text())["students"] for w in ("dask", "local"))
    assert (
        [(s["name"], s["status"], s["score"]) for s in dask]
        == [(s["name"], s["status"], s["score"]) for s in local]
        == [("ada", "graded", 11.0), ("dana", "graded", 7.0), ("eve", "invalid", 0.0)]
    )
    assert [r["final_pose"] for r in dask[1]["runs"]] == [r["final_pose"] for r in local[1]["runs"]]
