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


def entropy_bits(p):
    if p <= 0.0 or p >= 1.0:
        return 0.0
    return -p * math.log2(p) - (1.0 - p) * math.log2(1.0 - p)


class PyPaper(afford.Motivation):
    """processes/motivation/motivation.cpp in Python, without revisits: FIX, IGN and IMP (paper 2.4.1)."""

    kind = "py-paper"

    def __init__(self, config):
        super().__init__(config)
        m = config["motivation"]
        self.system = config["system"]
        self.leak_rate, self.margin = m["leak"], m["act_margin"]
        self.observed = m["imp_threshold_input"] == "observed_change"
        self.threshold = m["fixed_threshold"] if self.system == "FIX" else m["initial_threshold"]
        self.awaiting = False  # IMP with observed_change: the threshold waits for the last action's change

    @property
    def needs_last_change(self):
        return self.awaiting

    def leak(self, x):
        self.threshold += self.leak_rate * (x - self.threshold)

    def decide(self, p):
        if self.awaiting:
            self.awaiting = False
            self.leak(p["last_change"])
        imp = self.system == "IMP"
        action, signal = -1, 0.0
        for a in range(4):
            s = abs(p["learning_progress"][a]) if imp else entropy_bits(p["affordance"][a])
            if action < 0 or s > signal:  # ties: the lowest action
                action, signal = a, s
        threshold = self.threshold
        act = signal + self.margin >= threshold
        if self.system != "FIX":
            if not act:
                self.leak(0.0)
            elif imp and self.observed:
                self.awaiting = True
            else:
                self.leak(signal)
        return afford.Decision(act, action, signal, threshold)


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


class ReturnsNothing(afford.Motivation):
    """A decide() that forgets to return (or returns a tuple): the run fails saying what decide() returns."""

    kind = "returns-nothing"

    def decide(self, p):
        if p["step"] == 3:
            return (True, 0)
        return None if p["step"] >= 2 else afford.Decision(False)
