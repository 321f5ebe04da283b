"""The seal catalogue: SQLite round trip, concurrency, migrations, export/import, selection,
comparison, and prediction of another cylinder size by seal contact length."""

from __future__ import annotations

import json
import multiprocessing
import sqlite3

import numpy as np
import pytest
from numpy.testing import assert_allclose

from cylfric.catalog import Catalog, CatalogError, contact_ratio, default_path
from cylfric.catalog.store import MIGRATIONS, SCHEMA_VERSION
from cylfric.datasheet import DatasheetError
from cylfric.model import FrictionModel


def _scaled_truth(model: FrictionModel, ratio: float) -> FrictionModel:
    """The bench's true model for a cylinder whose seal contact is ``ratio`` times longer:
    every coefficient of F_c, F_s and sigma_2 times ``ratio`` (the rule under test)."""
    coefficients = model.coefficients(include_dynamic=False)
    for name in ("F_c", "F_s", "sigma_2"):
        coefficients[name] = {
            c: (v if c == "law" else v * ratio) for c, v in coefficients[name].items()
        }
    return model.replace(coefficients=coefficients)


def _sheet(ratio=1.0) -> dict:
    """A datasheet with a covariance: the thesis law with 1 % standard errors (made up for
    the test: diagonal covariance on the five linear-law coefficients and v_r)."""
    model = _scaled_truth(FrictionModel(), ratio)
    values = {n: p.value for n, p in model.parameters.items() if p.value is not None}
    names = ["F_c.intercept", "F_c.slope", "F_s.intercept", "F_s.slope", "sigma_2.intercept"]
    cov = np.diag([(0.01 * values[n]) ** 2 for n in names])
    model = model.replace(
        covariance=(names, cov),
        statistics={"dof": 100, "residual_std": 1.0, "rmse": 1.0, "n_points": 110},
        validity={
            "pressure_min": 5e5,
            "pressure_max": 160e5,
            "velocity_min": 1e-3,
            "velocity_max": 0.135,
        },
    )
    return json.loads(json.dumps(model.to_datasheet()))


@pytest.fixture
def db(tmp_path):
    return Catalog(tmp_path / "seals.sqlite")


def test_round_trip_gives_the_identical_datasheet(db, tmp_path):
    sheet = _sheet()
    path = tmp_path / "datasheet.json"
    path.write_text(json.dumps(sheet))
    db.add(path, "from-file", seal="NBR U-cup", bore=0.040, rod=0.028, temperature=313.15)
    db.add(sheet, "from-dict")
    assert db.get("from-file") == sheet
    assert db.get("from-dict") == sheet
    meta = db.metadata("from-file")
    assert meta["bore"] == 0.040 and meta["rod"] == 0.028 and meta["temperature"] == 313.15
    table = db.list()
    assert list(table["name"]) == ["from-dict", "from-file"]
    assert {"bore [m]", "rod [m]", "temperature [K]", "pressure max [Pa]"} <= set(table.columns)
    assert_allclose(db.model("from-file").friction(0.025, 55e5), 111.26, atol=0.005)  # eq. 4.1-4.3
    db.remove("from-dict")
    assert db.names() == ["from-file"]


def test_add_refuses_bad_input(db, tmp_path):
    sheet = _sheet()
    db.add(sheet, "a")
    with pytest.raises(CatalogError, match="'a' is already in the catalogue.*replace"):
        db.add(sheet, "a")
    db.add(_sheet(2.0), "a", replace=True)
    assert db.get("a")["parameters"]["F_c"]["intercept"] == pytest.approx(140.4)
    with pytest.raises(CatalogError, match="bore = 40.0 m: larger than 2 m"):
        db.add(sheet, "b", bore=40.0)
    with pytest.raises(CatalogError, match="rod = 0.05 m must be smaller than the bore"):
        db.add(sheet, "b", bore=0.04, rod=0.05)
    with pytest.raises(CatalogError, match="temperature = 40.0 K: outside"):
        db.add(sheet, "b", temperature=40.0)
    with pytest.raises(CatalogError, match="catalogue name ' b'"):
        db.add(sheet, " b")
    broken = dict(
        sheet, parameters=dict(sheet["parameters"], F_c={"intercept": -5.0, "slope": 0.0})
    )
    with pytest.raises(DatasheetError, match="F_c < 0"):
        db.add(broken, "b")
    with pytest.raises(DatasheetError, match="cannot read"):
        db.add(tmp_path / "missing.json", "b")
    with pytest.raises(CatalogError, match="'zz' is not in the catalogue.*known: 'a'"):
        db.get("zz")
    with pytest.raises(CatalogError, match="'zz' is not in the catalogue"):
        db.remove("zz")
    assert db.names() == ["a"]


