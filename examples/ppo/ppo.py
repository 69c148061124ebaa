"""PPO on afford's environment, in one file (in the style of CleanRL's ppo_atari.py), with PyTorch from Debian.

    PYTHONPATH=build/python /usr/bin/python3 examples/ppo/ppo.py --scenario scenario1 --total-steps 40000 --out ~/ppo

The learner sees what afford.env.AffordVectorEnv gives: one image per world (the scene, the eye's window as a
mask, the scenario's goal; 150 x 150 x 7), one discrete action (act on what the eye's scan found, pass, or look
at one of grid x grid places and act), and the goal reward (minus the scene's distance to the goal, each step;
the episode ends when the scene matches the goal, or after --episode-steps steps). The reward is scaled by
--reward-scale (the distances are ~3e-4). Every --eval-every updates, --eval-episodes episodes on worlds of other
seeds are played with the policy's most likely action: their share of successes and steps to success go to
OUT/ppo_eval.csv (one row per evaluation, with the environment steps trained so far). OUT: --out, else a new
folder in the temporary directory (never inside the checkout).

Reproducible from --seed: one thread, deterministic algorithms, the worlds' seeds and the sampling keyed by it;
the same command gives the same OUT/ppo_eval.csv and the same final weights (their checksum is printed).
"""
from __future__ import annotations

import argparse
import csv
import hashlib
import json
import tempfile
import time
from pathlib import Path

import numpy as np
import torch
import torch.nn as nn
from torch.distributions.categorical import Categorical

from afford.env import AffordVectorEnv


