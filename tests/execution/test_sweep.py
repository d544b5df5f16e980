"""Sweeps: each row equals the run it stands for, upstream work is shared, errors come first."""

from __future__ import annotations

import csv
import xml.etree.ElementTree as ET
from concurrent.futures import Future
from pathlib import Path
from typing import Any

import pytest

import graphvision as gv
from graphvision.execution.sweep import sweep
from graphvision.views.sweep_page import sweep_plot_svg

LINE_FIT = Path(__file__).parents[2] / "pipelines" / "line_fit.yaml"
GRID = {"robust.threshold": [1.0, 3.0, 9.0], "robust.confidence": [0.9, 0.99]}


class CountingExecutor(gv.SyncExecutor):
    """Runs in the calling thread and counts the nodes it is handed."""

    def __init__(self) -> None:
        self.submitted = 0

    def submit(self, fn: Any, /, *args: Any) -> Future:
        self.submitted += 1
        return super().submit(fn, *args)


@pytest.fixture(scope="module")
def line_sweep() -> gv.SweepResult:
    return sweep(gv.load_pipeline(LINE_FIT), GRID, executor="sync")


def test_each_row_equals_a_single_run_with_those_values(line_sweep) -> None:
    graph = gv.load_pipeline(LINE_FIT)
    assert len(line_sweep.rows) == 6
    for row in line_sweep.rows[::2]:
        overrides = {key: row[key] for key in GRID}
        alone = gv.run(graph, overrides=overrides, executor="sync").outputs
        assert row["status"] == "ok"
        assert row["error_ransac"] == alone["error_ransac"]
        assert row["error_lstsq"] == alone["error_lstsq"]


def test_nodes_upstream_of_the_grid_run_once(line_sweep) -> None:
    computed: dict[str, int] = {}
    for record in line_sweep.records:
        for node in record.nodes:
            computed[node.name] = computed.get(node.name, 0) + (node.status == "computed")
    assert computed["points"] == computed["lstsq"] == computed["total"] == 1
    assert computed["robust"] == computed["error_ransac"] == 6
    # later runs load points and the two unswept errors; lstsq and total are not even read
    assert [row["cached"] for row in line_sweep.rows][1:] == [3] * 5


def test_csv_has_a_row_per_combination_and_every_scalar_output(line_sweep, tmp_path) -> None:
    path = line_sweep.write_csv(tmp_path / "sweep.csv")
    with path.open() as stream:
        rows = list(csv.DictReader(stream))
    assert len(rows) == 6
    assert {"robust.threshold", "robust.confidence", "error_ransac", "status"} <= set(rows[0])
    assert [float(r["robust.threshold"]) for r in rows] == [1.0, 1.0, 3.0, 3.0, 9.0, 9.0]


def test_plot_has_a_chart_per_parameter_and_a_line_per_other_combination(line_sweep) -> None:
    root = ET.fromstring(sweep_plot_svg(line_sweep, "error_ransac"))
    charts = root.findall("{http://www.w3.org/2000/svg}g")
    assert len(charts) == 2
    lines = [len(chart.findall("{http://www.w3.org/2000/svg}polyline")) for chart in charts]
    assert lines == [2, 3]  # threshold chart: one line per confidence; and the reverse
    with pytest.raises(gv.PipelineError, match=r"no scalar output 'error_ransc' \(did you mean"):
        sweep_plot_svg(line_sweep, "error_ransc")


@pytest.mark.parametrize(
    ("grid", "message"),
    [
        (
            {"robst.threshold": [1.0]},
            r"grid robst.threshold: no node 'robst' \(did you mean 'robust'",
        ),
        ({"robust.treshold": [1.0]}, r"unknown parameter 'treshold'.*\(did you mean 'threshold'"),
        ({"robust.threshold": [1.0, "wide"]}, r"invalid value 'wide'.*threshold='wide'"),
        ({"robust.threshold": []}, r"grid robust.threshold: has no values"),
        ({"robust.threshold": [1.0, 3.0, 1.0]}, r"grid robust.threshold: gives 1.0 twice"),
        ({"robust.threshold": [3, 3.0]}, r"grid robust.threshold: gives 3 and 3.0, one value"),
        ({}, r"the grid is empty"),
    ],
)
def test_a_bad_grid_is_refused_before_anything_runs(grid, message) -> None:
    executor = CountingExecutor()
    with pytest.raises(gv.PipelineError, match=message):
        sweep(gv.load_pipeline(LINE_FIT), grid, executor=executor)
    assert executor.submitted == 0


