"""afford.load: every kind of experiment folder as data frames, checked against summary.json and the CSV files."""
import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import afford


def test_a_plain_experiment_has_its_runs_final_tables_curves_and_tests(made):
    e = afford.load(made / "base")
    s = json.loads((made / "base" / "summary.json").read_text())
    assert e.summary == s
    assert sorted(e.runs["system"].unique()) == ["FIX", "IGN", "IMP"]
    assert len(e.runs) == 6
    by_id = {r["run_id"]: r for sys in s["systems"].values() for r in sys["runs"]}
    for _, row in e.runs.iterrows():
        assert row["weights_checksum"] == by_id[row["run_id"]]["weights_checksum"]
        assert row["actions_executed[move]"] == by_id[row["run_id"]]["actions_executed"][0]
    # long form: a row per run, object and action, with the target
    assert len(e.affordances) == 6 * 9 * 4
    first = by_id[e.runs["run_id"].iloc[0]]
    cells = e.affordances[e.affordances["run_id"] == first["run_id"]]
    assert np.allclose(cells["value"].to_numpy().reshape(9, 4), np.array(first["affordance"]))
    # the mean table is the mean of the runs' tables
    imp = e.affordances[e.affordances["system"] == "IMP"].groupby(["object", "action"], sort=False)["value"].mean()
    table = e.tables[e.tables["system"] == "IMP"].set_index(["object", "action"])["mean"]
    assert np.allclose(imp.loc[table.index].to_numpy(), table.to_numpy())
    assert set(e.tables["target"].unique()) <= {0, 1}
    # the CSV files, whole
    curves = pd.concat([pd.read_csv(f) for f in sorted((made / "base").glob("curves_*.csv"))], ignore_index=True)
    pd.testing.assert_frame_equal(e.curves, curves)
    assert len(e.extrinsic) == s["extrinsic_tests"] == 6 * 2
    assert set(e.extrinsic["scenario"]) == {"scenario1", "scenario2"}
    assert e.goals.empty  # no goals agent ran


def test_a_sweep_names_each_runs_condition(made):
    e = afford.load(made / "sweep")
    assert list(e.conditions["kind"]) == ["sweep", "sweep"]
    assert set(e.runs["sweep_condition"]) == set(e.conditions["name"]) == {"motivation.leak=0.1",
                                                                          "motivation.leak=0.3"}
    assert len(e.affordances) == 2 * 9 * 4


def test_random_tables_give_each_run_its_table_and_condition(made):
    e = afford.load(made / "tables")
    s = e.summary["random_tables"]
    assert list(e.conditions["name"]) == s["condition_order"]
    assert set(e.runs["table"]) == {0, 1}
    assert set(e.runs["condition"]) == set(s["condition_order"])
    for _, r in e.runs.iterrows():  # each run against its own table
        cells = e.affordances[e.affordances["run_id"] == r["run_id"]]
        assert np.isclose((cells["value"] - cells["target"]).abs().mean(), r["affordance_mae"])


def test_an_extrinsic_design_has_a_row_per_condition_and_scenario(made):
    e = afford.load(made / "utility")
    conditions = e.summary["systems"]["IMP"]["extrinsic"]["conditions"]
    assert len(e.design) == sum(len(c["scenarios"]) for c in conditions)
    assert set(e.design["condition"]) == {c["label"] for c in conditions}
    assert "utility.mean" in e.design.columns
    assert (e.conditions["kind"] == "extrinsic").sum() == len(conditions)


def test_generated_scenarios_have_their_points(made):
    e = afford.load(made / "attention")
    assert not e.points.empty
    assert set(e.points["sub_goals"]) == {1, 2}
    assert {"condition", "success_rate", "tests"} <= set(e.points.columns)


def test_bad_folders_are_named(tmp_path):
    with pytest.raises(FileNotFoundError, match="no experiment folder"):
        afford.load(tmp_path / "nowhere")
    with pytest.raises(FileNotFoundError, match="holds no summary.json"):
        afford.load(tmp_path)
    (tmp_path / "summary.json").write_text("{not json")
    with pytest.raises(ValueError, match="summary.json: not JSON"):
        afford.load(tmp_path)


def test_every_folder_of_the_documented_results_loads_whole():
    docs = Path(__file__).resolve().parents[2] / "docs" / "results"
    folders = sorted(d for d in docs.iterdir() if d.is_dir())
    assert folders
    for d in folders:
        e = afford.load(d)
        csvs = sorted(d.glob("fig_*.csv"))
        assert sorted(e.figures) == [f.stem[len("fig_"):] for f in csvs], d
        for f in csvs:
            lines = [line for line in f.read_text().splitlines() if line.strip()]
            assert len(e.figures[f.stem[len("fig_"):]]) == len(lines) - 1, f  # every row, under its header


def test_a_goals_agents_goals_per_module_and_interval_with_their_competence():
    folder = Path(__file__).resolve().parents[2] / "tests" / "data" / "compat" / "0.2.0" / "experiment"
    e = afford.load(folder)
    written = pd.read_csv(folder / "goals_GOALS.csv")
    pd.testing.assert_frame_equal(e.goals.drop(columns="competence"), written)
    goals = e.summary["systems"]["GOALS"]["goals"]
    pooled = e.goals.groupby(["module", "step"]).sum(numeric_only=True)
    for module, m in goals["modules"].items():
        for step, competence in zip(goals["steps"], m["competence"]):
            rows = e.goals[(e.goals["module"] == module) & (e.goals["step"] == step)]
            if module == "explore":  # random actions: no competence
                assert rows["competence"].isna().all()
                continue
            if competence is None:
                continue
            p = pooled.loc[(module, step)]
            assert (p["reached"] - p["found"]) / (p["set"] - p["found"]) == pytest.approx(competence)
            if len(rows) == 1:  # one run: its row is the summary's
                assert rows["competence"].iloc[0] == pytest.approx(competence)
