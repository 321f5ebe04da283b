"""Memory bounds of the simulator (issue 23, item 5): the output size is estimated before
anything is allocated, and a simulation above the limit is refused with the estimate, the
limit and the ways out; the limit can be raised. Small limits keep every test small."""

from __future__ import annotations

import time

import pytest
from typer.testing import CliRunner

from cylfric.cli import app
from cylfric.friction.literature import CANUDAS_DE_WIT_1995
from cylfric.model import FrictionModel
from cylfric.simulate import MAX_OUTPUT_BYTES, Cylinder, SpringPull, simulate, simulate_batch

MODEL = FrictionModel(dict(CANUDAS_DE_WIT_1995.params), pressure_law="constant")
# 1 s every 1 ms: 1001 samples x 8 arrays x 8 bytes = 64064 bytes
SIZE = 1001 * 8 * 8


def test_a_simulation_above_the_limit_is_refused_with_the_size_the_limit_and_the_ways_out():
    with pytest.raises(ValueError) as caught:
        simulate(Cylinder(1.0), MODEL, SpringPull(2, 0.1), 1.0, max_output_bytes=SIZE - 1)
    message = str(caught.value)
    assert f"{SIZE / 2**30:.3g} GiB of outputs (1001 samples" in message
    assert f"limit of {(SIZE - 1) / 2**30:.3g} GiB" in message
    assert "a coarser output grid (a larger dt) or a shorter duration" in message
    assert "max_output_bytes=" in message and "--max-output-gib" in message


def test_raising_the_limit_lets_the_simulation_run():
    result = simulate(Cylinder(1.0), MODEL, SpringPull(2, 0.1), 1.0, max_output_bytes=SIZE)
    assert result.time.size == 1001


def test_the_default_limit_refuses_a_long_fine_simulation_before_allocating():
    # 1e5 s every 1 ms would be 6.4e9 bytes; refused at once (nothing allocated, no run)
    start = time.perf_counter()
    with pytest.raises(ValueError, match=r"about 5\.96 GiB of outputs .* limit of 1 GiB"):
        simulate(Cylinder(1.0), MODEL, SpringPull(2, 0.1), 1e5)
    assert time.perf_counter() - start < 1.0
    assert MAX_OUTPUT_BYTES == 2**30


def test_a_limit_that_is_not_positive_is_refused():
    with pytest.raises(ValueError, match=r"max_output_bytes = 0; expected a size > 0 bytes"):
        simulate(Cylinder(1.0), MODEL, SpringPull(2, 0.1), 1.0, max_output_bytes=0)


def test_simulate_batch_counts_its_records_and_inputs_against_the_limit():
    # 3 sets x 5 signals x 101 records + 4 input rows x 1001 samples, x 8 bytes
    size = (3 * 5 * 101 + 4 * 1001) * 8
    springs = [SpringPull(2, 0.1), SpringPull(3, 0.1), SpringPull(4, 0.1)]
    with pytest.raises(ValueError, match=r"3 sets x 5 signals x 101 records, plus 4 input"):
        simulate_batch(Cylinder(1.0), MODEL, springs, 1.0, max_output_bytes=size - 1)
    batch = simulate_batch(Cylinder(1.0), MODEL, springs, 1.0, max_output_bytes=size)
    assert batch.position.shape == (3, 101)


def test_the_command_refuses_a_long_simulation_and_takes_a_higher_limit(tmp_path):
    runner = CliRunner()
    out = tmp_path / "sim"
    args = ["simulate", "thesis_2016", "--duration", "1e5s", "--out", str(out)]
    done = runner.invoke(app, args)
    assert done.exit_code == 2, done.output
    assert "5.96 GiB of outputs" in done.output and "--max-output-gib" in done.output
    assert not out.exists()
    args = ["simulate", "thesis_2016", "--duration", "1s", "--out", str(out)]
    done = runner.invoke(app, [*args, "--max-output-gib", "1e-5"])  # 10.7 kB < 64 kB
    assert done.exit_code == 2, done.output
    done = runner.invoke(app, [*args, "--max-output-gib", "1e-4"])  # 107 kB
    assert done.exit_code == 0, done.output
    assert (out / "simulation.csv").is_file()
