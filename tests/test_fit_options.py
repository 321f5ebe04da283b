"""FitOptions: the options of one fit, checked once (issue 24, item 2)."""

from __future__ import annotations

import pickle

import pytest

from cylfric.options import FITTED_PRESSURE_LAWS, FitOptions


def test_the_pressure_laws_are_those_the_identification_compares():
    from cylfric.identify.steady import LAWS_COMPARED

    assert tuple(FITTED_PRESSURE_LAWS) == tuple(LAWS_COMPARED)


def test_defaults_are_those_of_fit_campaign():
    options = FitOptions()
    assert options.fixed == {} and options.pressure_law == "linear"
    assert (options.per_direction, options.skip_bad, options.report, options.strict) == (
        False,
        False,
        True,
        False,
    )
    assert options.export == () and options.workers is None
    assert options.viscosity_correction is None and options.name is None
    assert options.scheduler is None  # the files read on this machine


def test_export_targets_are_parsed_once():
    assert FitOptions(export="FMU, matlab,fmu").export == ("fmu", "matlab")
    assert FitOptions(export=["hopsan"]).export == ("hopsan",)
    assert FitOptions(export=None).export == ()


@pytest.mark.parametrize(
    ("keywords", "message"),
    [
        ({"pressure_law": "cubic"}, r"unknown pressure law 'cubic' \(pressure_law\); valid: \["),
        ({"export": "fmu,stl"}, r"unknown export target 'stl'; valid: \["),
        ({"workers": 0}, r"workers = 0: expected a whole number >= 1"),
        ({"workers": 1.5}, r"workers = 1.5: expected a whole number >= 1"),
        ({"report": "no"}, r"report = 'no': expected one of \[True, False\]"),
        ({"viscosity_correction": "on"}, r"viscosity_correction = 'on': expected one of"),
        ({"fixed": [("alpha", 1.0)]}, r"fixed = .*: expected a dict"),
        ({"glob": 3}, r"glob = 3: expected a string or None"),
    ],
)
def test_a_wrong_option_names_itself_and_the_valid_values(keywords, message):
    with pytest.raises(ValueError, match=message):
        FitOptions(**keywords)


def test_options_are_frozen_and_travel_to_worker_processes():
    options = FitOptions(fixed={"alpha": 1.0}, export="fmu", workers=1)
    with pytest.raises(AttributeError):
        options.report = False  # type: ignore[misc]
    assert pickle.loads(pickle.dumps(options)) == options


def test_options_or_keywords_but_not_both():
    given = FitOptions(strict=True)
    assert FitOptions.from_keywords(given) is given
    assert FitOptions.from_keywords(strict=True) == given
    with pytest.raises(ValueError, match="either options .* or its keywords, not both"):
        FitOptions.from_keywords(given, report=False)
    with pytest.raises(ValueError, match=r"unknown fit option\(s\) \['law'\]; valid: \["):
        FitOptions.from_keywords(law="linear")


def test_fit_campaign_refuses_options_with_keywords(tmp_path):
    from cylfric.pipeline import fit_campaign

    with pytest.raises(ValueError, match="not both"):
        fit_campaign(tmp_path / "c", tmp_path / "o", FitOptions(), report=False)
    with pytest.raises(ValueError, match=r"unknown fit option\(s\) \['reprt'\]"):
        fit_campaign(tmp_path / "c", tmp_path / "o", reprt=False)


def test_fit_many_refuses_a_name_for_every_campaign(tmp_path):
    from cylfric.many import fit_many

    with pytest.raises(ValueError, match="names each datasheet after its campaign"):
        fit_many(tmp_path, tmp_path / "o", FitOptions(name="one"), scheduler="serial")
    with pytest.raises(ValueError, match="fit_many sends whole campaigns"):
        fit_many(tmp_path, tmp_path / "o", FitOptions(scheduler="tcp://127.0.0.1:8786"))
    with pytest.raises(ValueError, match="scheduler = 8786: expected a string"):
        FitOptions(scheduler=8786)
