"""Figure and numbers of docs/dynamic_parameters.md: sigma_0 and sigma_1 from virtual tests.

Run: ``.venv/bin/python docs/make_dynamic_figures.py`` (writes docs/img/dynamic_parameters.png
and prints the table of the page). Two bristle sets are simulated on the virtual bench with
its noise (presliding and breakaway tests at 20, 80 and 140 bar), written to files, read back
and identified with the steady-state law of the bench, as tests/test_dynamic_identify.py does.
"""

from __future__ import annotations

import math
import sys
import tempfile
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

from cylfric.identify.dynamic import dynamic_record, identify_dynamic  # noqa: E402
from cylfric.io.campaign import discover_runs, load_config, read_run  # noqa: E402
from cylfric.model import FrictionModel  # noqa: E402
from cylfric.report.dynamic import figure_dynamic  # noqa: E402
from cylfric.simulate.bench import (  # noqa: E402
    BenchSettings,
    generate_dynamic_tests,
    write_test_manifest,
)

IMG = Path(__file__).resolve().parent / "img"
MASS = 2.5  # [kg], the bench's moving mass
PRESSURES = (20.0, 80.0, 140.0)  # [bar]


def identify(folder, sigma_0, seed):
    sigma_1 = 2 * math.sqrt(sigma_0 * MASS)
    settings = BenchSettings(
        friction=FrictionModel(sigma_0=sigma_0, sigma_1=sigma_1), pressures_bar=PRESSURES, seed=seed
    )
    rows = generate_dynamic_tests(folder, settings)
    write_test_manifest(folder / "manifest.csv", rows)
    config = load_config(folder)
    records = []
    for info in discover_runs(folder, config):
        data, metadata = read_run(info, config)
        metadata["path"] = info.path.name
        records.append(dynamic_record(data, metadata))
    return sigma_1, identify_dynamic(records, FrictionModel())


def main(out=IMG):
    print(
        "| true sigma_0 [N/mm] | true sigma_1 [N*s/mm] | p [bar] | sigma_0 [N/mm] | "
        "error | sigma_1 [N*s/mm] | error |"
    )
    print("|---|---|---|---|---|---|---|")
    results = []
    for k, sigma_0 in enumerate((1e6, 1e7)):
        with tempfile.TemporaryDirectory() as tmp:
            sigma_1, result = identify(Path(tmp), sigma_0, seed=20 + k)
        results.append(result)
        for _, row in result.per_pressure.iterrows():
            s0, s1 = row["sigma_0 [N/m]"], row["sigma_1 [N*s/m]"]
            print(
                f"| {sigma_0 / 1e3:g} | {sigma_1 / 1e3:.3g} | {row['pressure [Pa]'] / 1e5:g} | "
                f"{s0 / 1e3:.4g} ± {row['sigma_0_stderr [N/m]'] / 1e3:.2g} | "
                f"{(s0 / sigma_0 - 1) * 100:+.1f} % | "
                f"{s1 / 1e3:.4g} ± {row['sigma_1_stderr [N*s/m]'] / 1e3:.2g} | "
                f"{(s1 / sigma_1 - 1) * 100:+.1f} % |"
            )
        law_0, law_1 = result.laws["sigma_0"], result.laws["sigma_1"]
        error_0 = (law_0["intercept"] / sigma_0 - 1) * 100
        error_1 = (law_1["intercept"] / sigma_1 - 1) * 100
        print(
            f"| | | law | {law_0['intercept'] / 1e3:.4g} ({law_0['law']}) | {error_0:+.1f} % "
            f"| {law_1['intercept'] / 1e3:.4g} ({law_1['law']}) | {error_1:+.1f} % |"
        )
    print()
    print("| true sigma_0 [N/mm] | p [bar] | rate [N/s] | measured [N] | simulated [N] | error |")
    print("|---|---|---|---|---|---|")
    for sigma_0, result in zip((1e6, 1e7), results, strict=True):
        for _, row in result.breakaway.iterrows():
            print(
                f"| {sigma_0 / 1e3:g} | {row['pressure [Pa]'] / 1e5:g} | "
                f"{row['force_rate [N/s]']:.0f} | {row['measured [N]']:.1f} | "
                f"{row['simulated [N]']:.1f} | {row['relative_error [-]'] * 100:+.2f} % |"
            )
    fig = figure_dynamic(results[0])
    fig.savefig(Path(out) / "dynamic_parameters.png", dpi=100)
    print(f"wrote {Path(out) / 'dynamic_parameters.png'}")


if __name__ == "__main__":
    main(*sys.argv[1:])