def parse_args(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--scenario", default="scenario1", help="an extrinsic scenario (config/scenarios)")
    p.add_argument("--world", default="base", help="the experiment whose world it is")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--total-steps", type=int, default=40000, help="environment steps to train on, all worlds")
    p.add_argument("--num-envs", type=int, default=16)
    p.add_argument("--num-steps", type=int, default=64, help="steps per world per rollout")
    p.add_argument("--episode-steps", type=int, default=125,
                   help="an episode's steps at most (the planner's budget per extrinsic test: planner.budget)")
    p.add_argument("--grid", type=int, default=5, help="places to look at: grid x grid")
    p.add_argument("--reward-scale", type=float, default=100.0)
    p.add_argument("--lr", type=float, default=2.5e-4)
    p.add_argument("--gamma", type=float, default=0.99)
    p.add_argument("--gae-lambda", type=float, default=0.95)
    p.add_argument("--minibatches", type=int, default=4)
    p.add_argument("--update-epochs", type=int, default=4)
    p.add_argument("--clip", type=float, default=0.1)
    p.add_argument("--ent-coef", type=float, default=0.01)
    p.add_argument("--vf-coef", type=float, default=0.5)
    p.add_argument("--max-grad-norm", type=float, default=0.5)
    p.add_argument("--eval-every", type=int, default=4, help="updates between evaluations")
    p.add_argument("--eval-episodes", type=int, default=32)
    p.add_argument("--out", help="the folder written (default: a new one in the temporary directory)")
    return p.parse_args(argv)


def output_folder(given: str | None, prefix: str) -> Path:
    """The folder --out names, made if new; without --out, a new one in the temporary directory (never a folder
    inside the checkout that the command happens to be run from)."""
    out = Path(given) if given else Path(tempfile.mkdtemp(prefix=prefix))
    out.mkdir(parents=True, exist_ok=True)
    return out


def layer(m: nn.Module, std: float = np.sqrt(2), bias: float = 0.0) -> nn.Module:
    torch.nn.init.orthogonal_(m.weight, std)
    torch.nn.init.constant_(m.bias, bias)
    return m


class Agent(nn.Module):
    """CleanRL's Atari network, on the 150 x 150 x C image halved to 75 x 75."""

    def __init__(self, channels: int, actions: int):
        super().__init__()
        self.network = nn.Sequential(
            nn.AvgPool2d(2),
            layer(nn.Conv2d(channels, 32, 8, stride=4)), nn.ReLU(),
            layer(nn.Conv2d(32, 64, 4, stride=2)), nn.ReLU(),
            layer(nn.Conv2d(64, 64, 3, stride=1)), nn.ReLU(),
            nn.Flatten(),
            layer(nn.Linear(64 * 5 * 5, 256)), nn.ReLU())
        self.actor = layer(nn.Linear(256, actions), std=0.01)
        self.critic = layer(nn.Linear(256, 1), std=1)

    def hidden(self, x: torch.Tensor) -> torch.Tensor:
        return self.network(x.permute(0, 3, 1, 2).float() / 255.0)

    def value(self, x):
        return self.critic(self.hidden(x))

    def act(self, x, action=None):
        h = self.hidden(x)
        dist = Categorical(logits=self.actor(h))
        if action is None:
            action = dist.sample()
        return action, dist.log_prob(action), dist.entropy(), self.critic(h)


def checksum(model: nn.Module) -> str:
    h = hashlib.sha256()
    for t in model.state_dict().values():
        h.update(t.detach().cpu().numpy().tobytes())
    return h.hexdigest()[:16]


def evaluate(agent: Agent, a, seed: int) -> tuple[float, float, float]:
    """--eval-episodes episodes, one per world of seeds seed, seed + 1, ..., the most likely action each step:
    (share solved, median steps to a solution or nan, mean return unscaled)."""
    envs = AffordVectorEnv(a.eval_episodes, world=a.world, seed=seed, scenario=a.scenario, reward="goal",
                           grid=a.grid, set={"run.steps": a.episode_steps})
    obs, _ = envs.reset()
    done = np.zeros(a.eval_episodes, bool)
    solved, steps, returns = np.zeros(a.eval_episodes, bool), np.zeros(a.eval_episodes), np.zeros(a.eval_episodes)
    with torch.no_grad():
        while not done.all():
            action = agent.actor(agent.hidden(torch.as_tensor(obs))).argmax(1).numpy()
            obs, reward, terminated, truncated, info = envs.step(action)
            live = ~done
            returns[live] += reward[live]
            ended = (terminated | truncated) & live
            solved[terminated & live] = True
            if ended.any():
                steps[ended] = info["episode"]["l"][ended]
            done |= ended
    return float(solved.mean()), float(np.median(steps[solved])) if solved.any() else float("nan"), float(returns.mean())


def train(a) -> dict:
    torch.manual_seed(a.seed)
    torch.set_num_threads(1)
    torch.use_deterministic_algorithms(True)
    np.random.seed(a.seed)
    out = output_folder(a.out, "afford-ppo-")
    a.out = str(out)  # (in ppo_result.json's args: where it went)
    envs = AffordVectorEnv(a.num_envs, world=a.world, seed=a.seed * 1000, scenario=a.scenario, reward="goal",
                           grid=a.grid, set={"run.steps": a.episode_steps})
    shape = envs.single_observation_space.shape
    agent = Agent(shape[-1], envs.single_action_space.n)
    optimizer = torch.optim.Adam(agent.parameters(), lr=a.lr, eps=1e-5)
    batch = a.num_envs * a.num_steps
    minibatch = batch // a.minibatches
    updates = max(1, a.total_steps // batch)

    obs_buf = torch.zeros((a.num_steps, a.num_envs) + shape, dtype=torch.uint8)
    actions = torch.zeros((a.num_steps, a.num_envs), dtype=torch.long)
    logprobs, rewards, dones, values = (torch.zeros((a.num_steps, a.num_envs)) for _ in range(4))
    obs, _ = envs.reset()
    next_obs, next_done = torch.as_tensor(obs), torch.zeros(a.num_envs)
    rows, episodes, steps_done, began = [], [], 0, time.monotonic()
    eval_seed = a.seed * 1000 + 500  # worlds the learner never trains on

    def record(update: int):
        share, median, ret = evaluate(agent, a, eval_seed)
        rows.append({"update": update, "env_steps": steps_done, "success": share, "median_steps_to_success": median,
                     "mean_return": ret, "seconds": round(time.monotonic() - began, 1)})
        print(f"update {update}/{updates}: {steps_done} env steps, greedy success {share:.2f}, median steps "
              f"{median}, {rows[-1]['seconds']} s", flush=True)

    record(0)
    for update in range(1, updates + 1):
        optimizer.param_groups[0]["lr"] = a.lr * (1.0 - (update - 1.0) / updates)
        for step in range(a.num_steps):
            obs_buf[step], dones[step] = next_obs, next_done
            with torch.no_grad():
                action, logprob, _, value = agent.act(next_obs)
            values[step], actions[step], logprobs[step] = value.flatten(), action, logprob
            obs, reward, terminated, truncated, info = envs.step(action.numpy())
            steps_done += a.num_envs
            rewards[step] = torch.as_tensor(reward * a.reward_scale, dtype=torch.float32)
            next_obs, next_done = torch.as_tensor(obs), torch.as_tensor(terminated | truncated, dtype=torch.float32)
            if "_episode" in info:
                for i in np.flatnonzero(info["_episode"]):
                    episodes.append((steps_done, bool(terminated[i]), int(info["episode"]["l"][i])))
        with torch.no_grad():  # generalized advantage estimation
            next_value = agent.value(next_obs).reshape(1, -1)
            advantages = torch.zeros_like(rewards)
            last = 0
            for t in reversed(range(a.num_steps)):
                nonterminal = 1.0 - (next_done if t == a.num_steps - 1 else dones[t + 1])
                following = next_value if t == a.num_steps - 1 else values[t + 1]
                delta = rewards[t] + a.gamma * following * nonterminal - values[t]
                advantages[t] = last = delta + a.gamma * a.gae_lambda * nonterminal * last
            returns = advantages + values
        b_obs = obs_buf.reshape((-1,) + shape)
        b_logprobs, b_actions = logprobs.reshape(-1), actions.reshape(-1)
        b_advantages, b_returns, b_values = advantages.reshape(-1), returns.reshape(-1), values.reshape(-1)
        order = np.random.default_rng([a.seed, update]).permutation  # keyed by (seed, update)
        for epoch in range(a.update_epochs):
            index = order(batch)
            for start in range(0, batch, minibatch):
                mb = torch.as_tensor(index[start:start + minibatch])
                _, newlogprob, entropy, newvalue = agent.act(b_obs[mb], b_actions[mb])
                ratio = (newlogprob - b_logprobs[mb]).exp()
                adv = b_advantages[mb]
                adv = (adv - adv.mean()) / (adv.std() + 1e-8)
                pg_loss = torch.max(-adv * ratio, -adv * torch.clamp(ratio, 1 - a.clip, 1 + a.clip)).mean()
                v_clipped = b_values[mb] + torch.clamp(newvalue.view(-1) - b_values[mb], -a.clip, a.clip)
                v_loss = 0.5 * torch.max((newvalue.view(-1) - b_returns[mb]) ** 2,
                                         (v_clipped - b_returns[mb]) ** 2).mean()
                loss = pg_loss - a.ent_coef * entropy.mean() + a.vf_coef * v_loss
                optimizer.zero_grad()
                loss.backward()
                nn.utils.clip_grad_norm_(agent.parameters(), a.max_grad_norm)
                optimizer.step()
        if update % a.eval_every == 0 or update == updates:
            record(update)
    with open(out / "ppo_eval.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    with open(out / "ppo_episodes.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["env_steps", "solved", "length"])
        w.writerows(episodes)
    result = {"scenario": a.scenario, "seed": a.seed, "env_steps": steps_done, "updates": updates,
              "final_success": rows[-1]["success"], "final_median_steps": rows[-1]["median_steps_to_success"],
              "weights_checksum": checksum(agent), "seconds": round(time.monotonic() - began, 1),
              "args": vars(a)}
    (out / "ppo_result.json").write_text(json.dumps(result, indent=2) + "\n")
    torch.save(agent.state_dict(), out / "ppo_agent.pt")
    print(f"weights {result['weights_checksum']}; {out / 'ppo_eval.csv'}")
    return result


if __name__ == "__main__":
    train(parse_args())
