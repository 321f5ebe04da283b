"""Validating a datasheet of many runs (issue 27): the compiled schema check is only a fast
path; jsonschema still decides what is refused and words the message."""

import hashlib
import math
import re

import jsonschema
import numpy as np
import pytest
from jsonschema.exceptions import best_match

from cylfric.model import SCHEMA, DatasheetError, FrictionModel, validate
from cylfric.model.serialize import _compiled_schema, _schema_problem

N_RUNS = 500  # rows of fit.influence and entries of fit.source.files
NAMES = ["F_c.intercept", "F_c.slope", "F_s.intercept", "F_s.slope", "v_r"]


def _large_sheet():
    """A valid datasheet with the bulky parts of a many-run fit: influence and file list."""
    sheet = FrictionModel().to_datasheet()
    rng = np.random.default_rng(27)
    sheet["fit"]["influence"] = {
        "names": list(NAMES),
        "matrix": rng.normal(0.0, 1e-3, (N_RUNS, len(NAMES))).tolist(),
    }
    sheet["fit"]["source"]["files"] = [
        {"name": f"run_{i:05d}.csv", "sha256": hashlib.sha256(str(i).encode()).hexdigest()}
        for i in range(N_RUNS)
    ]
    sheet["fit"]["n_points"] = 12 * N_RUNS
    sheet["validity"] = {
        "pressure_min": 0.0,
        "pressure_max": 159e5,
        "velocity_min": 1e-3,
        "velocity_max": 0.135,
    }
    sheet["quality"] = {
        "lack_of_fit": {
            "test": "runs",
            "statistic": 1.2,
            "dof": [3, 40],
            "p_value": 0.3,
            "significant": False,
            "action": "none",
        }
    }
    return sheet


def _set(path, value):
    def change(sheet):
        *parents, last = path
        target = sheet
        for key in parents:
            target = target[key]
        target[last] = value

    return change


# each change either breaks the schema or (marked valid) is an edge the schema allows
CHANGES = {
    "string in the influence matrix": _set(["fit", "influence", "matrix", 400, 2], "0.1"),
    "bool in the influence matrix": _set(["fit", "influence", "matrix", 7, 0], True),
    "ragged influence row": _set(["fit", "influence", "matrix", 3], 0.5),
    "influence without names": _set(["fit", "influence"], {"matrix": [[1.0]]}),
    "influence with an extra key": _set(
        ["fit", "influence"], {"names": [], "matrix": [], "rows": []}
    ),
    "upper-case digest": _set(["fit", "source", "files", 499, "sha256"], "A" * 64),
    "short digest": _set(["fit", "source", "files", 0, "sha256"], "a" * 63),
    "digest with a newline (valid: $ matches before it)": _set(
        ["fit", "source", "files", 5, "sha256"], "a" * 64 + "\n"
    ),
    "file without a digest": _set(["fit", "source", "files", 10], {"name": "x.csv"}),
    "n_points 3.0 (valid: an integral number)": _set(["fit", "n_points"], 3.0),
    "n_points true": _set(["fit", "n_points"], True),
    "n_points 2.5": _set(["fit", "n_points"], 2.5),
    "wrong schema id": _set(["schema"], "cylfric-datasheet/2"),
    "unknown pressure reference": _set(["model", "pressure_reference"], "avg"),
    "v_r zero": _set(["parameters", "v_r"], 0.0),
    "extra law coefficient": _set(["parameters", "F_c", "offset"], 1.0),
    "law coefficients without intercept": _set(["parameters", "F_s"], {"slope": 1e-6}),
    "negative rmse": _set(["fit", "rmse"], -1.0),
    "one lack-of-fit dof": _set(["quality", "lack_of_fit", "dof"], [3]),
    "p-value above 1": _set(["quality", "lack_of_fit", "p_value"], 1.5),
    "number in notes": _set(["notes"], ["ok", 1]),
    "number as a not-identified reason": _set(["not_identified"], {"v_r": 1}),
    "bool velocity_min": _set(["validity", "velocity_min"], False),
    "top level not an object": lambda sheet: sheet.clear(),
}


