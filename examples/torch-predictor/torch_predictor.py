"""A convolutional affordance and learning-progress predictor written with PyTorch (Debian's python3-torch),
as an afford.AffordancePredictor: in process (afford.run(..., affordance=TorchConv)) or as the predictors
process on the bus (/usr/bin/python3 -m afford.process predictors examples/torch-predictor/torch_predictor.py:TorchConv).

The paper's predictors are one perceptron per action over the focus image's pixels (section 2.3); the
paper's conclusions (section 5) point at more powerful learned models. This one shares a small
convolutional trunk between the actions:

    focus image (3 x side x side, /255) -> conv 3x3 stride 2 (8) -> tanh -> conv 3x3 stride 2 (8) -> tanh
        -> features -> affordance head: linear, one sigmoid output per action
                    -> learning-progress heads: one linear output per action, on the features (detached)

learn() takes one plain stochastic-gradient step on the acted action's logistic loss (binary cross-entropy
on the logit; the paper's perceptrons take the squared error through the sigmoid, the delta rule), then IMP's
learning-progress head of that action one
normalised least-mean-squares step towards the change the update made (after - before). relearn() (replay) takes the affordance step only.

Deterministic, so that the weights checksum, the checkpoints, replay and a live restart hold: one thread,
torch.use_deterministic_algorithms, float64 parameters, no optimiser state (plain SGD), and initial
weights drawn from the run's keyed generator (seed, purpose), not torch's. state(action) gives the
parameters themselves as numpy views (a checkpoint loaded into them is loaded into the network): action
0 holds the trunk and the affordance head, every action its learning-progress head.
"""
import numpy as np
import torch

import afford

torch.set_num_threads(1)
torch.use_deterministic_algorithms(True)

ACTIONS = 4


class TorchConv(afford.AffordancePredictor):
    kind = "torch-conv"
    channels = 8            # of each convolution
    learning_rate = 0.03    # of the affordance step (the network's own: the paper's rate is a perceptron's)
    lp_learning_rate = 0.1  # of the learning-progress step, normalised by 1 + |features|^2 (NLMS: stable)

    def __init__(self, config):
        super().__init__(config)
        side = config["eye"]["focus_side"]
        self.imp = config["system"] == "IMP"
        c = self.channels
        self.trunk = torch.nn.Sequential(
            torch.nn.Conv2d(3, c, 3, stride=2), torch.nn.Tanh(),
            torch.nn.Conv2d(c, c, 3, stride=2), torch.nn.Tanh(), torch.nn.Flatten()).double()
        features = self.trunk(torch.zeros(1, 3, side, side, dtype=torch.float64)).shape[1]
        self.affordance = torch.nn.Linear(features, ACTIONS).double()
        self.learning_progress = torch.nn.ModuleList(torch.nn.Linear(features, 1).double() for _ in range(ACTIONS))
        self._init(config["seed"], config["predictors"]["learning_progress"]["init_magnitude"])
        self._state = self._views()

    def _init(self, seed, lp_magnitude):
        """Glorot-uniform weights and zero biases from the run's keyed generator; the learning-progress heads
        at +-init_magnitude, as the paper's learning-progress perceptrons."""
        with torch.no_grad():
            k = 0
            for layer in [m for m in self.trunk if isinstance(m, torch.nn.Conv2d)] + [self.affordance]:
                w = layer.weight
                fan_in, fan_out = w[0].numel(), w.shape[0] * (w[0].numel() // w.shape[1])
                bound = (6.0 / (fan_in + fan_out)) ** 0.5
                rng = afford.KeyedRng(seed, 0, k, purpose="component")
                w.copy_(torch.tensor([(2 * rng.uniform(i) - 1) * bound for i in range(w.numel())],
                                     dtype=torch.float64).reshape(w.shape))
                layer.bias.zero_()
                k += 1
            for a, head in enumerate(self.learning_progress):
                rng = afford.KeyedRng(seed, 0, a, purpose="learning_progress_init")
                head.weight.copy_(torch.tensor([lp_magnitude if rng.bits(i) & 1 else -lp_magnitude
                                                for i in range(head.weight.numel())],
                                               dtype=torch.float64).reshape(head.weight.shape))
                head.bias.zero_()

    def _views(self):
        """Every parameter as a numpy array sharing its memory: per action, what state(action) gives."""
        shared = [p.detach().numpy() for p in list(self.trunk.parameters()) + list(self.affordance.parameters())]
        own = [[p.detach().numpy() for p in head.parameters()] for head in self.learning_progress]
        return [(shared if a == 0 else []) + own[a] for a in range(ACTIONS)]

    @staticmethod
    def _input(image):
        x = torch.from_numpy(np.ascontiguousarray(image, dtype=np.float64) / 255.0)
        return x.permute(2, 0, 1).unsqueeze(0)

    def predict(self, image):
        with torch.no_grad():
            f = self.trunk(self._input(image))
            affordance = torch.sigmoid(self.affordance(f))[0]
            lp = [float(head(f)[0, 0]) for head in self.learning_progress]
        return [float(v) for v in affordance], lp

    def _affordance_step(self, x, action, succeeded):
        """One step on the action's logistic loss (cross-entropy: unlike the squared error through the sigmoid, a
        confidently wrong output still learns); returns its output before the step."""
        for p in list(self.trunk.parameters()) + list(self.affordance.parameters()):
            p.grad = None
        z = self.affordance(self.trunk(x))[0, action]
        target = torch.tensor(1.0 if succeeded else 0.0, dtype=torch.float64)
        torch.nn.functional.binary_cross_entropy_with_logits(z, target).backward()
        y = torch.sigmoid(z.detach())
        with torch.no_grad():
            for p in list(self.trunk.parameters()) + list(self.affordance.parameters()):
                p -= self.learning_rate * p.grad
        return float(y)

    def learn(self, image, action, succeeded):
        x = self._input(image)
        before = self._affordance_step(x, action, succeeded)
        with torch.no_grad():
            f = self.trunk(x)
            after = float(torch.sigmoid(self.affordance(f))[0, action])
        head = self.learning_progress[action]
        head.weight.grad = head.bias.grad = None
        out = head(f)[0, 0]
        lp = float(out)
        if self.imp:
            (0.5 * ((after - before) - out) ** 2).backward()
            with torch.no_grad():
                rate = self.lp_learning_rate / (1.0 + float((f * f).sum()))
                for p in head.parameters():
                    p -= rate * p.grad
        return before, after, lp

    def relearn(self, image, action, succeeded):
        self._affordance_step(self._input(image), action, succeeded)

    def state(self, action):
        return self._state[action]
