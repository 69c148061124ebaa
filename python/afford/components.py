"""Components written in Python (docs/python.md#components-in-python).

A motivation is a class constructed with the run's configuration (a dict:
experiment, system, seed, steps, motivation_kind) whose decide(percept)
says, each step, whether to act and with which action. It stands in for
the shipped motivation in this process (afford.run(..., motivation=Cls)) or
as a process on the bus (python3 -m afford.process motivation MODULE:CLASS).
For exact replay and live restart, its state must be a pure function of the
percepts it was given, in order, and of the configuration; its randomness
comes from KeyedRng(config["seed"], step, sub), never from a clock or a
global generator.
"""
from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Any

from . import _afford

ACTIONS = ("move", "turn green", "turn red", "turn blue")  # the action ids 0..3


@dataclass
class Decision:
    act: bool                 # act this step, or pass
    action: int = -1          # 0..3 (ACTIONS) when acting
    motivation: float = 0.0   # the signal, which DECISION reports
    threshold: float = 0.0    # ... and what it was compared with


class Motivation:
    """A base for a motivation in Python (duck typing works as well).

    decide(percept) gets a dict: step; affordance and learning_progress
    (numpy arrays of the 4 actions); with needs_memory, look (which look the
    focused object is, -1 without) and tried_ago (steps since each action was
    tried on it, -1: never); with needs_last_change, last_change (|change|
    the previous step's action caused). It returns a Decision (or a dict or
    an object with act, action, motivation, threshold).
    """

    kind: str = ""                # motivation.kind naming it (default: the class name in lower case)
    needs_memory: bool = False
    needs_last_change: bool = False

    def __init__(self, config: dict[str, Any]):
        self.config = config

    def decide(self, percept: dict[str, Any]) -> Decision:
        raise NotImplementedError


class KeyedRng:
    """The run's keyed generator for a component: the draws of (seed, step, sub), whenever made.

    The C++ generator itself (KeyedRng(seed, step, Purpose::Component, sub)), so
    a component draws the same in Python as in C++.
    """

    def __init__(self, seed: int, step: int, sub: int):
        self._rng = _afford.KeyedRng(seed, step, sub)

    def bits(self, i: int = 0) -> int:
        return self._rng.bits(i)

    def uniform(self, i: int = 0) -> float:
        return self._rng.uniform(i)

    def integer(self, n: int, i: int = 0) -> int:
        """In [0, n), from the i-th draw."""
        return self.bits(i) % n


_NAME = re.compile(r"^[a-z0-9_-]{1,64}$")


def kind_of(cls: Any) -> str:
    kind = getattr(cls, "kind", "") or cls.__name__.lower()
    if not _NAME.match(kind):
        raise ValueError(f"motivation kind {kind!r} of {cls!r}: use lower-case letters, digits, '_' or '-' "
                         "(set the class attribute `kind`)")
    return kind


def register_motivation(cls: Any, kind: str | None = None) -> str:
    """Make `cls` the motivation of motivation.kind `kind` (default: kind_of(cls)) in this process."""
    kind = kind or kind_of(cls)
    if not _NAME.match(kind):
        raise ValueError(f"motivation kind {kind!r}: use lower-case letters, digits, '_' or '-'")
    if not callable(getattr(cls, "decide", None)):
        raise TypeError(f"{cls!r} has no decide(percept)")
    _afford.register_motivation(kind, cls)
    return kind
