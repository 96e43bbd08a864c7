"""Sweeps on local worker processes (joblib) and on a Dask cluster give the rows of one process."""

from __future__ import annotations

import os

import pytest
from click.testing import CliRunner

from moveability.cli import main
from moveability.sweep import local_cluster, read_table, restore_malloc_thresholds
from moveability.sweep.runner import run_chunk

SPEC = "examples/five-bar-paper.toml"
VARY = ["--vary", "L2=4.5:5.5:3", "--vary", "theta1.max=pi/2:pi:2", "-p", "0.25"]


def sweep(*args: str):
    result = CliRunner().invoke(main, ["sweep", SPEC, *VARY, *args])
    assert result.exit_code == 0, result.output
    return result


def results(path):
    """The rows less their timing, in a fixed order (workers finish in any order)."""
    _, rows = read_table(path)
    return sorted(
        (tuple((k, v) for k, v in row.items() if k != "seconds") for row in rows), key=repr
    )


@pytest.fixture(scope="module")
def serial(tmp_path_factory):
    out = tmp_path_factory.mktemp("serial") / "designs.csv"
    sweep("--out", str(out))
    return results(out)


def test_joblib_two_jobs_same_rows(serial, tmp_path):
    out = tmp_path / "designs.csv"
    result = sweep("--jobs", "2", "--out", str(out))
    assert "6 designs: 6 computed" in result.output
    assert results(out) == serial
    assert len(serial) == 6


def test_dask_local_cluster_same_rows(serial, tmp_path):
    out = tmp_path / "designs.parquet"
    with local_cluster(n_workers=2) as cluster:
        from distributed import Client

        result = sweep("--scheduler", cluster.scheduler_address, "--out", str(out))
        assert "6 designs: 6 computed" in result.output
        with Client(cluster, set_as_default=False) as client:
            # (functions sent to workers must be importable there: no test-module functions)
            # the workers of our cluster run without Dask's MALLOC_TRIM_THRESHOLD_,
            # and the allocator thresholds were set on them by the first design
            assert set(client.run(os.getenv, "MALLOC_TRIM_THRESHOLD_").values()) == {None}
            assert set(client.run(restore_malloc_thresholds).values()) == {True}
            # a task runs the designs of its chunk, in order
            rows = client.submit(
                run_chunk, {"mechanism": "five-bar"}, ["L2"], [(1.0,), (2.0,)], 0.5
            ).result()
            assert [row["L2"] for row in rows] == [1.0, 2.0]
            assert all(row["error"] for row in rows)
    assert results(out) == serial
    # resumed on the cluster: nothing left to do
    with local_cluster(n_workers=1) as cluster:
        result = sweep("--scheduler", cluster.scheduler_address, "--out", str(out))
        assert "6 designs: 0 computed, 6 already in" in result.output


def test_dask_default_environment_has_the_trim_threshold():
    """What the benchmark's "no fix" case measures: Dask's own worker environment."""
    with local_cluster(n_workers=1, malloc_trim=True) as cluster:
        from distributed import Client

        with Client(cluster, set_as_default=False) as client:
            assert set(client.run(os.getenv, "MALLOC_TRIM_THRESHOLD_").values()) == {"65536"}


def test_dask_task_failure_is_recorded(tmp_path, monkeypatch):
    """A task that fails on the worker (not inside an analysis) gives error rows; the sweep ends."""
    import math

    from moveability.sweep import runner

    # a task function that fails on the worker and is importable there
    monkeypatch.setattr(runner, "run_chunk", math.hypot)
    out = tmp_path / "designs.csv"
    with local_cluster(n_workers=1) as cluster:
        result = sweep("--scheduler", cluster.scheduler_address, "--out", str(out))
    assert "6 designs: 6 computed, 0 already in" in result.output and "6 failed" in result.output
    _, rows = read_table(out)
    assert len(rows) == 6
    assert all(row["error"].startswith("TypeError") for row in rows)