@pytest.mark.parametrize("name", sorted(CHANGES))
def test_the_compiled_check_never_accepts_what_jsonschema_refuses(name):
    sheet = _large_sheet()
    CHANGES[name](sheet)
    errors = sorted(
        jsonschema.Draft202012Validator(SCHEMA).iter_errors(sheet), key=lambda e: list(e.path)
    )
    try:
        _compiled_schema()(sheet)
        compiled_accepts = True
    except Exception:
        compiled_accepts = False
    if compiled_accepts:
        assert not errors, f"{name}: the compiled schema accepted what jsonschema refuses"
    # the message is jsonschema's: its first error by path (inside a oneOf, the closest
    # alternative), with the full path to the offending value
    if errors:
        first = best_match(errors[:1])
        where = "/".join(str(p) for p in first.absolute_path) or "(top level)"
        assert _schema_problem(sheet) == f"{where}: {first.message}"
        assert len(_schema_problem(sheet)) < 200  # never the repr of the whole matrix
    else:
        assert "(valid" in name
        assert _schema_problem(sheet) is None


def test_a_large_valid_sheet_passes_both_checks():
    sheet = _large_sheet()
    assert validate(sheet) is sheet
    assert not list(jsonschema.Draft202012Validator(SCHEMA).iter_errors(sheet))


def test_a_string_deep_in_the_influence_matrix_is_named_with_its_row_and_column():
    sheet = _large_sheet()
    sheet["fit"]["influence"]["matrix"][400][2] = "0.1"
    with pytest.raises(
        DatasheetError, match=r"^big\.json: fit/influence/matrix/400/2: '0\.1' is not of type"
    ):
        validate(sheet, source="big.json")


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (_set(["parameters", "v_r"], 0.0), "parameters/v_r: 0.0 is less than or equal to"),
        (_set(["fit", "rmse"], -1.0), "fit/rmse: -1.0 is less than the minimum of 0"),
        (
            _set(["fit", "influence", "matrix", 3], 0.5),
            "fit/influence/matrix/3: 0.5 is not of type 'array'",
        ),
        (
            _set(["fit", "influence"], {"matrix": [[1.0]]}),
            "fit/influence: 'names' is a required property",
        ),
    ],
)
def test_a_oneof_error_names_the_closest_alternatives_expectation(change, message):
    sheet = _large_sheet()
    change(sheet)
    with pytest.raises(DatasheetError, match=rf"^big\.json: {re.escape(message)}"):
        validate(sheet, source="big.json")


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
def test_a_non_finite_number_in_the_influence_matrix_is_named_with_its_row_and_column(bad):
    sheet = _large_sheet()
    sheet["fit"]["influence"]["matrix"][345][3] = bad
    with pytest.raises(
        DatasheetError,
        match=rf"^big\.json: fit/influence/matrix/345/3: {bad} is not finite; expected a finite number",
    ):
        validate(sheet, source="big.json")


def test_non_finite_numbers_beside_strings_and_nulls_are_found():
    sheet = _large_sheet()
    sheet["fit"]["statistics"] = {"aic": [None, "x", 1.0, [2.0, math.nan]]}
    with pytest.raises(DatasheetError, match=r"fit/statistics/aic/3/1: nan is not finite"):
        validate(sheet)
    sheet["fit"]["statistics"] = {"aic": [None, "nan", "inf", 1.0]}  # strings, not numbers
    validate(sheet)


