"""Memory bounds of the simulator (issue 23, item 5): the peak memory is estimated before
anything is allocated (from bytes per sample measured in fresh processes), and a simulation
above the limit is refused with the estimate, the limit and the ways out; the limit can be
raised. Small limits keep every test small."""

from __future__ import annotations

import subprocess
import sys
import time

import pytest
from typer.testing import CliRunner

from cylfric.cli import app
from cylfric.friction.literature import CANUDAS_DE_WIT_1995
from cylfric.model import FrictionModel
from cylfric.simulate import (
    BATCH_PEAK_FACTOR,
    MAX_OUTPUT_BYTES,
    PEAK_BYTES_PER_SAMPLE,
    Cylinder,
    SpringPull,
    simulate,
    simulate_batch,
)

MODEL = FrictionModel(dict(CANUDAS_DE_WIT_1995.params), pressure_law="constant")
# 1 s every 1 ms: 1001 samples x 256 bytes measured per sample
SIZE = 1001 * PEAK_BYTES_PER_SAMPLE


def test_a_simulation_above_the_limit_is_refused_with_the_size_the_limit_and_the_ways_out():
    with pytest.raises(ValueError) as caught:
        simulate(Cylinder(1.0), MODEL, SpringPull(2, 0.1), 1.0, max_output_bytes=SIZE - 1)
    message = str(caught.value)
    assert f"{SIZE / 2**30:.3g} GiB of memory at its peak (1001 samples" in message
    assert f"limit of {(SIZE - 1) / 2**30:.3g} GiB" in message
    assert "a coarser output grid (a larger dt) or a shorter duration" in message
    assert "max_output_bytes=" in message and "--max-output-gib" in message


def test_raising_the_limit_lets_the_simulation_run():
    result = simulate(Cylinder(1.0), MODEL, SpringPull(2, 0.1), 1.0, max_output_bytes=SIZE)
    assert result.time.size == 1001


def test_the_default_limit_refuses_a_long_fine_simulation_before_allocating():
    # 1e5 s every 1 ms would be 2.56e10 bytes; refused at once (nothing allocated, no run)
    start = time.perf_counter()
    with pytest.raises(
        ValueError, match=r"about 23\.8 GiB of memory at its peak .* limit of 1 GiB"
    ):
        simulate(Cylinder(1.0), MODEL, SpringPull(2, 0.1), 1e5)
    assert time.perf_counter() - start < 1.0
    assert MAX_OUTPUT_BYTES == 2**30


def test_a_limit_that_is_not_positive_is_refused():
    with pytest.raises(ValueError, match=r"max_output_bytes = 0; expected a size > 0 bytes"):
        simulate(Cylinder(1.0), MODEL, SpringPull(2, 0.1), 1.0, max_output_bytes=0)


def test_simulate_batch_counts_its_records_and_inputs_against_the_limit():
    # 3 sets x 5 signals x 101 records + 4 input rows x 1001 samples, x 8 bytes x 2.5
    size = BATCH_PEAK_FACTOR * (3 * 5 * 101 + 4 * 1001) * 8
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
    assert "23.8 GiB of memory at its peak" in done.output and "--max-output-gib" in done.output
    assert not out.exists()
    args = ["simulate", "thesis_2016", "--duration", "1s", "--out", str(out)]
    done = runner.invoke(app, [*args, "--max-output-gib", "1e-4"])  # 107 kB < 256 kB
    assert done.exit_code == 2, done.output
    done = runner.invoke(app, [*args, "--max-output-gib", "1e-3"])  # 1.07 MB
    assert done.exit_code == 0, done.output
    assert (out / "simulation.csv").is_file()


