"""afford from Python (docs/python.md).

    import afford
    e = afford.load("out/base")              # an experiment folder as pandas data frames
    log = afford.read_log("logs/<run-id>")    # a run's messages, images as numpy arrays
    e = afford.run("base", system="IMP", reps=2, set={"motivation.leak": 0.3})  # in this process
"""
from . import _afford
from .components import (ACTIONS, GOAL_MODULES, AffordancePredictor, Decision, Goal, GoalChooser, KeyedRng,
                         Motivation, register_affordance, register_goals, register_motivation)
from .experiments import ExperimentError, replay, run
from .logs import Message, RunLog, read_log
from .results import Experiment, load

__version__ = _afford.version
ConfigError = _afford.ConfigError
channels = _afford.channels

__all__ = ["Motivation", "Decision", "KeyedRng", "ACTIONS", "register_motivation", "AffordancePredictor",
           "GoalChooser", "Goal", "GOAL_MODULES", "register_goals",
           "register_affordance", "run", "replay", "ExperimentError", "load", "Experiment", "read_log", "RunLog", "Message", "ConfigError", "channels"]
