"""An experiment folder as pandas data frames: afford.load(folder).

Reads what `afford experiment --out DIR` writes (docs/results-schema.md):
summary.json and the CSV files, of a plain experiment, a sweep, a shard, a
merged one, random tables, extrinsic designs and generated scenarios. The
columns of each frame are in docs/python.md.
"""
from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pandas as pd


@dataclass
class Experiment:
    """What one experiment folder holds (docs/python.md#results-as-data-frames)."""

    folder: Path
    summary: dict[str, Any]
    runs: pd.DataFrame                 # one row per intrinsic run
    affordances: pd.DataFrame          # long: one row per run, object and action (final prediction)
    tables: pd.DataFrame               # long: the mean table per system (and condition), with its target
    curves: pd.DataFrame               # long: curves_<S>.csv, one row per run, step, object and action
    extrinsic: pd.DataFrame            # one row per extrinsic test (extrinsic_<S>.csv)
    conditions: pd.DataFrame           # the conditions compared: sweep, random-table or extrinsic-design ones
    design: pd.DataFrame               # extrinsic designs: per system, condition and scenario
    points: pd.DataFrame               # generated scenarios: per system, condition and (k, n, m) point
    figures: dict[str, pd.DataFrame] = field(default_factory=dict)  # fig_<name>.csv by name
    goals: pd.DataFrame = field(default_factory=pd.DataFrame)  # GOALS: one row per run, curve interval and module

    def __repr__(self) -> str:
        return (f"Experiment({self.summary.get('experiment', '?')!r} in {str(self.folder)!r}: "
                f"{len(self.runs)} runs, {len(self.extrinsic)} extrinsic tests, {len(self.conditions)} conditions)")


def _read_csvs(folder: Path, pattern: str) -> pd.DataFrame:
    frames = [pd.read_csv(f) for f in sorted(folder.glob(pattern)) if f.stat().st_size > 0]
    frames = [f for f in frames if not f.empty]
    return pd.concat(frames, ignore_index=True) if frames else pd.DataFrame()


def _goals_of(folder: Path) -> pd.DataFrame:
    """The goals_<S>.csv files together, with each row's competence: goals reached of those pursued (the goals
    found reached when set left out), NaN where none was pursued and for `explore`, whose actions are random."""
    goals = _read_csvs(folder, "goals_*.csv")
    if goals.empty:
        return goals
    pursued = goals["set"] - goals["found"]
    competence = (goals["reached"] - goals["found"]) / pursued.where(pursued > 0)
    goals["competence"] = competence.where(goals["module"] != "explore")
    return goals


def _runs_of(summary: dict[str, Any], condition: str | None) -> tuple[list[dict], list[dict], list[dict]]:
    """Run rows, their final predictions (long) and the mean tables (long) of one summary."""
    objects = summary.get("objects", [])
    actions = summary.get("actions", [])
    runs, cells, tables = [], [], []
    for system, s in summary.get("systems", {}).items():
        for r in s.get("runs", []):
            row = {"system": system, "sweep_condition": condition}
            for key, value in r.items():
                if key in ("affordance", "target", "peak_rss_kb"):
                    continue
                if isinstance(value, list):  # per action: one column each
                    for a, v in zip(actions, value):
                        row[f"{key}[{a}]"] = v
                else:
                    row[key] = value
            for proc, kb in (r.get("peak_rss_kb") or {}).items():
                row[f"peak_rss_kb[{proc}]"] = kb
            runs.append(row)
            target = r.get("target", s.get("target"))
            for i, obj in enumerate(objects):
                for j, act in enumerate(actions):
                    if r.get("affordance") is None:
                        continue
                    cells.append({"system": system, "sweep_condition": condition, "run_id": r.get("run_id"),
                                  "seed": r.get("seed"), "condition": r.get("condition"), "table": r.get("table"),
                                  "object": obj, "action": act, "value": r["affordance"][i][j],
                                  "target": None if target is None else target[i][j]})
        if "affordance" in s:
            for i, obj in enumerate(objects):
                for j, act in enumerate(actions):
                    tables.append({"system": system, "sweep_condition": condition, "object": obj, "action": act,
                                   "mean": s["affordance"][i][j],
                                   "min": s.get("affordance_min", s["affordance"])[i][j],
                                   "max": s.get("affordance_max", s["affordance"])[i][j],
                                   "target": s["target"][i][j] if "target" in s else None})
    return runs, cells, tables


