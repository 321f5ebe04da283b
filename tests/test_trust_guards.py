"""Guards of issue 11 found missing by the hostile check (F11, F6, F7): --strict names every
flagged run and promises no file it does not write; simulate and the band warn outside the
validity ranges (raise with strict=True) and the CLI prints each warning once as a note;
unit prefixes are case-sensitive (M is mega, never read as milli); impossible --fix values
are refused naming the option."""

from __future__ import annotations

import json
import math
import re
import warnings

import numpy as np
import pandas as pd
import pytest
from hypothesis import given
from hypothesis import strategies as st
from typer.testing import CliRunner

from cylfric.cli import app
from cylfric.friction.literature import THESIS_2016
from cylfric.model import FrictionModel, ValidityWarning
from cylfric.pipeline import STRICT_SHOWN, _strict_message
from cylfric.simulate import Cylinder, SpringPull, simulate
from cylfric.simulate.bench import BenchSettings, generate_campaign
from cylfric.units import _MILLI_AT, UNITS, UnitError, parse_quantity

runner = CliRunner()
VALIDITY = {  # the thesis campaign's ranges
    "pressure_min": 1e5,
    "pressure_max": 159e5,
    "velocity_min": 1e-3,
    "velocity_max": 0.1,
}


def _model():
    return FrictionModel(dict(THESIS_2016.coefficients), validity=VALIDITY)


def _flat(text: str) -> str:
    return " ".join(text.split())


# ---------------------------------------------------------------- F11: --strict
def test_strict_names_every_flagged_run_and_writes_nothing(tmp_path):
    folder = tmp_path / "campaign"
    generate_campaign(
        folder, BenchSettings.clean(pressures_bar=(10.0, 100.0), speeds_mm_s=(2, 5, 10, 20, 50))
    )
    names = sorted(p.name for p in folder.glob("run_*.txt"))
    flagged = [names[1], names[7]]
    for name in flagged:  # position in mm labelled m: 1000 times the nominal speed
        path = folder / name
        path.write_text(path.read_text().replace("s\tmm\tkN", "s\tm\tkN"))
    out = tmp_path / "out"
    result = runner.invoke(app, ["fit", str(folder), "--out", str(out), "--no-report", "--strict"])
    assert result.exit_code == 2, result.output
    message = _flat(result.output)
    assert "--strict: the data-quality gate flags 2 run(s) (2 by speed)" in message
    for name in flagged:
        assert f"{name}: measured speed" in message
    assert "excluded.csv" not in message  # nothing is written, so no file is promised
    assert "Nothing was written" in message
    assert not out.exists()


def test_strict_names_the_first_runs_and_counts_the_rest():
    excluded = pd.DataFrame(
        {
            "file": [f"run_{i:03d}.txt" for i in range(STRICT_SHOWN + 3)],
            "check": ["speed"] * (STRICT_SHOWN + 1) + ["metadata"] * 2,
            "reason": [f"reason {i}" for i in range(STRICT_SHOWN + 3)],
        }
    )
    message = _strict_message(excluded)
    assert message.startswith(
        f"--strict: the data-quality gate flags {STRICT_SHOWN + 3} run(s) "
        f"({STRICT_SHOWN + 1} by speed, 2 by metadata): run_000.txt: reason 0; "
    )
    assert f"run_{STRICT_SHOWN - 1:03d}.txt: reason {STRICT_SHOWN - 1}; and 3 more run(s)." in (
        message
    )
    assert f"run_{STRICT_SHOWN:03d}.txt" not in message


# ---------------------------------------------------------------- F6: simulate guards
def test_simulate_warns_when_the_speed_leaves_the_validity_range():
    model = _model()
    drive = SpringPull(stiffness=2e4, speed=0.5)  # pulls to about 0.5 m/s, range ends at 0.1
    with pytest.warns(ValidityWarning, match=r"the simulated speed reaches \d+(\.\d+)? mm/s "):
        result = simulate(Cylinder(mass=10.0), model, drive, 0.5, pressure_a=80e5)
    assert np.max(np.abs(result.states["velocity"])) > 0.1
    with pytest.raises(ValueError, match=r"beyond the model's validity speeds 1-100 mm/s"):
        simulate(Cylinder(mass=10.0), model, drive, 0.5, pressure_a=80e5, strict=True)
    with warnings.catch_warnings():  # a slow pull stays inside: no warning at all
        warnings.simplefilter("error")
        simulate(Cylinder(mass=10.0), model, SpringPull(2e4, 0.02), 0.5, pressure_a=80e5)


