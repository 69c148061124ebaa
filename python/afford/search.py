"""What a study searches and what it measures (afford.tune, python/afford/study.py): config keys' ranges and
choices, and the objectives of a finished experiment."""
from __future__ import annotations

import importlib.util
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Iterable

from .results import Experiment


# ---- the search space -----------------------------------------------------------------------------------------

@dataclass(frozen=True)
class Float:
    """A config key's real values in [low, high] (log: sampled on a log scale)."""
    low: float
    high: float
    log: bool = False

    def spec(self) -> str:  # (float: Float(0.005, 1) and 'log:0.005:1' are one range, and say so alike)
        return f"{'log' if self.log else 'float'}:{float(self.low)!r}:{float(self.high)!r}"


class Int(Float):
    """A config key's whole values in [low, high] (log: sampled on a log scale)."""

    def spec(self) -> str:
        return f"{'intlog' if self.log else 'int'}:{self.low}:{self.high}"


@dataclass(frozen=True)
class Choice:
    """One of the given values of a config key."""
    choices: tuple

    def __init__(self, choices: Iterable[Any]):
        object.__setattr__(self, "choices", tuple(choices))

    def spec(self) -> str:
        return "choice:" + ",".join(str(c) for c in self.choices)


def _scalar(text: str) -> Any:
    for kind in (int, float):
        try:
            return kind(text)
        except ValueError:
            pass
    return {"true": True, "false": False}.get(text.lower(), text)


def parse_param(key: str, spec: Any) -> Float | Int | Choice:
    """A parameter from its spec: Float/Int/Choice, or the text `afford tune --param KEY=SPEC` takes:
    float:LOW:HIGH, log:LOW:HIGH (a log scale), int:LOW:HIGH, intlog:LOW:HIGH, choice:A,B,C."""
    if isinstance(spec, (Float, Int, Choice)):
        p = spec
    elif isinstance(spec, str):
        kind, _, rest = spec.partition(":")
        bounds = rest.split(":")
        try:
            if kind in ("float", "log") and len(bounds) == 2:
                p = Float(float(bounds[0]), float(bounds[1]), log=kind == "log")
            elif kind in ("int", "intlog") and len(bounds) == 2:
                p = Int(int(bounds[0]), int(bounds[1]), log=kind == "intlog")
            elif kind == "choice" and rest:
                p = Choice(_scalar(c) for c in rest.split(","))
            else:
                raise ValueError("not a spec")
        except ValueError:
            raise ValueError(f"parameter '{key}': '{spec}' is not float:LOW:HIGH, log:LOW:HIGH, int:LOW:HIGH, "
                             f"intlog:LOW:HIGH or choice:A,B,...") from None
    else:
        raise ValueError(f"parameter '{key}': {spec!r} is not afford.Float, afford.Int, afford.Choice or a spec "
                         f"such as 'log:0.001:0.1'")
    if isinstance(p, (Float, Int)):
        if not (math.isfinite(p.low) and math.isfinite(p.high)) or p.low >= p.high:
            raise ValueError(f"parameter '{key}': its range [{p.low}, {p.high}] is empty (low must be below high)")
        if p.log and p.low <= 0:
            raise ValueError(f"parameter '{key}': a log scale needs a low above 0, not {p.low}")
    elif not p.choices:
        raise ValueError(f"parameter '{key}': no choices")
    return p


def _distribution(p: Float | Int | Choice):
    import optuna
    if isinstance(p, Int):  # (an Int is a Float whose values are whole)
        return optuna.distributions.IntDistribution(int(p.low), int(p.high), log=p.log)
    if isinstance(p, Float):
        return optuna.distributions.FloatDistribution(p.low, p.high, log=p.log)
    return optuna.distributions.CategoricalDistribution(list(p.choices))


# ---- objectives ----------------------------------------------------------------------------------------------

def _affordance_mae(e: Experiment) -> float:
    return float(e.runs["affordance_mae"].mean())


def _curve_mae(e: Experiment) -> float:
    if e.curves.empty:
        raise ValueError("curve_mae: the experiment wrote no curves (random tables have none)")
    target = e.tables[["system", "object", "action", "target"]]
    c = e.curves.merge(target, on=["system", "object", "action"])
    return float((c["prediction"] - c["target"]).abs().mean())


def _success(e: Experiment) -> float:
    if e.extrinsic.empty:
        raise ValueError("success: the experiment ran no extrinsic tests (give extrinsic_reps and scenarios)")
    return float(e.extrinsic["success"].mean())


def _table2(e: Experiment) -> float:
    metrics = [v for system in e.summary.get("systems", {}).values()
               for v in system.get("extrinsic", {}).get("table_metric", {}).values()]
    if not metrics:
        raise ValueError("table2: the experiment ran no extrinsic tests (give extrinsic_reps and scenarios)")
    return float(sum(metrics) / len(metrics))


# name -> (the function of the loaded experiment, its direction)
OBJECTIVES: dict[str, tuple[Callable[[Experiment], float], str]] = {
    "affordance_mae": (_affordance_mae, "minimize"),  # the final tables' error from the world's, mean over runs
    "curve_mae": (_curve_mae, "minimize"),            # the error over the whole learning curves (how fast)
    "success": (_success, "maximize"),                # the extrinsic tests' share of successes
    "table2": (_table2, "maximize"),                  # the paper's Table 2 measure, mean over the scenarios
}


def _objective(objective: str | Callable[[Experiment], float]) -> Callable[[Experiment], float]:
    if callable(objective):
        return objective
    if objective in OBJECTIVES:
        return OBJECTIVES[objective][0]
    file, sep, name = objective.rpartition(":")
    if not sep or not file.endswith(".py"):
        raise ValueError(f"objective '{objective}': one of {', '.join(OBJECTIVES)}, or FILE.py:FUNCTION (a function "
                         f"of the afford.load result)")
    path = Path(file)
    if not path.is_file():
        raise ValueError(f"objective '{objective}': no file {path}")
    spec = importlib.util.spec_from_file_location(f"afford_objective_{path.stem}", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    if not callable(getattr(module, name, None)):
        raise ValueError(f"objective '{objective}': {path} has no function {name}")
    return getattr(module, name)