def _design_of(summary: dict[str, Any], condition: str | None) -> tuple[list[dict], list[dict]]:
    """Per system, extrinsic condition and scenario; and the generated scenarios' points."""
    design, points = [], []
    for system, s in summary.get("systems", {}).items():
        for c in s.get("extrinsic", {}).get("conditions", []) or []:
            for scenario, st in c.get("scenarios", {}).items():
                row = {"system": system, "sweep_condition": condition, "condition": c.get("label"),
                       "scenario": scenario}
                row.update({f"setting[{k}]": v for k, v in c.get("settings", {}).items()})
                for key, value in st.items():
                    if isinstance(value, dict):
                        row.update({f"{key}.{k}": v for k, v in value.items() if not isinstance(v, (list, dict))})
                    elif not isinstance(value, list):
                        row[key] = value
                design.append(row)
            for p in c.get("points", []) or []:
                row = {"system": system, "sweep_condition": condition, "condition": c.get("label")}
                for key, value in p.items():
                    if isinstance(value, dict):
                        row.update({f"{key}.{k}": v for k, v in value.items() if not isinstance(v, (list, dict))})
                    else:
                        row[key] = value
                points.append(row)
    return design, points


def _conditions_of(summary: dict[str, Any]) -> list[dict]:
    out = []
    for c in summary.get("sweep", {}).get("conditions", []):
        out.append({"kind": "sweep", "name": c["name"], "settings": c.get("settings", []), "folder": c.get("folder")})
    rt = summary.get("random_tables")
    if rt:
        for name in rt.get("condition_order", []):
            out.append({"kind": "random_tables", "name": name, "settings": rt.get("conditions", {}).get(name, []),
                        "folder": None})
    seen = set()
    for s in summary.get("systems", {}).values():
        for c in s.get("extrinsic", {}).get("conditions", []) or []:
            if c.get("label") in seen:
                continue
            seen.add(c.get("label"))
            out.append({"kind": "extrinsic", "name": c.get("label"),
                        "settings": [f"{k}={v}" for k, v in c.get("settings", {}).items()], "folder": None})
    return out


def load(folder: str | Path) -> Experiment:
    """Read an experiment folder (`afford experiment --out DIR`) into data frames.

    Raises FileNotFoundError naming the folder when it holds neither a
    summary.json nor any fig_*.csv, and ValueError naming the file when
    summary.json is not JSON.
    """
    folder = Path(folder)
    if not folder.is_dir():
        raise FileNotFoundError(f"no experiment folder at {folder}")
    figures = {f.stem[len("fig_"):]: pd.read_csv(f) for f in sorted(folder.glob("fig_*.csv"))}
    summary_path = folder / "summary.json"
    if not summary_path.exists():
        if not figures:
            raise FileNotFoundError(f"{folder} holds no summary.json and no fig_*.csv: not an experiment's folder")
        empty = pd.DataFrame()
        return Experiment(folder, {}, empty, empty, empty, empty, empty, empty, empty, empty, figures)
    try:
        summary = json.loads(summary_path.read_text())
    except json.JSONDecodeError as e:
        raise ValueError(f"{summary_path}: not JSON ({e})") from e

    runs, cells, tables, design, points = [], [], [], [], []
    parts = ([(name, s) for name, s in summary["conditions"].items()] if "sweep" in summary and
             isinstance(summary.get("conditions"), dict) else [(None, summary)])
    for condition, s in parts:
        r, c, t = _runs_of(s, condition)
        runs += r
        cells += c
        tables += t
        d, p = _design_of(s, condition)
        design += d
        points += p

    def frame(rows: list[dict]) -> pd.DataFrame:
        df = pd.DataFrame(rows)
        if "sweep_condition" in df and df["sweep_condition"].isna().all():
            df = df.drop(columns="sweep_condition")
        return df.dropna(axis=1, how="all") if not df.empty else df

    return Experiment(
        folder=folder,
        summary=summary,
        runs=frame(runs),
        affordances=frame(cells),
        tables=frame(tables),
        curves=_read_csvs(folder, "curves_*.csv"),
        extrinsic=_read_csvs(folder, "extrinsic_*.csv"),
        conditions=pd.DataFrame(_conditions_of(summary), columns=["kind", "name", "settings", "folder"]),
        design=frame(design),
        points=frame(points),
        figures=figures,
        goals=_goals_of(folder),
    )