def _add_many(args):
    path, worker, count = args
    catalog = Catalog(path)
    sheet = _sheet(1.0 + 0.01 * worker)
    for i in range(count):
        catalog.add(sheet, f"w{worker}-{i}", bore=0.040)
    return worker


def test_concurrent_adds_from_several_processes(tmp_path):
    """4 processes x 5 adds into one new file (each opens it, migrating it if first)."""
    path = tmp_path / "shared.sqlite"
    context = multiprocessing.get_context("spawn")
    with context.Pool(4) as pool:
        done = pool.map(_add_many, [(path, w, 5) for w in range(4)])
    assert sorted(done) == [0, 1, 2, 3]
    catalog = Catalog(path)
    assert len(catalog) == 20
    assert catalog.names() == sorted(f"w{w}-{i}" for w in range(4) for i in range(5))
    assert catalog.get("w3-4")["parameters"]["F_c"]["intercept"] == pytest.approx(70.2 * 1.03)
    assert catalog.schema_version == SCHEMA_VERSION


def test_migration_from_version_1_keeps_the_entries(tmp_path):
    path = tmp_path / "old.sqlite"
    sheet = _sheet()
    with sqlite3.connect(path) as old:
        old.executescript(MIGRATIONS[0])
        old.execute("PRAGMA user_version = 1")
        old.execute(
            "INSERT INTO seals (name, datasheet, added) VALUES (?, ?, ?)",
            ("legacy", json.dumps(sheet), "2025-01-01T00:00:00+00:00"),
        )
    old.close()
    catalog = Catalog(path)
    assert catalog.schema_version == SCHEMA_VERSION == 2
    assert catalog.get("legacy") == sheet
    assert catalog.metadata("legacy")["bore"] is None
    catalog.add(sheet, "new", bore=0.05)
    assert catalog.metadata("new")["bore"] == 0.05


def test_newer_or_foreign_files_are_refused(tmp_path):
    newer = tmp_path / "newer.sqlite"
    with sqlite3.connect(newer) as handle:
        handle.execute(f"PRAGMA user_version = {SCHEMA_VERSION + 1}")
    handle.close()
    with pytest.raises(CatalogError, match="schema version 3 is newer"):
        Catalog(newer)
    foreign = tmp_path / "foreign.sqlite"
    with sqlite3.connect(foreign) as handle:
        handle.execute("CREATE TABLE t (x)")
    handle.close()
    with pytest.raises(CatalogError, match="not a cylfric catalogue"):
        Catalog(foreign)
    text = tmp_path / "text.sqlite"
    text.write_text("not sqlite at all, just some words " * 40)
    with pytest.raises(CatalogError, match="not a usable catalogue"):
        Catalog(text)


def test_default_path_follows_the_environment(tmp_path, monkeypatch):
    monkeypatch.setenv("CYLFRIC_CATALOG", str(tmp_path / "env.sqlite"))
    assert default_path() == tmp_path / "env.sqlite"
    assert Catalog().path == tmp_path / "env.sqlite"
    monkeypatch.delenv("CYLFRIC_CATALOG")
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "xdg"))
    assert default_path() == tmp_path / "xdg" / "cylfric" / "catalog.sqlite"


def test_export_import_round_trip(db, tmp_path):
    db.add(_sheet(), "a", seal="O-ring", bore=0.025, fluid="air")
    db.add(_sheet(1.5), "b", manufacturer="X", temperature=300.0)
    path = db.export_json(tmp_path / "export.json")
    other = Catalog(tmp_path / "other.sqlite")
    assert other.import_json(path) == 2
    for name in ("a", "b"):
        assert other.get(name) == db.get(name)
        assert {k: v for k, v in other.metadata(name).items() if k != "added"} == {
            k: v for k, v in db.metadata(name).items() if k != "added"
        }
    with pytest.raises(CatalogError, match="'a' is already in the catalogue"):
        other.import_json(path)
    assert other.import_json(path, replace=True) == 2
    document = json.loads(path.read_text())
    document["entries"][1]["datasheet"]["parameters"]["F_s"] = {"intercept": 1.0, "slope": 0.0}
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(document))
    third = Catalog(tmp_path / "third.sqlite")
    with pytest.raises(DatasheetError, match=r"entries/1 \('b'\)/datasheet: .*F_s < F_c"):
        third.import_json(bad)
    assert len(third) == 0  # all or nothing
    foreign = tmp_path / "foreign.json"
    foreign.write_text("{}")
    with pytest.raises(CatalogError, match="format: expected 'cylfric-catalog/1'"):
        third.import_json(foreign)


