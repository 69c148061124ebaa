"""afford from Python (docs/python.md).

    import afford
    e = afford.load("out/base")              # an experiment folder as pandas data frames
    log = afford.read_log("logs/<run-id>")    # a run's messages, images as numpy arrays
    e = afford.run("base", system="IMP", reps=2, set={"motivation.leak": 0.3})  # in this process
    s = afford.tune("studies/leak", "base", params={"motivation.leak": afford.Float(0.01, 0.9, log=True)})
"""
from . import _afford
from .components import (ACTIONS, GOAL_MODULES, AffordancePredictor, Decision, Goal, GoalChooser, KeyedRng,
                         Motivation, register_affordance, register_goals, register_motivation)
from .experiments import CurvePoint, ExperimentError, ExperimentStopped, check, replay, run
from .logs import LogCutWarning, Message, RunLog, read_log
from .results import Experiment, load
from .search import Choice, Float, Int
from .study import Study, load_study, tune

__version__ = _afford.version
ConfigError = _afford.ConfigError
channels = _afford.channels

__all__ = ["Motivation", "Decision", "KeyedRng", "ACTIONS", "register_motivation", "AffordancePredictor",
           "GoalChooser", "Goal", "GOAL_MODULES", "register_goals",
           "register_affordance", "run", "check", "replay", "ExperimentError", "ExperimentStopped", "CurvePoint", "load", "Experiment", "read_log", "RunLog", "Message", "LogCutWarning", "ConfigError", "channels",
           "tune", "load_study", "Study", "Float", "Int", "Choice"]
