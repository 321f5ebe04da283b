"""The progress bar of long work (issue 27): runs per second and the time left, at a cost of
microseconds per advance."""

from __future__ import annotations

import io
import time

from rich.console import Console

import cylfric.cli.common as common


def _bar(monkeypatch):
    out = io.StringIO()
    monkeypatch.setattr(common, "err_console", Console(file=out, force_terminal=True, width=160))
    return common._progress(), out


def test_the_bar_shows_runs_per_second_and_the_time_left(monkeypatch):
    progress, out = _bar(monkeypatch)
    clock = iter(range(100_000))
    progress.get_time = lambda: float(next(clock)) / 10  # 0.1 s per call: a known rate
    task = progress.add_task("reading", total=1000, unit="runs")
    progress.start()
    for _ in range(40):
        progress.advance(task, 20)
    shown = progress.tasks[task]
    column = common._RateColumn()
    assert column.render(shown).plain.endswith(" runs/s")
    assert column.render(shown).plain.split()[0] == f"{shown.speed:,.0f}"  # rounded
    assert shown.time_remaining is not None and shown.time_remaining > 0
    progress.stop()
    assert "runs/s" in out.getvalue() and "eta" in out.getvalue()


def test_no_rate_in_the_first_second(monkeypatch):
    progress, _ = _bar(monkeypatch)
    task = progress.add_task("reading", total=10, unit="runs")
    progress.advance(task)
    assert common._RateColumn().render(progress.tasks[task]).plain == ""


def test_an_advance_costs_microseconds(monkeypatch):
    progress, _ = _bar(monkeypatch)
    task = progress.add_task("reading", total=20000, unit="runs")
    progress.start()
    t0 = time.perf_counter()
    for _ in range(20000):
        progress.advance(task)
    per_advance = (time.perf_counter() - t0) / 20000
    progress.stop()
    assert per_advance < 100e-6  # a run file takes milliseconds to read: under 5 % of that
