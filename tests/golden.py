"""The fixed campaigns of the before/after test (issue 24: behaviour unchanged) and the
normalised digests of everything ``cylfric fit`` writes for them.

``python tests/golden.py`` rewrites ``tests/data/golden_outputs.json``: do that only when an
output is meant to change, and say so in the commit.
"""

from __future__ import annotations

import hashlib
import io
import json
import sys
import zipfile
from pathlib import Path

GOLDEN = Path(__file__).parent / "data" / "golden_outputs.json"
CAMPAIGNS = {
    # name: (BenchSettings keywords, extra `cylfric fit` arguments)
    "camp": (
        {
            "pressures_bar": (10.0, 50.0, 100.0, 150.0),
            "speeds_mm_s": (1, 2, 5, 10, 20, 50, 100),
            "seed": 3,
        },
        ["--export", "fmu,matlab,modelica,simscape,hopsan"],
    ),
    "sparse": (
        {"pressures_bar": (20.0, 80.0), "speeds_mm_s": (3, 30, 90), "seed": 5},
        ["--no-report", "--per-direction"],
    ),
}
_SKIP = {".svg"}  # matplotlib writes an id and a date into each SVG


def _normalised(data: bytes, campaign: Path) -> bytes:
    text = data.decode("utf-8", "surrogateescape")
    text = text.replace(str(campaign), "<campaign>")
    return text.encode("utf-8", "surrogateescape")


def _datasheet(data: bytes, campaign: Path) -> dict:
    sheet = json.loads(_normalised(data, campaign))
    sheet.pop("created", None)
    return sheet


def digests(out: Path, campaign: Path) -> dict:
    """Relative path -> sha256 of every output (SVG left out; the creation date removed)."""
    result = {}
    for path in sorted(p for p in out.rglob("*") if p.is_file()):
        name = path.relative_to(out).as_posix()
        if path.suffix in _SKIP or name.startswith(".cylfric"):
            continue
        data = path.read_bytes()
        if path.name == "datasheet.json":
            data = json.dumps(_datasheet(data, campaign), sort_keys=True).encode()
        elif path.suffix == ".fmu":
            with zipfile.ZipFile(io.BytesIO(data)) as archive:
                # the model's equations and values; the GUID and datasheet carry the date
                data = archive.read("sources/cylfric_params.h")
        elif path.suffix in (".html", ".csv", ".m", ".mo", ".hcom", ".md", ".txt", ".json"):
            data = _normalised(data, campaign)
            if path.suffix == ".html":
                import re

                data = re.sub(rb"\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d\+00:00", b"<created>", data)
        result[name] = hashlib.sha256(data).hexdigest()
    return result


def run(root: Path) -> dict:
    """Generate and fit every campaign under ``root``; {campaign: {file: digest}, ...}."""
    from typer.testing import CliRunner

    from cylfric.cli import app
    from cylfric.simulate.bench import BenchSettings, generate_campaign

    runner = CliRunner()
    found = {}
    for name, (settings, arguments) in CAMPAIGNS.items():
        campaign = root / name
        generate_campaign(campaign, BenchSettings.clean(**settings))
        out = root / f"{name}-fit"
        result = runner.invoke(app, ["fit", str(campaign), "--out", str(out), *arguments])
        assert result.exit_code == 0, result.output
        found[name] = digests(out, campaign)
        found[f"{name}/datasheet"] = _datasheet((out / "datasheet.json").read_bytes(), campaign)
    return found


if __name__ == "__main__":
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        GOLDEN.write_text(json.dumps(run(Path(tmp)), indent=1, sort_keys=True) + "\n")
    print(f"wrote {GOLDEN}", file=sys.stderr)