def _clean_by_lists(value):
    """clean() as it was before its array shortcut: every array through its lists."""
    if isinstance(value, dict):
        return {str(k): _clean_by_lists(v) for k, v in value.items()}
    if isinstance(value, np.ndarray):
        return _clean_by_lists(value.tolist())
    if isinstance(value, list | tuple):
        return [_clean_by_lists(v) for v in value]
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def _typed(value):
    """``value`` with the type of every leaf beside it (1 == 1.0 == True in Python)."""
    if isinstance(value, dict):
        return {k: _typed(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_typed(v) for v in value]
    return (type(value).__name__, value)


@pytest.mark.parametrize(
    "array",
    [
        np.array([[1.5, -2.0], [3.25, 1e-300]]),
        np.array([[1.0, np.nan], [np.inf, -np.inf]]),
        np.array([1, 2, 3], dtype=np.int32),
        np.array([[True, False]]),
        np.array([7], dtype=np.uint64),
        np.array(2.5),
        np.array(np.nan),
        np.zeros((0, 3)),
        np.array([1.5, 2.5], dtype=np.float32),
        np.array([1 + 2j]),
        np.array(["a", "b"]),
        np.array([1.0, None], dtype=object),
    ],
    ids=lambda a: f"{a.dtype}{a.shape}",
)
def test_clean_gives_an_array_the_same_lists_and_types_as_through_its_lists(array):
    from cylfric.model.serialize import clean

    expected = _clean_by_lists({"matrix": array})
    got = clean({"matrix": array})
    assert _typed(got) == _typed(expected)
    assert got["matrix"] is not None or array.ndim == 0


def test_a_datasheet_has_the_influence_matrix_as_lists_of_floats_and_writes_as_before(tmp_path):
    """to_datasheet hands the model's arrays to clean() whole: the same JSON as lists."""
    import json

    from cylfric.datasheet import write_datasheet

    coefficients = {"F_c": 70.0, "F_s": 110.0, "sigma_2": 300.0, "v_r": 0.01, "alpha": 1.0}
    names = ["F_c", "F_s"]
    influence = np.random.default_rng(27).normal(0.0, 1e-3, (N_RUNS, 2))
    model = FrictionModel(
        coefficients,
        pressure_law="constant",
        covariance=(names, influence.T @ influence),
        influence=(names, influence),
        statistics={"dof": 30},
    )
    sheet = model.to_datasheet()
    rows = sheet["fit"]["influence"]["matrix"]
    assert type(rows) is list and all(type(r) is list for r in rows)
    assert all(type(x) is float for r in rows for x in r)
    assert rows == influence.tolist()
    assert sheet["fit"]["covariance"]["matrix"] == (influence.T @ influence).tolist()
    path = write_datasheet(tmp_path / "d.json", sheet)
    assert json.loads(path.read_text())["fit"]["influence"]["matrix"] == influence.tolist()
    again = FrictionModel.from_datasheet(path)
    np.testing.assert_array_equal(again.influence[1], influence)


def test_compile_schema_compiles_once_per_process():
    from cylfric.model.serialize import compile_schema

    compile_schema()
    before = _compiled_schema.cache_info()
    compile_schema()
    after = _compiled_schema.cache_info()
    assert after.misses == before.misses and after.hits == before.hits + 1


def test_a_schema_fastjsonschema_cannot_compile_leaves_validate_to_jsonschema(monkeypatch):
    """compile_schema (called by cylfric fit while its pool reads) does not fail a fit where
    validate() would fall back to jsonschema."""
    import fastjsonschema

    from cylfric.model.serialize import compile_schema

    def refuse(*args, **kwargs):
        raise fastjsonschema.JsonSchemaDefinitionException("unsupported keyword (simulated)")

    sheet = _large_sheet()
    _compiled_schema.cache_clear()
    monkeypatch.setattr(fastjsonschema, "compile", refuse)
    try:
        compile_schema()  # no error
        assert validate(sheet) is sheet  # jsonschema decided
        sheet["fit"]["influence"]["matrix"][3][1] = "x"
        with pytest.raises(DatasheetError, match="influence/matrix/3/1"):
            validate(sheet)
    finally:
        monkeypatch.undo()
        _compiled_schema.cache_clear()  # the next check compiles the real one
