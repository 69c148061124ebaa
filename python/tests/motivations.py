"""Motivations written in Python for the tests: ports of the C++ ones, which they must equal."""
import math

import afford


class PyNovelty(afford.Motivation):
    """processes/motivation/novelty.cpp in Python: the same decisions, so the same weights."""

    kind = "py-novelty"
    needs_memory = True

    def __init__(self, config):
        super().__init__(config)
        self.counts = {}  # look -> times each action was chosen on it
        self.threshold = 0.1  # motivation.novelty.threshold's default

    def decide(self, p):
        n = self.counts.setdefault(p["look"], [0] * 4)
        least = min(range(4), key=lambda a: (n[a], a))
        signal = 1.0 / math.sqrt(1.0 + n[least])
        act = signal >= self.threshold
        if act:
            n[least] += 1
        return afford.Decision(act, least, signal, self.threshold)


class PyRandom(afford.Motivation):
    """examples/random-motivation in Python: an action drawn for each step from the keyed generator."""

    kind = "py-random"
    MINE = 0x72616E646F6D  # the C++ example's sub-key ("random")

    def decide(self, p):
        rng = afford.KeyedRng(self.config["seed"], p["step"], self.MINE)
        return {"act": True, "action": rng.integer(4), "motivation": 1.0, "threshold": 0.0}


class Broken(afford.Motivation):
    kind = "broken"

    def decide(self, p):
        if p["step"] == 7:
            raise ValueError("no decision at step seven")
        return afford.Decision(False)