def test_values_given_twice_and_refused_values_are_named_in_one_error() -> None:
    grid = {"robust.threshold": [1.0, 1.0, "wide"], "robust.confidence": [0.9, 7.0, 0.9]}
    with pytest.raises(gv.PipelineError) as refused:
        sweep(gv.load_pipeline(LINE_FIT), grid, executor=CountingExecutor())
    message = str(refused.value)
    assert "grid robust.threshold: gives 1.0 twice" in message
    assert "grid robust.confidence: gives 0.9 twice" in message
    assert "threshold='wide'" in message and "confidence=7.0" in message


def test_on_row_hears_every_combination_in_order() -> None:
    heard: list[tuple[int, int, float]] = []
    grid = {"robust.threshold": [1.0, 3.0]}
    result = sweep(
        gv.load_pipeline(LINE_FIT),
        grid,
        executor="sync",
        on_row=lambda n, total, row: heard.append((n, total, row["robust.threshold"])),
    )
    assert heard == [(1, 2, 1.0), (2, 2, 3.0)] and len(result.rows) == 2


def test_the_sweep_command_writes_its_files_and_a_line_per_combination(capsys, tmp_path) -> None:
    from graphvision.cli import main

    out = tmp_path / "sweep"
    args = ["sweep", str(LINE_FIT), "--no-cache", "-d", str(out), "--progress"]
    status = main([*args, "--grid", "robust.threshold=1,3", "--plot", "error_ransac"])
    err = capsys.readouterr().err
    assert status == 0, err
    assert "[1/2 combinations] robust.threshold=1 ok" in err
    assert "2 of 2 combinations succeeded" in err
    rows = list(csv.DictReader((out / "sweep.csv").open()))
    assert [row["robust.threshold"] for row in rows] == ["1", "3"]
    assert (out / "sweep_error_ransac.svg").is_file() and (out / "sweep.html").is_file()
    assert main([*args, "--no-progress", "--grid", "robust.threshold=2"]) == 0
    assert "combinations]" not in capsys.readouterr().err


def test_an_interrupted_sweep_keeps_the_rows_done(capsys, tmp_path, monkeypatch) -> None:
    """Ctrl-C after the first combination: the exception is still a KeyboardInterrupt,
    and it carries the row done with the others marked 'not run'; the command writes
    them to sweep.csv and exits 130."""
    from graphvision.cli import main

    def stop_after_one(number: int, total: int, row: dict[str, Any]) -> None:
        if number == 1:
            raise KeyboardInterrupt

    grid = {"robust.threshold": [1.0, 3.0, 9.0]}
    with pytest.raises(KeyboardInterrupt) as stopped:
        sweep(gv.load_pipeline(LINE_FIT), grid, executor="sync", on_row=stop_after_one)
    assert isinstance(stopped.value, gv.SweepInterrupted)
    rows = stopped.value.result.rows
    assert [row["status"] for row in rows] == ["ok", "not run", "not run"]
    assert rows[0]["error_ransac"] != "" and rows[2]["robust.threshold"] == 9.0

    calls = iter([None, KeyboardInterrupt])

    def interrupt_second(self, *args: Any, **kwargs: Any) -> None:
        if next(calls) is KeyboardInterrupt:
            raise KeyboardInterrupt

    monkeypatch.setattr("graphvision.views.progress.FileProgress.finished", interrupt_second)
    out = tmp_path / "sweep"
    args = ["sweep", str(LINE_FIT), "--no-cache", "-d", str(out), "--progress"]
    assert main([*args, "--grid", "robust.threshold=1,3,9"]) == 130
    assert "combinations done so far are in" in capsys.readouterr().err
    statuses = [row["status"] for row in csv.DictReader((out / "sweep.csv").open())]
    assert statuses == ["ok", "ok", "not run"]
    assert "not run" in (out / "sweep.html").read_text()


COINS = Path(__file__).parents[2] / "pipelines" / "coins.yaml"


def test_a_grid_too_large_is_refused_before_anything_is_made() -> None:
    grid = {"binary.window": list(range(3, 403, 2)), "binary.k": [0.0] * 100, "disk.size": [3] * 2}
    with pytest.raises(gv.PipelineError, match=r"40,000 combinations \(200 × 100 × 2\); at most"):
        sweep(gv.load_pipeline(COINS), grid, executor="sync")


