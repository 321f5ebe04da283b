"""The README's Python tour runs as written (on a small virtual campaign)."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

README = Path(__file__).resolve().parents[1] / "README.md"


def test_readme_tour_runs(tmp_path):
    from cylfric.simulate.bench import BenchSettings, generate_campaign

    text = README.read_text(encoding="utf-8")
    tour = text.split("## The Python route", 1)[1]
    code = re.search(r"```python\n(.*?)```", tour, re.S).group(1)
    generate_campaign(
        tmp_path / "my_campaign",
        BenchSettings.clean(
            pressures_bar=(0.1, 80.0, 159.0), speeds_mm_s=(1, 3, 8, 15, 30, 60, 135)
        ),
    )
    script = "import matplotlib\nmatplotlib.use('Agg')\n" + code
    done = subprocess.run(
        [sys.executable, "-c", script], cwd=tmp_path, capture_output=True, text=True, timeout=300
    )
    assert done.returncode == 0, done.stderr[-3000:]
    assert "[[Variables]]" in done.stdout
    assert (tmp_path / "my_campaign-fit" / "datasheet.json").is_file()
    assert (tmp_path / "my_campaign-fit" / "report.html").is_file()  # what `cylfric fit` writes