def test_band_warns_outside_the_validity_range_like_friction():
    model = FrictionModel.from_datasheet(_fitted_sheet())
    with pytest.warns(ValidityWarning, match=r"outside the validity ranges"):
        model.band(0.02, 300e5)
    with pytest.raises(ValueError, match=r"outside the validity ranges"):
        model.band(0.02, 300e5, strict=True)
    with pytest.raises(ValueError, match=r"outside the validity ranges"):
        model.prediction_band(0.5, 80e5, strict=True)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        lower, upper = model.band(0.02, 80e5)
    assert lower < model.friction(0.02, 80e5) < upper


def _fitted_sheet():
    """A small identified model (with covariance) as a datasheet dict."""
    from cylfric.identify import identify

    rng = np.random.default_rng(0)
    speeds = np.array([1, 2, 4, 7, 10, 15, 25, 40, 70, 100]) * 1e-3
    v, p = (a.ravel() for a in np.meshgrid(speeds, np.array([10, 80, 159]) * 1e5))
    f = _model().friction(v, p)  # the thesis laws (Table 4.5), inside the ranges
    points = pd.DataFrame(
        {"velocity [m/s]": v, "pressure [Pa]": p, "friction [N]": f + rng.normal(0, 0.3, v.size)}
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return identify(points, sensitivity=False).model.to_datasheet()


def test_cli_simulate_prints_each_warning_once_as_a_note(tmp_path):
    sheet = tmp_path / "datasheet.json"
    sheet.write_text(json.dumps(_model().to_datasheet()))
    args = ["simulate", str(sheet), "--pressure", "300bar", "--duration", "0.2s"]
    result = runner.invoke(app, [*args, "--out", str(tmp_path / "sim")])
    assert result.exit_code == 0, result.output
    output = _flat(result.output)
    assert output.count("note: 1 of 1 point(s) outside the validity ranges 1-159 bar") == 1
    assert "(pressures only; given 300 bar)" in output
    assert "ValidityWarning" not in output and ".py:" not in output


# ---------------------------------------------------------------- F7: unit prefixes
@pytest.mark.parametrize(
    ("text", "dimension", "written"),
    [
        ("10 Mm/s", "velocity", "mm/s"),
        ("10 Mm", "length", "mm"),
        ("10 Ms", "time", "ms"),
        ("1 Mbar", "pressure", "mbar"),
        ("0.3 N*s/Mm", "damping", "N*s/mm"),
    ],
)
def test_an_upper_case_M_is_mega_and_refused_never_milli(text, dimension, written):
    with pytest.raises(
        UnitError, match=rf"M is the mega prefix .* write {re.escape(written)} for the milli"
    ):
        parse_quantity(text, dimension)


@pytest.mark.parametrize(
    ("text", "dimension", "expected"),
    [
        ("10 mm/s", "velocity", 0.01),
        ("3 M/S", "velocity", 3.0),  # metre in capitals: no prefix
        ("2 MIN", "time", 120.0),
        ("1 CM", "length", 0.01),
        ("5 MPa", "pressure", 5e6),  # a mega unit cylfric reads
        ("5 mbar", "pressure", 500.0),
        # all capitals carry no case (an export's units row): the only unit there is
        ("10 MM/S", "velocity", 0.01),
        ("10 MM", "length", 0.01),
        ("2 MS", "time", 2e-3),
        ("5 MBAR", "pressure", 500.0),
        ("5 MPA", "pressure", 5e6),
        ("5 KN", "force", 5e3),
    ],
)
def test_the_case_of_units_without_a_milli_prefix_is_free(text, dimension, expected):
    assert parse_quantity(text, dimension) == pytest.approx(expected, rel=1e-12)


@given(
    key=st.sampled_from(sorted(_MILLI_AT)),
    number=st.floats(min_value=1e-6, max_value=1e6, allow_nan=False),
)
def test_no_mega_spelling_of_a_milli_unit_is_read(key, number):
    from cylfric.units import UNITS

    dimension = UNITS[key][0]
    mega = "".join("M" if i in _MILLI_AT[key] else c for i, c in enumerate(key))
    with pytest.raises(UnitError, match="M is the mega prefix"):
        parse_quantity(f"{number!r} {mega}", dimension)
    assert parse_quantity(f"{number!r} {key}", dimension) == pytest.approx(
        number * UNITS[key][1], rel=1e-12
    )


@pytest.mark.parametrize(
    ("text", "dimension", "written"),
    [
        ("5 mM/s", "velocity", "mm/s"),  # was read as 5 mm/s (0.005 m/s)
        ("5 mm/S", "velocity", "mm/s"),
        ("5 mS", "time", "ms"),  # millisiemens
        ("5 N*S/mm", "damping", "N*s/mm"),
        ("5 mM²/s", "kinematic viscosity", "mm²/s"),
    ],
)
def test_a_mixed_case_milli_unit_is_refused_naming_the_spelling_to_write(text, dimension, written):
    unit = text.split()[1]
    with pytest.raises(
        UnitError,
        match=rf"^unit {re.escape(repr(unit))} is ambiguous: in a unit the case of m and s "
        rf"carries the meaning .* write {re.escape(written)} \(or "
        rf"{re.escape(written.upper())} in all capitals, as bench exports do\)$",
    ):
        parse_quantity(text, dimension)


@pytest.mark.parametrize(
    ("text", "dimension", "written"),
    [
        ("5 Mm/S", "velocity", "mm/s"),  # the milli spelling it names is one that is read
        ("5 N*s/MM", "damping", "N*s/mm"),
        ("5 Mm2/s", "kinematic viscosity", "mm2/s"),  # was read as mm2/s: a factor 1e18
        ("5 MSec", "time", "mSec"),
    ],
)
def test_a_mega_spelling_names_a_milli_spelling_that_is_read(text, dimension, written):
    with pytest.raises(UnitError, match=rf"write {re.escape(written)} for the milli unit"):
        parse_quantity(text, dimension)
    assert parse_quantity(f"5 {written}", dimension) == pytest.approx(
        5 * UNITS[written.lower()][1], rel=1e-12
    )


@pytest.mark.parametrize(
    ("text", "dimension", "expected"),
    [  # spellings of real exports and of the readers' tests (Sec mm kN, KN, MPA, MM_S, ...)
        ("2 Sec", "time", 2.0),
        ("2 SEC", "time", 2.0),
        ("2 mSec", "time", 2e-3),  # sec is a word, not the symbol S
        ("2 msec", "time", 2e-3),
        ("5 kN", "force", 5e3),
        ("5 kn", "force", 5e3),  # k/K: no milli or mega to swap
        ("5 Bar", "pressure", 5e5),
        ("5 mBar", "pressure", 500.0),  # b, a, r carry no prefix
        ("5 barg", "pressure", 5e5),
        ("5 psi", "pressure", 6894.757293168 * 5),
        ("5 mm_s", "velocity", 5e-3),
        ("5 MM_S", "velocity", 5e-3),
        ("5 mm/Min", "velocity", 5e-3 / 60),
        ("5 n/mm", "stiffness", 5e3),
        ("5 N·s/mm", "damping", 5e3),
        ("5 N*S/MM", "damping", 5e3),
        ("5 cSt", "kinematic viscosity", 5e-6),
        ("5 MM2/S", "kinematic viscosity", 5e-6),
    ],
)
def test_spellings_in_use_are_still_read(text, dimension, expected):
    assert parse_quantity(text, dimension) == pytest.approx(expected, rel=1e-12)


@given(
    key=st.sampled_from(sorted(k for k in UNITS if any(c.isalpha() for c in k))),
    upper=st.lists(st.booleans(), min_size=8, max_size=8),
    number=st.floats(min_value=1e-6, max_value=1e6, allow_nan=False),
)
def test_no_case_variant_swaps_milli_and_mega(key, upper, number):
    """Every case variant of every unit is either read as that unit or refused: never as a
    unit a factor of 10^3 to 10^18 away. Refused are exactly the variants of a milli unit
    that are not all capitals and write M or S outside the words sec and min."""
    variant = "".join(  # (an upper-case µ is Greek capital mu: no unit, not tried)
        c.upper() if up and c.isascii() else c for c, up in zip(key, upper * 2, strict=False)
    )
    dimension, factor = UNITS[key]
    mixed = (
        key in _MILLI_AT
        and not variant.isupper()
        and re.search("[MS]", re.sub("sec|min", "", variant, flags=re.IGNORECASE))
    )
    if mixed:
        with pytest.raises(UnitError, match=rf"^unit {re.escape(repr(variant))}[: ]"):
            parse_quantity(f"{number!r} {variant}", dimension)
    else:
        assert parse_quantity(f"{number!r} {variant}", dimension) == pytest.approx(
            number * factor, rel=1e-12
        )


@pytest.mark.parametrize(
    ("option", "expected"),
    [
        (
            "v_r=0mm/s",
            "--fix 'v_r=0mm/s': v_r = 0 mm/s is out of range; expected 0.01 to 10000 mm/s",
        ),
        ("v_r=10Mm/s", "--fix 'v_r=10Mm/s': unit 'Mm/s': M is the mega prefix"),
        ("alpha=0", "--fix 'alpha=0': alpha = 0 is out of range; expected 0.2 to 5"),
        ("F_c=-3N", "--fix 'F_c=-3N': F_c = -3 N is out of range; expected 0 N or more"),
        ("F_c=70N,F_s=50N", "--fix F_s=50N is below --fix F_c=70N; expected F_s >= F_c"),
    ],
)
def test_impossible_fixed_values_exit_2_naming_the_option(tmp_path, option, expected):
    args = ["fit", str(tmp_path), "--out", str(tmp_path / "out"), "--no-report", "--fix", option]
    result = runner.invoke(app, args)
    assert result.exit_code == 2
    assert expected in _flat(result.output)
    assert "Traceback" not in result.output


def test_cli_simulate_names_the_datasheet_when_the_extrapolated_law_is_unphysical(tmp_path):
    sheet = _model().to_datasheet()
    # sigma_2 falls with pressure: 500 N*s/m at 0 bar, 102.5 at 159 bar (valid), -250 at 300
    sheet["parameters"]["sigma_2"] = {"intercept": 500.0, "slope": -500.0 / 200e5}
    path = tmp_path / "falling.json"
    path.write_text(json.dumps(sheet))
    args = ["simulate", str(path), "--pressure", "300bar", "--duration", "0.2s"]
    result = runner.invoke(app, [*args, "--out", str(tmp_path / "sim")])
    assert result.exit_code == 2
    assert (
        "falling.json: the friction model cannot be simulated: parameter sigma_2 = -250.0 is "
        "out of range; expected >= 0 N*s/m"
    ) in _flat(result.output)
    assert "np.float64" not in result.output


def test_simulate_batch_warns_once_for_the_sets_outside_the_validity_ranges():
    from cylfric.simulate import simulate_batch

    model = _model()
    drives = [SpringPull(2e4, 0.02), SpringPull(2e4, 0.5), SpringPull(2e4, 0.02)]
    pressures = [80e5, 80e5, 300e5]  # set 1 runs too fast, set 2 at too high a pressure
    with pytest.warns(ValidityWarning) as caught:
        simulate_batch(Cylinder(mass=10.0), model, drives, 0.5, pressures=pressures)
    messages = [str(w.message) for w in caught]
    assert messages == [
        "1 of 3 set(s) (2) leave their model's validity pressures (set 2: 300 bar against "
        "1-159 bar): the friction is extrapolated there",
        messages[1],
    ]
    assert messages[1].startswith("1 of 3 set(s) (1) leave their model's validity speeds (set 1: ")
    with pytest.raises(ValueError, match=r"\(2\) leave their model's validity pressures"):
        simulate_batch(Cylinder(mass=10.0), model, drives, 0.5, pressures=pressures, strict=True)


def test_a_model_read_from_a_file_names_it_when_its_extrapolated_law_fails(tmp_path):
    sheet = _model().to_datasheet()
    sheet["parameters"]["sigma_2"] = {"intercept": 500.0, "slope": -500.0 / 200e5}
    path = tmp_path / "falling.json"
    path.write_text(json.dumps(sheet))
    model = FrictionModel.from_datasheet(path)
    assert model.source == str(path)
    assert model.friction(0.01, 100e5) > 0  # inside the validity range: evaluates
    with (
        pytest.warns(ValidityWarning),
        pytest.raises(
            ValueError,
            match=rf"^{re.escape(str(path))}: parameter sigma_2 = -250\.0 is out of range",
        ),
    ):
        model.friction(0.01, 300e5)
    assert FrictionModel.from_datasheet(sheet).source is None  # a dict has no file to name


def test_a_replaced_model_still_names_its_file_and_what_was_replaced(tmp_path):
    """replace() dropped ``source``: a model read from a file and changed (the simulate
    command's --sigma-0, a scaled catalogue model) raised errors naming no file."""
    sheet = _model().to_datasheet()
    sheet["parameters"]["sigma_2"] = {"intercept": 500.0, "slope": -500.0 / 200e5}
    path = tmp_path / "falling.json"
    path.write_text(json.dumps(sheet))
    model = FrictionModel.from_datasheet(path)
    assert model.replaced == ()
    stiffer = model.replace(sigma_0=2e6).replace(sigma_1=1e3, sigma_0=3e6)
    assert stiffer.source == str(path) and stiffer.replaced == ("sigma_0", "sigma_1")
    assert model.replace().replaced == ()  # an unchanged copy is the file's model
    at_300_bar = dict(velocity=0.01, pressure=300e5, strict=False)
    for changed, prefix in [
        (stiffer, rf"{re.escape(str(path))}, with sigma_0, sigma_1 replaced: "),
        (model.replace(source="rig.json", sigma_0=2e6), r"rig\.json: "),  # a new source
        (model.replace(source=None), ""),  # source=None: named by nobody
    ]:
        with (
            pytest.warns(ValidityWarning),
            pytest.raises(ValueError, match=rf"^{prefix}parameter sigma_2 = -250\.0 is out of"),
        ):
            changed.friction(**at_300_bar)
    assert FrictionModel().replace(sigma_0=2e6).source is None  # built in Python: no file


@pytest.mark.parametrize(
    ("fixed", "message"),
    [
        ({"v_r": 0.0}, r"fixed v_r = 0\.0 m/s is out of range; expected 1e-05 to 10 m/s"),
        ({"F_c": -1.0}, r"fixed F_c = -1\.0 N is out of range; expected >= 0 N"),
        ({"alpha": math.nan}, r"fixed alpha = nan - is out of range; expected 0\.2 to 5 -"),
    ],
)
def test_identify_refuses_impossible_fixed_values(fixed, message):
    from cylfric.identify import identify

    speeds = np.array([1, 2, 5, 10, 20, 50, 100]) * 1e-3
    v, p = (a.ravel() for a in np.meshgrid(speeds, np.array([10, 100]) * 1e5))
    points = pd.DataFrame({"velocity [m/s]": v, "pressure [Pa]": p, "friction [N]": 100 + 500 * v})
    with pytest.raises(ValueError, match=message):
        identify(points, fixed=fixed, sensitivity=False)


# ------------------------------------------------- validity ranges (re-check after the fixes)
def _demo_sheet():
    model = FrictionModel().replace(
        validity={
            "pressure_min": 0.0,
            "pressure_max": 159e5,
            "velocity_min": 1e-3,
            "velocity_max": 0.135,
        }
    )
    return model.to_datasheet()


@pytest.mark.parametrize(
    ("key", "value", "message"),
    [
        ("pressure_min", 200e5, "validity/pressure_min: 200-159 bar is not a range"),
        ("velocity_min", 0.2, "validity/velocity_min: 200-135 mm/s is not a range"),
        ("pressure_min", -1e4, "validity/pressure_min: -0.1-159 bar is not a range"),
    ],
)
def test_a_datasheet_with_an_inverted_or_negative_validity_range_is_refused(key, value, message):
    from cylfric.datasheet import validate
    from cylfric.model.serialize import DatasheetError

    sheet = _demo_sheet()
    validate(sheet)  # the untouched sheet is valid
    sheet["validity"][key] = value
    with pytest.raises(DatasheetError, match=re.escape(message)):
        validate(sheet, source="inv.json")


def test_a_noisy_zero_bar_channel_does_not_put_the_validity_range_below_0_bar():
    """The mean of a 0-bar pressure channel fell to -0.038 bar: the datasheet said 'valid
    for -0.038-159 bar' and the Hopsan and Simscape exports refused it."""
    from cylfric.identify.steady import validity_of

    points = pd.DataFrame(
        {"pressure [Pa]": [-3804.9, 55e5, 159e5], "velocity [m/s]": [0.001, -0.05, 0.1]}
    )
    assert validity_of(points) == {
        "pressure_min": 0.0,
        "pressure_max": 159e5,
        "velocity_min": 0.001,
        "velocity_max": 0.1,
    }
