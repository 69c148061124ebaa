"""Affordance predictors written in Python for the tests: a port of the paper's, which must equal it."""
import math

import numpy as np

import afford


def sequential_dot(w, idx, x):
    """sum(w[idx] * x) added up in index order, as the C++ perceptron does (bit for bit)."""
    return float(np.cumsum(w[idx] * x)[-1])


class PyPerceptrons(afford.AffordancePredictor):
    """processes/predictors/affordance.cpp's paper kind in numpy: for each action, a sigmoid
    affordance perceptron and a linear learning-progress perceptron of the focus image."""

    kind = "py-perceptrons"

    def __init__(self, config):
        super().__init__(config)
        side = config["eye"]["focus_side"]
        p = config["predictors"]
        self.dim = side * side * 3 + 1
        self.rate = p["affordance"]["learning_rate"]
        self.lp_rate = p["learning_progress"]["learning_rate"]
        self.imp = config["system"] == "IMP"
        self.affordance = [np.zeros(self.dim) for _ in range(4)]
        magnitude = p["learning_progress"]["init_magnitude"]
        self.learning_progress = []
        for a in range(4):
            rng = afford.KeyedRng(config["seed"], 0, a, purpose="learning_progress_init")
            self.learning_progress.append(
                np.array([magnitude if rng.bits(i) & 1 else -magnitude for i in range(self.dim)]))

    def sparse(self, image):
        flat = image.reshape(-1)
        idx = np.flatnonzero(flat)
        return np.append(idx, self.dim - 1), np.append(flat[idx] / 255.0, 1.0)

    @staticmethod
    def sigmoid(a):
        return 1.0 / (1.0 + math.exp(-a))

    def predict(self, image):
        idx, x = self.sparse(image)
        return ([self.sigmoid(sequential_dot(w, idx, x)) for w in self.affordance],
                [sequential_dot(w, idx, x) for w in self.learning_progress])

    def train_affordance(self, idx, x, action, succeeded):
        w = self.affordance[action]
        y = self.sigmoid(sequential_dot(w, idx, x))
        delta = ((1.0 if succeeded else 0.0) - y) * (y * (1.0 - y))
        w[idx] += (self.rate * delta) * x
        return y

    def learn(self, image, action, succeeded):
        idx, x = self.sparse(image)
        before = self.train_affordance(idx, x, action, succeeded)
        after = self.sigmoid(sequential_dot(self.affordance[action], idx, x))
        lp_w = self.learning_progress[action]
        lp = sequential_dot(lp_w, idx, x)
        if self.imp:
            lp_w[idx] += (self.lp_rate * ((after - before) - lp)) * x
        return before, after, lp

    def relearn(self, image, action, succeeded):
        idx, x = self.sparse(image)
        self.train_affordance(idx, x, action, succeeded)

    def state(self, action):
        return [self.affordance[action], self.learning_progress[action]]


class Frozen(afford.AffordancePredictor):
    """Predicts 0.5 for everything and learns nothing: a component that differs from the paper's."""

    kind = "frozen"

    def __init__(self, config):
        super().__init__(config)
        self.calls = np.zeros(1)  # its whole state: how many times it was asked to learn

    def predict(self, image):
        return [0.5] * 4, [0.0] * 4

    def learn(self, image, action, succeeded):
        self.calls[0] += 1
        return 0.5, 0.5, 0.0

    def relearn(self, image, action, succeeded):
        pass

    def state(self, action):
        return [self.calls] if action == 0 else []