def test_select_ranks_by_friction_with_band(db):
    for name, ratio in (("big", 2.0), ("small", 0.5), ("mid", 1.0)):
        db.add(_sheet(ratio), name)
    table = db.select(100e5, 0.020)
    assert list(table["name"]) == ["small", "mid", "big"]
    assert list(table["rank"]) == [1, 2, 3]
    mid = FrictionModel().friction(0.020, 100e5)  # the thesis law scaled by 1
    assert_allclose(table["friction [N]"], [0.5 * mid, mid, 2 * mid], rtol=1e-12)
    assert (table["lower [N]"] < table["friction [N]"]).all()
    assert (table["upper [N]"] > table["friction [N]"]).all()
    assert table["inside validity"].all()
    limited = db.select(100e5, 0.020, max_friction=mid * 1.05)  # band half-width about 2 %
    assert list(limited["name"]) == ["small", "mid"]
    outside = db.select(300e5, 0.020)
    assert not outside["inside validity"].any()
    with pytest.raises(CatalogError, match="max_friction = -1 N"):
        db.select(100e5, 0.020, max_friction=-1)


def test_compare_writes_figures_and_table(db, tmp_path):
    db.add(_sheet(), "a")
    db.add(_sheet(1.2), "b")
    result = db.compare(["a", "b"], tmp_path / "cmp", [20e5, 150e5], [0.005, 0.05])
    table = result["table"]
    assert len(table) == 2 * 2 * 2
    for key in ("csv", "png", "svg"):
        assert result[key].stat().st_size > 500
    a = table[table["name"] == "a"]["friction [N]"].to_numpy()
    b = table[table["name"] == "b"]["friction [N]"].to_numpy()
    assert_allclose(b, 1.2 * a, rtol=1e-12)
    with pytest.raises(CatalogError, match="'zz' is not in the catalogue"):
        db.compare(["a", "zz"], tmp_path / "cmp2", [20e5], [0.01])


def test_contact_ratio_rules():
    assert contact_ratio(0.040, 0.063)[0] == pytest.approx(63 / 40)
    assert contact_ratio(None, None, source_rod=0.028, rod=0.036, contact="rod")[0] == (
        pytest.approx(36 / 28)
    )
    ratio, text = contact_ratio(
        0.040, 0.063, source_rod=0.028, rod=0.036, contact="total", rod_seals=2
    )
    assert ratio == pytest.approx((63 + 72) / (40 + 56))
    assert "pi (D + 2 d)" in text
    with pytest.raises(ValueError, match="does not record the tested bore"):
        contact_ratio(None, 0.063)
    with pytest.raises(ValueError, match="needs the target rod diameter"):
        contact_ratio(0.04, 0.063, source_rod=0.028, contact="total")
    with pytest.raises(ValueError, match="ratio 5: beyond 0.25-4"):
        contact_ratio(0.020, 0.100)
    with pytest.raises(ValueError, match="contact = 'gland': unknown"):
        contact_ratio(0.04, 0.05, contact="gland")