def test_the_command_counts_its_own_peak_not_only_the_outputs(tmp_path):
    # 10 s: 10001 samples x 256 bytes (CSV, figure) = 2.56 MB, above 1e-3 GiB = 1.07 MB;
    # the outputs alone (0.64 MB) were under it, and 16000 s passed the default 1 GiB
    # while peaking at 6.26 GB
    runner = CliRunner()
    out = tmp_path / "sim"
    args = ["simulate", "thesis_2016", "--duration", "10s", "--out", str(out)]
    done = runner.invoke(app, [*args, "--max-output-gib", "1e-3"])
    assert done.exit_code == 2, done.output
    assert "about 0.00238 GiB of memory at its peak" in done.output
    assert "limit of 0.001 GiB" in done.output and not out.exists()
    args = ["simulate", "thesis_2016", "--duration", "16000s", "--out", str(out)]
    done = runner.invoke(app, args)
    assert done.exit_code == 2, done.output
    assert "3.81 GiB of memory at its peak" in done.output and "limit of 1 GiB" in done.output


def test_a_huge_duration_is_refused_naming_it():
    runner = CliRunner()
    done = runner.invoke(app, ["simulate", "thesis_2016", "--duration=1e308s", "--out", "x"])
    assert done.exit_code == 2, done.output
    assert "--duration 1e308s" in done.output and "inf GiB" in done.output
    assert "unexpected" not in done.output
    with pytest.raises(ValueError, match=r"inf GiB .*duration 1e\+308 s"):
        simulate(Cylinder(1.0), MODEL, SpringPull(2, 0.1), 1e308)
    with pytest.raises(ValueError, match=r"inf GiB .*duration 1e\+308 s"):
        simulate_batch(Cylinder(1.0), MODEL, SpringPull(2, 0.1), 1e308)


def test_simulation_csv_written_in_blocks_is_the_text_of_the_data_frame(tmp_path, monkeypatch):
    from cylfric.cli import bench

    monkeypatch.setattr(bench, "CSV_ROWS", 7)
    result = simulate(Cylinder(1.0), MODEL, SpringPull(2, 0.1), 0.05)
    text = b"".join(bench._csv_blocks(result)).decode()
    assert text == result.to_pandas().to_csv(index=False)


PEAK_PROBE = """
import sys
from cylfric.friction.literature import CANUDAS_DE_WIT_1995
from cylfric.model import FrictionModel
from cylfric.simulate import Cylinder, PositionServo, simulate
model = FrictionModel(dict(CANUDAS_DE_WIT_1995.params), pressure_law="constant")
servo = PositionServo(lambda t: 0.01 * (t > 0.1), kp=2e4, kd=900, ki=2e4)
simulate(Cylinder(10.0), model, servo, 1.0)  # compiled before the big call
with open("/proc/self/clear_refs", "w") as f:  # the peak so far (imports, a compilation) is
    f.write("5")                               # forgotten: VmHWM counts from here
result = simulate(Cylinder(10.0), model, servo, float(sys.argv[1]), max_output_bytes=1e12)
status = open("/proc/self/status").read()
peak = int(status.split("VmHWM:")[1].split()[0]) * 1024
print(result.time.size, peak)
"""


def _peak(duration):
    done = subprocess.run(
        [sys.executable, "-c", PEAK_PROBE, str(duration)],
        capture_output=True,
        text=True,
        check=True,
    )
    samples, peak = map(int, done.stdout.split()[-2:])
    return samples, peak


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc/self/statm")
def test_the_estimate_bounds_the_measured_peak_of_a_servo_simulation():
    """Bytes per output sample of the peak, as the slope between two fresh processes (400 s
    and 1000 s at 1 ms): what does not grow with the output (the interpreter, the libraries,
    a compilation) cancels. A position servo holds its input grid too (about 112 bytes per
    sample measured). The peak is counted from after a first short run (a compilation peaks
    at about 660 MB, above what the runs themselves reach: /proc/self/clear_refs resets it).
    Each peak is the smaller of two processes: one that compiles inside its measured call
    (another test process rewriting the compiled cache at that moment) is not the estimate's
    subject."""
    short = min(_peak(400.0), _peak(400.0), key=lambda r: r[1])
    long_ = min(_peak(1000.0), _peak(1000.0), key=lambda r: r[1])
    assert long_[0] == 1_000_001
    slope = (long_[1] - short[1]) / (long_[0] - short[0])
    assert 0 < slope <= PEAK_BYTES_PER_SAMPLE, (slope, short, long_)