def test_a_params_key_whose_every_use_is_swept_is_refused() -> None:
    grid = {"params.window": [31, 51], "binary.window": [11, 21]}
    refused = r"grid params.window: has no effect: .*binary.window"
    with pytest.raises(gv.PipelineError, match=refused):
        sweep(gv.load_pipeline(COINS), grid, executor="sync")


def test_a_grid_value_that_is_not_a_list_is_refused() -> None:
    with pytest.raises(
        gv.PipelineError, match=r"grid binary.window: needs a list of values, got '31,51'"
    ):
        sweep(gv.load_pipeline(COINS), {"binary.window": "31,51"}, executor="sync")


def test_outputs_limit_each_run_and_the_table() -> None:
    result = sweep(
        gv.load_pipeline(LINE_FIT), {"robust.threshold": [1.0, 3.0]}, outputs=["error_ransac"]
    )
    assert result.outputs == ["error_ransac"]
    assert all(record.count("computed") < 6 for record in result.records)  # not every node


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--grid", "robust.threshold=5"], "--grid robust.threshold is given twice"),
        (["-s", "robust.threshold=5"], "robust.threshold is both swept (--grid) and set (--set)"),
        (["--plot", "points"], "--plot points: not a scalar output of the sweep"),
        (["--plot", "error_ransak"], "did you mean 'error_ransac'"),
        (["--grid", "robust.confidence=0.9,,0.99"], "=0.9,,0.99: an empty value (give V1,V2,...)"),
        (["--grid", "robust.confidence=0.9,"], "=0.9,: an empty value (give V1,V2,...)"),
        (["--grid", "robust.confidence="], "--grid robust.confidence=: an empty value"),
    ],
)
def test_sweep_command_mistakes_are_refused_before_anything_runs(
    capsys, tmp_path, extra, message
) -> None:
    from graphvision.cli import main

    out = tmp_path / "sweep"
    args = ["sweep", str(LINE_FIT), "--no-cache", "-d", str(out), "--grid", "robust.threshold=1,3"]
    assert main([*args, *extra]) == 2
    assert message in capsys.readouterr().err
    assert not (out / "sweep.csv").exists()


def test_a_sweep_never_replaces_a_users_files_and_removes_its_own_stale_ones(
    capsys, tmp_path
) -> None:
    from graphvision.cli import main

    out = tmp_path / "sweep"
    out.mkdir()
    (out / "sweep.csv").write_text("my own table")
    args = ["sweep", str(LINE_FIT), "--no-cache", "-d", str(out), "--grid", "robust.threshold=1,3"]
    assert main(args) == 2
    assert "holds sweep.csv, and no sweep.json says a sweep wrote it" in capsys.readouterr().err
    assert (out / "sweep.csv").read_text() == "my own table"
    (out / "sweep.csv").unlink()
    assert main([*args, "--plot", "error_ransac"]) == 0
    assert (out / "sweep_error_ransac.svg").is_file()
    assert main(args) == 0  # no plot this time: the old chart goes
    assert not (out / "sweep_error_ransac.svg").exists()
    (out / "sweep.json").write_text("{}")
    assert main(args) == 2
    assert "is not a graphvision sweep manifest" in capsys.readouterr().err


def test_a_bad_grid_value_is_named_as_the_grid_it_came_from() -> None:
    with pytest.raises(gv.PipelineError) as caught:
        sweep(gv.load_pipeline(COINS), {"binary.window": [31, 52]}, executor="sync")
    (problem,) = caught.value.problems
    assert problem.where == "--grid binary.window=52" and "must be odd" in problem.message


def test_every_bad_grid_value_is_named_at_once_each_once() -> None:
    """A sweep names every refused value, as ``validate`` names every problem; a bad first
    value (part of every combination checked) is named once, not once per check."""
    grid = {"binary.window": [30, 31, 52, "wide"], "binary.k": [0.2, "low"]}
    with pytest.raises(gv.PipelineError) as caught:
        sweep(gv.load_pipeline(COINS), grid, executor="sync")
    named = sorted(p.where for p in caught.value.problems)
    assert named == [
        "--grid binary.k='low'",
        "--grid binary.window='wide'",
        "--grid binary.window=30",
        "--grid binary.window=52",
    ]