def test_predict_scales_forces_and_adds_the_rule_uncertainty(db):
    sheet = _sheet()
    db.add(sheet, "thesis", bore=0.040, rod=0.028)
    predicted = db.predict("thesis", 0.080, rule_stderr=0.10)
    model = FrictionModel.from_datasheet(predicted)  # validates
    source = db.model("thesis")
    assert_allclose(model.friction(0.02, 80e5), 2 * source.friction(0.02, 80e5), rtol=1e-12)
    assert model.parameters["v_r"].value == source.parameters["v_r"].value
    assert model.parameters["alpha"].value == source.parameters["alpha"].value
    # F_c.intercept: (2 x 1 %)^2 from the fit plus (10 % of the scaled value)^2 from the rule
    F_c = 2 * 70.2
    assert_allclose(
        model.parameters["F_c.intercept"].stderr, np.hypot(0.01 * F_c, 0.10 * F_c), rtol=1e-9
    )
    assert predicted["prediction"]["ratio"] == 2.0
    assert predicted["prediction"]["rule_relative_stderr"] == 0.10
    assert "L = pi D" in predicted["fit"]["method"]
    assert predicted["per_pressure"] == [] and predicted["offset"] is None
    # the rule's common factor alone gives a standard error of 10 % of the friction
    se = model.standard_error(0.02, 80e5)
    assert se > 0.10 * model.friction(0.02, 80e5)
    # the tested size itself: same friction, same uncertainty (no rule term at k = 1)
    same = FrictionModel.from_datasheet(db.predict("thesis", 0.040))
    assert_allclose(same.friction(0.02, 80e5), source.friction(0.02, 80e5), rtol=1e-12)
    assert_allclose(same.standard_error(0.02, 80e5), source.standard_error(0.02, 80e5), rtol=1e-6)
    with pytest.raises(ValueError, match="rule_stderr = 1.5"):
        db.predict("thesis", 0.080, rule_stderr=1.5)


def test_predict_a_rod_seal_without_a_target_bore(db):
    # a rod seal needs no bore: the name of the prediction had multiplied bore=None
    db.add(_sheet(), "thesis", bore=0.040, rod=0.028)
    predicted = db.predict("thesis", None, rod=0.036, contact="rod")  # type: ignore[arg-type]  # bore is unused by a rod seal
    assert predicted["name"] == "thesis scaled to rod 36 mm"
    assert predicted["prediction"]["ratio"] == pytest.approx(0.036 / 0.028)
    FrictionModel.from_datasheet(predicted)  # validates


def test_predict_acceptance_on_the_virtual_bench(tmp_path):
    """A virtual campaign at bore 40 mm predicts one at bore 63 mm within the stated
    uncertainty when the bench's friction scales with the seal contact length (its true
    model scaled by 63/40); a bench that scales with the piston area instead is caught."""
    from cylfric.pipeline import fit_campaign
    from cylfric.simulate.bench import BenchSettings, generate_campaign
    from cylfric.simulate.plant import Cylinder

    pressures, speeds = (20, 80, 150), (2, 5, 10, 25, 60, 120)  # 18 runs per campaign
    truth = FrictionModel()  # the thesis law, eq. 4.1-4.3
    catalog = Catalog(tmp_path / "c.sqlite")
    cases = {"bore40": (0.040, truth, 1), "bore63": (0.063, _scaled_truth(truth, 63 / 40), 2)}
    cases["area63"] = (0.063, _scaled_truth(truth, (63 / 40) ** 2), 3)
    for name, (bore, model, seed) in cases.items():
        settings = BenchSettings.clean(
            cylinder=Cylinder.from_diameters(bore, 0.028, 2.5, double_rod=True, stroke=0.15),
            friction=model,
            pressures_bar=pressures,
            speeds_mm_s=speeds,
            seed=seed,
        )
        generate_campaign(tmp_path / name, settings)
        fit_campaign(tmp_path / name, tmp_path / f"fit-{name}", report=False)
        catalog.add(tmp_path / f"fit-{name}", name, bore=bore, rod=0.028)
    v = np.geomspace(0.002, 0.12, 7)[:, None]  # inside the validity ranges
    p = np.array([20e5, 80e5, 150e5])[None, :]
    measured = catalog.model("bore63")

    def z_scores(predicted, rule_stderr):
        model = FrictionModel.from_datasheet(
            catalog.predict("bore40", 0.063, rule_stderr=rule_stderr)
        )
        se = np.hypot(model.standard_error(v, p), predicted.standard_error(v, p))
        return (model.friction(v, p) - predicted.friction(v, p)) / se

    # with the default 10 % rule uncertainty, and even with the fit's uncertainty alone
    assert np.abs(z_scores(measured, 0.10)).max() < 2.0
    assert np.abs(z_scores(measured, 0.0)).max() < 3.0
    # not scaling at all (k = 1) is far outside the fit's uncertainty
    same = catalog.model("bore40")
    z_same = (same.friction(v, p) - measured.friction(v, p)) / np.hypot(
        same.standard_error(v, p), measured.standard_error(v, p)
    )
    assert np.abs(z_same).min() > 20
    # friction that grows with the piston area (another 1.575x) is outside even the 10 % band
    assert np.abs(z_scores(catalog.model("area63"), 0.10)).min() > 3.0
