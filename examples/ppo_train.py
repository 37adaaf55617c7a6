"""PPO in pure numpy for Gymnasium vector environments: the CompoSuite paper's reference learner.

The algorithm follows OpenAI Spinning Up's PPO-clip as the CompoSuite paper used it (Mendez et
al., 2022; its learner is in the authors' fork of Spinning Up, `ppo/core.py`): a Gaussian policy
whose mean is a 2 x 64 tanh MLP with a tanh output layer and whose log-std is a fixed,
state-independent vector (0 on the seven joint dimensions, -0.5 on the gripper's, the last; not
trained — `--learn-log-std` trains it as Spinning Up's original does); a separate 2 x 64 tanh MLP
critic; GAE(lambda) advantages normalised
over the batch; discounted rewards-to-go as value targets; full-batch Adam steps (128 on the
clipped surrogate, stopped early once the approximate KL exceeds 1.5 x target_kl, then 128 on the
value MSE). Everything, including the backprop and Adam, is written out in numpy so that the
script runs anywhere Gymnasium does, without a deep-learning framework.

Usage

    # CompoSuite in-process (the default): the native vector env, one thread per core
    python examples/ppo_train.py --num-envs 2 --epochs 100 --log ppo.csv --save ppo.npz

    # over ROS 2: start the suite, then train against it (four environments /env_00 ... /env_03)
    composuite launch --envs 4 --task Jaco/dumbbell/object_door/shelf &
    python examples/ppo_train.py --backend ros --num-envs 4 --task Jaco/dumbbell/object_door/shelf

    # any Gymnasium environment with Box observations and actions (no ROS needed)
    python examples/ppo_train.py --gym-id Pendulum-v1 --num-envs 2 --epochs 20

    # verify the hand-written gradients against finite differences
    python examples/ppo_train.py --check-gradients

Every epoch prints one line and, with --log FILE.csv, appends one CSV row (see CSV_COLUMNS):
mean return, length and success rate are over the episodes that finished during the epoch (empty
if none did). --save PATH.npz stores the final parameters: `pi/W0, pi/b0, ...` (policy mean MLP,
layer k maps `h @ Wk + bk`, tanh after every layer, the last included), `log_std`, `v/W0, v/b0,
...` (critic; its last layer linear). To act with a saved policy: `mean = tanh(mlp(obs))`, then
clip to the action bounds.

Vector-env semantics (Gymnasium 1.x, autoreset mode NEXT_STEP): when env i ends an episode at step
t, the observation it returns is that episode's last one; at step t + 1 it ignores the action,
resets and returns the next episode's first observation with reward 0. That t + 1 transition is
not a transition of any episode, so it is masked out of the batch. The observation fed into step
t + 1 is therefore the final observation of the finished episode, and its value estimate is the
bootstrap of a time-limit truncation (terminations bootstrap 0). An epoch that stops in the middle
of an episode bootstraps with the value of the current observation.

Also usable as a library (the tests do): `RolloutCollector`, `compute_advantages`,
`policy_loss_and_grads`, `value_loss_and_grads`, `check_gradients`, `train`.
"""

from __future__ import annotations

import argparse
import json
import csv
import math
import os
import sys
import time
from dataclasses import dataclass, field

import numpy as np

LOG_2PI = math.log(2.0 * math.pi)

CSV_COLUMNS = [
    "epoch",          # 1-based
    "total_steps",    # env steps so far, summed over envs (reset steps included: they cost a step)
    "steps_per_s",    # env steps of this epoch / wall time of this epoch (rollout + update)
    "rollout_s",      # wall time collecting the epoch's steps
    "update_s",       # wall time of the policy and value updates
    "episodes",       # episodes that finished during the epoch
    "ep_return_mean",
    "ep_len_mean",
    "success_rate",   # empty if the env does not report info["success"]
    "approx_kl",      # mean(logp_old - logp) of the policy after the update
    "pi_iters",       # policy gradient steps taken (fewer than --pi-iters after an early stop)
    "v_loss",         # value MSE on the epoch's batch, before the value update
]
TIMING_COLUMNS = ("steps_per_s", "rollout_s", "update_s")


# ----------------------------------------------------------------------------------------------
# MLP with hand-written backprop
# ----------------------------------------------------------------------------------------------

def mlp_init(sizes: list[int], rng: np.random.Generator) -> list[np.ndarray]:
    """[W0, b0, W1, b1, ...] for layers sizes[k] -> sizes[k+1]. Uniform(+-1/sqrt(fan_in)) for
    weights and biases: PyTorch's default nn.Linear init, which Spinning Up relies on."""
    params = []
    for fan_in, fan_out in zip(sizes[:-1], sizes[1:]):
        bound = 1.0 / math.sqrt(fan_in)
        params.append(rng.uniform(-bound, bound, size=(fan_in, fan_out)))
        params.append(rng.uniform(-bound, bound, size=(fan_out,)))
    return params


def _tanh(z: np.ndarray) -> np.ndarray:
    """tanh(z) = 1 - 2 / (exp(2z) + 1), computed in place on z: about twice as fast as np.tanh
    on large batches here (np.exp is SIMD-vectorised, np.tanh is not in numpy 2.4's wheels).
    exp overflows to inf for z > ~354, which correctly gives 1."""
    with np.errstate(over="ignore"):
        np.multiply(z, 2.0, out=z)
        np.exp(z, out=z)
    z += 1.0
    np.divide(2.0, z, out=z)
    np.subtract(1.0, z, out=z)
    return z


def mlp_forward(params: list[np.ndarray], x: np.ndarray,
                tanh_output: bool = False) -> tuple[np.ndarray, list[np.ndarray]]:
    """Output and the cache backprop needs: the layer inputs, then (with `tanh_output`) the
    output itself. tanh after every hidden layer; the last layer is linear unless
    `tanh_output` (the paper's policy mean: MLP with a tanh output layer)."""
    layer_inputs = [x]
    h = x
    n_layers = len(params) // 2
    for k in range(n_layers):
        h = h @ params[2 * k] + params[2 * k + 1]
        if k < n_layers - 1 or tanh_output:
            h = _tanh(h)
            layer_inputs.append(h)
    return h, layer_inputs


def mlp_backward(params: list[np.ndarray], cache: list[np.ndarray], d_out: np.ndarray,
                 tanh_output: bool = False) -> list[np.ndarray]:
    """Gradients of a scalar loss w.r.t. [W0, b0, ...] given d loss / d output; `cache` and
    `tanh_output` as mlp_forward gave and took them."""
    n_layers = len(params) // 2
    grads: list[np.ndarray] = [np.empty(0)] * len(params)
    # gradient w.r.t. the current layer's pre-activation; tanh' = 1 - tanh^2
    d_pre = d_out - d_out * cache[n_layers] * cache[n_layers] if tanh_output else d_out
    for k in reversed(range(n_layers)):
        h_in = cache[k]
        grads[2 * k] = h_in.T @ d_pre
        grads[2 * k + 1] = d_pre.sum(axis=0)
        if k > 0:
            # h_in = tanh(z) for k > 0
            d_h = d_pre @ params[2 * k].T
            d_pre = d_h - d_h * h_in * h_in
    return grads


# ----------------------------------------------------------------------------------------------
# Policy and value losses
# ----------------------------------------------------------------------------------------------

def gaussian_log_prob(mean: np.ndarray, log_std: np.ndarray, act: np.ndarray) -> np.ndarray:
    z = (act - mean) / np.exp(log_std)
    return -0.5 * np.sum(z * z, axis=-1) - np.sum(log_std) - 0.5 * mean.shape[-1] * LOG_2PI


@dataclass
class PolicyInfo:
    approx_kl: float
    entropy: float
    clip_frac: float


def policy_loss_and_grads(pi_params: list[np.ndarray], obs: np.ndarray, act: np.ndarray,
                          adv: np.ndarray, logp_old: np.ndarray, clip_ratio: float,
                          ent_coef: float) -> tuple[float, list[np.ndarray], PolicyInfo]:
    """PPO-clip loss  -mean(min(r A, clip(r, 1-eps, 1+eps) A)) - ent_coef * entropy  and its
    gradient w.r.t. pi_params = [mean-MLP params..., log_std]."""
    mlp_params, log_std = pi_params[:-1], pi_params[-1]
    batch = obs.shape[0]
    mean, cache = mlp_forward(mlp_params, obs, tanh_output=True)
    std = np.exp(log_std)
    z = (act - mean) / std
    logp = -0.5 * np.sum(z * z, axis=1) - np.sum(log_std) - 0.5 * act.shape[1] * LOG_2PI
    ratio = np.exp(logp - logp_old)
    clipped = np.clip(ratio, 1.0 - clip_ratio, 1.0 + clip_ratio)
    unclipped_obj, clipped_obj = ratio * adv, clipped * adv
    entropy = float(np.sum(log_std) + 0.5 * act.shape[1] * (1.0 + LOG_2PI))
    loss = -float(np.mean(np.minimum(unclipped_obj, clipped_obj))) - ent_coef * entropy

    # The min picks the unclipped term wherever it is <= the clipped one (which includes every
    # sample with r inside the clip range); elsewhere the clipped term is flat in r.
    uses_unclipped = unclipped_obj <= clipped_obj
    d_ratio = np.where(uses_unclipped, -adv / batch, 0.0)
    d_logp = d_ratio * ratio
    d_mean = d_logp[:, None] * z / std                    # d logp / d mean = z / std
    d_log_std = d_logp @ (z * z - 1.0) - ent_coef         # d logp / d log_std = z^2 - 1
    grads = mlp_backward(mlp_params, cache, d_mean, tanh_output=True) + [d_log_std]

    info = PolicyInfo(
        approx_kl=float(np.mean(logp_old - logp)),
        entropy=entropy,
        clip_frac=float(np.mean(np.abs(ratio - 1.0) > clip_ratio)),
    )
    return loss, grads, info


def value_loss_and_grads(v_params: list[np.ndarray], obs: np.ndarray,
                         ret: np.ndarray) -> tuple[float, list[np.ndarray]]:
    """Mean squared error of V(obs) against the return targets, and its gradient."""
    out, cache = mlp_forward(v_params, obs)
    err = out[:, 0] - ret
    loss = float(np.mean(err * err))
    d_out = (2.0 / len(ret)) * err[:, None]
    return loss, mlp_backward(v_params, cache, d_out)


class Adam:
    """Adam with PyTorch's defaults (betas 0.9, 0.999, eps 1e-8), updating arrays in place."""

    def __init__(self, params: list[np.ndarray], lr: float,
                 betas: tuple[float, float] = (0.9, 0.999), eps: float = 1e-8):
        self.params, self.lr, self.eps = params, lr, eps
        self.beta1, self.beta2 = betas
        self.m = [np.zeros_like(p) for p in params]
        self.v = [np.zeros_like(p) for p in params]
        self.t = 0

    def step(self, grads: list[np.ndarray]) -> None:
        self.t += 1
        # bias corrections folded into the step size, as torch.optim.Adam does
        c1 = 1.0 - self.beta1 ** self.t
        c2 = 1.0 - self.beta2 ** self.t
        step_size = self.lr / c1
        for p, g, m, v in zip(self.params, grads, self.m, self.v):
            m *= self.beta1
            m += (1.0 - self.beta1) * g
            v *= self.beta2
            v += (1.0 - self.beta2) * g * g
            p -= step_size * m / (np.sqrt(v / c2) + self.eps)


# ----------------------------------------------------------------------------------------------
# Gradient check
# ----------------------------------------------------------------------------------------------

def _numeric_grads(loss_fn, params: list[np.ndarray], h: float = 1e-6) -> list[np.ndarray]:
    """Central finite differences of loss_fn() w.r.t. every entry of params (perturbed in place)."""
    grads = []
    for p in params:
        g = np.zeros_like(p)
        flat, g_flat = p.reshape(-1), g.reshape(-1)
        for i in range(flat.size):
            saved = flat[i]
            flat[i] = saved + h
            up = loss_fn()
            flat[i] = saved - h
            down = loss_fn()
            flat[i] = saved
            g_flat[i] = (up - down) / (2.0 * h)
        grads.append(g)
    return grads


def _relative_error(analytic: list[np.ndarray], numeric: list[np.ndarray]) -> float:
    """Largest per-entry |a - n| / max(|a| + |n|, 1e-8): the floor keeps entries whose gradient
    is (numerically) zero from dividing noise by noise."""
    worst = 0.0
    for a, n in zip(analytic, numeric):
        err = np.abs(a - n) / np.maximum(np.abs(a) + np.abs(n), 1e-8)
        worst = max(worst, float(err.max()))
    return worst


def check_gradients(seed: int = 0, batch: int = 16, obs_dim: int = 4, act_dim: int = 2,
                    hidden: tuple[int, ...] = (8, 8), clip_ratio: float = 0.2,
                    ent_coef: float = 0.01) -> dict[str, float]:
    """Compare the analytic gradients of both losses with finite differences on a tiny random
    batch, in float64. Old log-probs are perturbed so that some ratios fall outside the clip
    range and some advantages are negative: every branch of the clipped objective is exercised.
    Returns {"policy": max relative error, "value": ..., "clipped_fraction": ...}."""
    rng = np.random.default_rng(seed)
    obs = rng.normal(size=(batch, obs_dim))
    act = rng.normal(size=(batch, act_dim))
    adv = rng.normal(size=batch)
    ret = rng.normal(size=batch)
    pi_params = mlp_init([obs_dim, *hidden, act_dim], rng) + [rng.normal(scale=0.3, size=act_dim)]
    v_params = mlp_init([obs_dim, *hidden, 1], rng)
    mean, _ = mlp_forward(pi_params[:-1], obs, tanh_output=True)
    logp_old = gaussian_log_prob(mean, pi_params[-1], act) + rng.normal(scale=0.3, size=batch)

    _, pi_analytic, info = policy_loss_and_grads(pi_params, obs, act, adv, logp_old,
                                                 clip_ratio, ent_coef)
    pi_numeric = _numeric_grads(
        lambda: policy_loss_and_grads(pi_params, obs, act, adv, logp_old, clip_ratio,
                                      ent_coef)[0], pi_params)
    _, v_analytic = value_loss_and_grads(v_params, obs, ret)
    v_numeric = _numeric_grads(lambda: value_loss_and_grads(v_params, obs, ret)[0], v_params)
    return {
        "policy": _relative_error(pi_analytic, pi_numeric),
        "value": _relative_error(v_analytic, v_numeric),
        "clipped_fraction": info.clip_frac,
    }


# ----------------------------------------------------------------------------------------------
# Rollouts
# ----------------------------------------------------------------------------------------------

@dataclass
class Episode:
    ret: float
    length: int
    success: bool | None  # None: the env never reported info["success"] during the episode


@dataclass
class Rollout:
    """One epoch of experience, arrays shaped (T, num_envs, ...). valid[t, i] is False for the
    NEXT_STEP reset transitions, which belong to no episode."""
    obs: np.ndarray
    act: np.ndarray          # the unclipped Gaussian samples (what logp is of)
    logp: np.ndarray
    val: np.ndarray
    rew: np.ndarray
    terminated: np.ndarray
    truncated: np.ndarray
    valid: np.ndarray
    last_val: np.ndarray | None = None   # V(observation after the last step), filled by the caller
    episodes: list[Episode] = field(default_factory=list)


def _success_flags(info: dict, num_envs: int) -> tuple[np.ndarray, np.ndarray]:
    """(success, reported) per env from a vector info dict: Gymnasium puts a per-env array under
    "success" and a mask under "_success" saying which envs set the key this step."""
    if "success" not in info:
        return np.zeros(num_envs, bool), np.zeros(num_envs, bool)
    success = np.asarray(info["success"]).astype(bool).reshape(num_envs)
    reported = np.asarray(info.get("_success", np.ones(num_envs, bool))).astype(bool)
    return success & reported, reported.reshape(num_envs)


class RolloutCollector:
    """Steps a NEXT_STEP-autoreset vector env, keeping episode bookkeeping across epochs.

    act_fn(obs) -> (actions, logp, values) for a (num_envs, obs_dim) batch; actions are clipped
    to the action-space bounds before they reach the env, but stored unclipped."""

    def __init__(self, env, seed: int | None, recorder=None):
        mode = env.metadata.get("autoreset_mode")
        if mode is not None and getattr(mode, "name", str(mode)) not in ("NEXT_STEP", "NextStep"):
            raise ValueError(f"the vector env autoresets in mode {mode}; this trainer needs "
                             "NEXT_STEP (Gymnasium's default)")
        self.env = env
        self.num_envs = env.num_envs
        space = env.single_action_space
        self.act_low, self.act_high, self.act_dtype = space.low, space.high, space.dtype
        obs, info = env.reset(seed=seed)
        # Every episode the learner plays, for a medium-replay dataset (--dataset-out).
        self.recorder = recorder
        if recorder is not None:
            recorder.reset(obs, info)
        self.obs = np.asarray(obs, dtype=np.float64)
        # True where the last step ended an episode: that env's next step is a reset step
        self.reset_pending = np.zeros(self.num_envs, bool)
        self.ep_return = np.zeros(self.num_envs)
        self.ep_len = np.zeros(self.num_envs, dtype=np.int64)
        self.ep_success = np.zeros(self.num_envs, bool)
        self.ep_success_reported = np.zeros(self.num_envs, bool)
        self.total_steps = 0

    def collect(self, horizon: int, act_fn) -> Rollout:
        n, obs_dim = self.num_envs, self.obs.shape[1]
        act_dim = self.act_low.shape[0]
        ro = Rollout(
            obs=np.zeros((horizon, n, obs_dim)), act=np.zeros((horizon, n, act_dim)),
            logp=np.zeros((horizon, n)), val=np.zeros((horizon, n)), rew=np.zeros((horizon, n)),
            terminated=np.zeros((horizon, n), bool), truncated=np.zeros((horizon, n), bool),
            valid=np.zeros((horizon, n), bool))
        for t in range(horizon):
            act, logp, val = act_fn(self.obs)
            valid = ~self.reset_pending
            ro.obs[t], ro.act[t], ro.logp[t], ro.val[t], ro.valid[t] = self.obs, act, logp, val, valid

            env_act = np.clip(act, self.act_low, self.act_high).astype(self.act_dtype)
            obs, rew, terminated, truncated, info = self.env.step(env_act)
            if self.recorder is not None:
                self.recorder.step(env_act, obs, rew, terminated, truncated, info)
            self.total_steps += n
            terminated = np.asarray(terminated, bool) & valid
            truncated = np.asarray(truncated, bool) & valid
            rew = np.where(valid, np.asarray(rew, dtype=np.float64), 0.0)
            ro.rew[t], ro.terminated[t], ro.truncated[t] = rew, terminated, truncated

            # A reset step starts a fresh episode: its info (the reset's) is not part of any.
            self.ep_return = np.where(valid, self.ep_return + rew, 0.0)
            self.ep_len = np.where(valid, self.ep_len + 1, 0)
            success, reported = _success_flags(info, n)
            self.ep_success = np.where(valid, self.ep_success | success, False)
            self.ep_success_reported = np.where(valid, self.ep_success_reported | reported, False)

            done = terminated | truncated
            for i in np.flatnonzero(done):
                ro.episodes.append(Episode(
                    ret=float(self.ep_return[i]), length=int(self.ep_len[i]),
                    success=bool(self.ep_success[i]) if self.ep_success_reported[i] else None))
            self.reset_pending = done
            self.obs = np.asarray(obs, dtype=np.float64)
        return ro


def compute_advantages(ro: Rollout, gamma: float, lam: float) -> tuple[np.ndarray, np.ndarray]:
    """GAE(lambda) advantages and discounted rewards-to-go (the value targets), both (T, N), zero
    on masked rows. ro.last_val must hold V(observation after the last step)."""
    horizon = ro.rew.shape[0]
    # V of the observation following step t. Under NEXT_STEP this is, for an episode that ended
    # at t, V(its final observation): the right bootstrap for a truncation. Terminations get 0.
    next_val = np.concatenate([ro.val[1:], ro.last_val[None]], axis=0)
    next_val = np.where(ro.terminated, 0.0, next_val)
    continues = ~(ro.terminated | ro.truncated)   # the episode goes on at t + 1
    delta = ro.rew + gamma * next_val - ro.val

    adv = np.zeros_like(delta)
    ret = np.zeros_like(delta)
    adv_next = np.zeros(delta.shape[1])
    ret_next = ro.last_val.copy()
    for t in reversed(range(horizon)):
        adv[t] = delta[t] + gamma * lam * np.where(continues[t], adv_next, 0.0)
        ret[t] = ro.rew[t] + gamma * np.where(continues[t], ret_next, next_val[t])
        adv[t] *= ro.valid[t]
        ret[t] *= ro.valid[t]
        adv_next, ret_next = adv[t], ret[t]
    return adv, ret


# ----------------------------------------------------------------------------------------------
# Agent and training loop
# ----------------------------------------------------------------------------------------------

def initial_log_std(act_dim: int, init_log_std: float, last_log_std: float) -> np.ndarray:
    """The paper's learner: `init_log_std` on every action dimension but the last, which (the
    CompoSuite gripper) gets `last_log_std`."""
    log_std = np.full(act_dim, init_log_std)
    log_std[-1] = last_log_std
    return log_std


class ActorCritic:
    """Policy: a Gaussian whose mean is tanh(MLP(obs)) and whose log-std is state-independent
    (pi = [MLP params..., log_std]); critic: an MLP."""

    def __init__(self, obs_dim: int, act_dim: int, hidden: tuple[int, ...],
                 log_std: np.ndarray, rng: np.random.Generator, dtype=np.float64):
        self.pi = [p.astype(dtype) for p in mlp_init([obs_dim, *hidden, act_dim], rng)]
        self.pi.append(np.array(log_std, dtype=dtype))
        self.v = [p.astype(dtype) for p in mlp_init([obs_dim, *hidden, 1], rng)]

    def value(self, obs: np.ndarray) -> np.ndarray:
        return mlp_forward(self.v, obs)[0][:, 0]

    def act(self, obs: np.ndarray, rng: np.random.Generator):
        mean = mlp_forward(self.pi[:-1], obs, tanh_output=True)[0]
        log_std = self.pi[-1]
        act = mean + np.exp(log_std) * rng.standard_normal(mean.shape)
        return act, gaussian_log_prob(mean, log_std, act), self.value(obs)

    def save(self, path: str) -> None:
        arrays = {f"pi/{'W' if k % 2 == 0 else 'b'}{k // 2}": p for k, p in enumerate(self.pi[:-1])}
        arrays["log_std"] = self.pi[-1]
        arrays.update({f"v/{'W' if k % 2 == 0 else 'b'}{k // 2}": p for k, p in enumerate(self.v)})
        np.savez(path, **arrays)


def _mean_or_none(values):
    return float(np.mean(values)) if values else None


def _format(value, spec: str) -> str:
    return "-" if value is None else format(value, spec)


def make_env(args):
    """The vector env the flags ask for. The CompoSuite-ROS package is imported only here, so
    --gym-id runs need nothing but Gymnasium."""
    if args.gym_id:
        import gymnasium
        from gymnasium.wrappers import TimeLimit

        # An extra TimeLimit on top of the registered one: episodes end at --max-ep-len or at the
        # env's own limit, whichever comes first (Pendulum-v1's is 200).
        return gymnasium.make_vec(
            args.gym_id, num_envs=args.num_envs, vectorization_mode="sync",
            wrappers=[lambda env: TimeLimit(env, max_episode_steps=args.max_ep_len)])
    if args.backend == "native":
        from composuite_ros.native import CompoSuiteNativeVectorEnv

        return CompoSuiteNativeVectorEnv([args.task] * args.num_envs)
    from composuite_ros.vector import CompoSuiteRosVectorEnv

    return CompoSuiteRosVectorEnv(namespaces=args.namespaces, tasks=[args.task] * args.num_envs)


def train(args, env=None) -> list[dict]:
    """Run PPO; returns the per-epoch log rows (also printed, and appended to --log)."""
    if args.steps_per_epoch % args.num_envs:
        raise SystemExit("--steps-per-epoch must be a multiple of --num-envs")
    horizon = args.steps_per_epoch // args.num_envs
    env = env if env is not None else make_env(args)
    obs_space, act_space = env.single_observation_space, env.single_action_space
    if len(obs_space.shape) != 1 or len(act_space.shape) != 1:
        raise SystemExit("needs flat Box observation and action spaces")

    rng = np.random.default_rng(args.seed)
    act_dim = act_space.shape[0]
    # Parameters and the update in float32 by default, as the paper's PyTorch learner: 2.5x
    # faster full-batch iterations than float64 here. Rollouts keep float64 observations.
    dtype = np.dtype(args.dtype)
    agent = ActorCritic(obs_space.shape[0], act_dim, tuple(args.hidden),
                        initial_log_std(act_dim, args.init_log_std, args.last_log_std), rng, dtype)
    # The paper's learner keeps the log-std fixed (a constant, not a parameter); Spinning Up's
    # original learns it (--learn-log-std).
    trained_pi = agent.pi if args.learn_log_std else agent.pi[:-1]
    pi_opt, v_opt = Adam(trained_pi, args.pi_lr), Adam(agent.v, args.v_lr)
    recorder = None
    if args.dataset_out:
        from composuite_ros.datasets.run_recorder import RunRecorder

        recorder = RunRecorder(args.dataset_out, env, attrs={
            "learner": "examples/ppo_train.py (PPO, the paper's learner)",
            "learner_args": json.dumps({k: v for k, v in vars(args).items()
                                        if isinstance(v, (int, float, str, list, type(None)))})})
    collector = RolloutCollector(env, seed=args.seed, recorder=recorder)
    rows = []
    try:
        for epoch in range(1, args.epochs + 1):
            t_start = time.perf_counter()
            ro = collector.collect(horizon, lambda obs: agent.act(obs, rng))
            ro.last_val = agent.value(collector.obs)
            adv, ret = compute_advantages(ro, args.gamma, args.lam)
            t_rollout = time.perf_counter()

            keep = ro.valid.reshape(-1)
            obs = ro.obs.reshape(-1, ro.obs.shape[-1])[keep].astype(dtype)
            act = ro.act.reshape(-1, ro.act.shape[-1])[keep].astype(dtype)
            logp_old = ro.logp.reshape(-1)[keep].astype(dtype)
            ret = ret.reshape(-1)[keep].astype(dtype)
            adv = adv.reshape(-1)[keep]
            adv = ((adv - adv.mean()) / (adv.std() + 1e-8)).astype(dtype)

            pi_iters = 0
            for _ in range(args.pi_iters):
                _, grads, info = policy_loss_and_grads(agent.pi, obs, act, adv, logp_old,
                                                       args.clip_ratio, args.ent_coef)
                # the KL is measured before stepping, so the stop happens at the first
                # iterate whose distance from the data-collecting policy is too large
                if info.approx_kl > 1.5 * args.target_kl:
                    break
                pi_opt.step(grads[:len(trained_pi)])
                pi_iters += 1
            _, _, info = policy_loss_and_grads(agent.pi, obs, act, adv, logp_old,
                                               args.clip_ratio, args.ent_coef)

            v_loss_before = None
            for k in range(args.v_iters):
                loss, grads = value_loss_and_grads(agent.v, obs, ret)
                if k == 0:
                    v_loss_before = loss
                v_opt.step(grads)
            if v_loss_before is None:
                v_loss_before = value_loss_and_grads(agent.v, obs, ret)[0]
            t_end = time.perf_counter()

            successes = [e.success for e in ro.episodes if e.success is not None]
            row = {
                "epoch": epoch,
                "total_steps": collector.total_steps,
                "steps_per_s": horizon * args.num_envs / (t_end - t_start),
                "rollout_s": t_rollout - t_start,
                "update_s": t_end - t_rollout,
                "episodes": len(ro.episodes),
                "ep_return_mean": _mean_or_none([e.ret for e in ro.episodes]),
                "ep_len_mean": _mean_or_none([e.length for e in ro.episodes]),
                "success_rate": _mean_or_none(successes),
                "approx_kl": info.approx_kl,
                "pi_iters": pi_iters,
                "v_loss": v_loss_before,
            }
            rows.append(row)
            print(f"epoch {epoch:4d} | steps {row['total_steps']:9d} | "
                  f"{row['steps_per_s']:7.0f} steps/s | episodes {row['episodes']:4d} | "
                  f"return {_format(row['ep_return_mean'], '10.2f')} | "
                  f"len {_format(row['ep_len_mean'], '6.1f')} | "
                  f"success {_format(row['success_rate'], '.3f')} | "
                  f"kl {row['approx_kl']:.5f} | pi_iters {pi_iters:3d} | "
                  f"v_loss {row['v_loss']:.4g}", flush=True)
            if args.log:
                _append_csv(args.log, row)
    finally:
        env.close()
        if recorder is not None:
            recorder.close()
            print(f"run file {args.dataset_out}: {recorder.episodes} episodes, {recorder.rows} rows "
                  "(composuite-dataset subsample makes a medium-replay dataset of it)", flush=True)
    if args.save:
        agent.save(args.save)
    return rows


def _append_csv(path: str, row: dict) -> None:
    write_header = not os.path.exists(path) or os.path.getsize(path) == 0
    with open(path, "a", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=CSV_COLUMNS)
        if write_header:
            writer.writeheader()
        # repr-precision floats, so that identical runs give identical files
        writer.writerow({k: "" if v is None else repr(v) if isinstance(v, float) else v
                         for k, v in row.items()})


# ----------------------------------------------------------------------------------------------
# Command line
# ----------------------------------------------------------------------------------------------

EXAMPLES = """examples:
  python %(prog)s --num-envs 2 --log ppo.csv --save ppo.npz       # in-process
  composuite launch --envs 4 &        # the CompoSuite-ROS suite, envs /env_00 ... /env_03
  python %(prog)s --backend ros --num-envs 4 --log ppo.csv --save ppo.npz
  python %(prog)s --gym-id Pendulum-v1 --num-envs 2 --epochs 20
  python %(prog)s --check-gradients"""


class _HelpFormatter(argparse.ArgumentDefaultsHelpFormatter, argparse.RawDescriptionHelpFormatter):
    """Shows "(default: ...)" only for flags whose default says something (not None/False)."""

    def _get_help_string(self, action):
        if action.default in (None, False):
            return action.help
        return super()._get_help_string(action)


def parse_args(argv=None):
    p = argparse.ArgumentParser(
        description="PPO (Spinning Up style, pure numpy) on CompoSuite-ROS or a Gymnasium env.\n"
                    "Defaults are the CompoSuite paper's reference PPO settings.",
        epilog=EXAMPLES, formatter_class=_HelpFormatter)
    env = p.add_argument_group("environment")
    env.add_argument("--gym-id", default=None,
                     help="train on this Gymnasium env id (e.g. Pendulum-v1) instead of "
                          "CompoSuite-ROS; built with gymnasium.make_vec(..., 'sync')")
    env.add_argument("--task", default="IIWA/box/no_obstacle/pick_place",
                     help="CompoSuite task robot/object/obstacle/objective, for every env")
    env.add_argument("--backend", choices=["native", "ros"], default=None,
                     help="native: CompoSuite in-process (composuite_ros.native, the default); ros: "
                          "the running suite's environments over ROS 2 (the default when "
                          "--namespaces are given)")
    env.add_argument("--namespaces", default=None,
                     help="--backend ros: comma-separated ROS namespaces of the running suite's envs; default "
                          "'/' for one env, '/env_00,...' for N (what `composuite launch "
                          "--envs N` uses)")
    env.add_argument("--num-envs", type=int, default=None,
                     help="parallel envs (default: the number of --namespaces, else 1)")
    env.add_argument("--max-ep-len", type=int, default=500,
                     help="episode length cap for --gym-id envs (their own limit still applies "
                          "if shorter); CompoSuite episodes end at the horizon (500; over ROS the "
                          "suite's)")

    ppo = p.add_argument_group("PPO")
    ppo.add_argument("--seed", type=int, default=42,
                     help="seeds the parameter init, the action noise and env.reset")
    ppo.add_argument("--epochs", type=int, default=50, help="number of epochs to train")
    ppo.add_argument("--steps-per-epoch", type=int, default=16000,
                     help="env steps per epoch summed over all envs (a multiple of --num-envs)")
    ppo.add_argument("--gamma", type=float, default=0.99, help="discount factor")
    ppo.add_argument("--lam", type=float, default=0.97, help="GAE lambda")
    ppo.add_argument("--clip-ratio", type=float, default=0.2,
                     help="PPO clip range: ratios are clipped to [1 - c, 1 + c]")
    ppo.add_argument("--pi-lr", type=float, default=1e-4, help="policy Adam learning rate")
    ppo.add_argument("--v-lr", type=float, default=1e-4, help="value Adam learning rate")
    ppo.add_argument("--pi-iters", type=int, default=128,
                     help="max full-batch policy gradient steps per epoch")
    ppo.add_argument("--v-iters", type=int, default=128,
                     help="full-batch value gradient steps per epoch")
    ppo.add_argument("--target-kl", type=float, default=0.02,
                     help="policy steps stop once approx KL > 1.5 x this")
    ppo.add_argument("--ent-coef", type=float, default=0.0, help="entropy bonus coefficient")
    ppo.add_argument("--init-log-std", type=float, default=0.0,
                     help="the (state-independent) policy log-std of every action dimension "
                          "but the last")
    ppo.add_argument("--last-log-std", type=float, default=-0.5,
                     help="the log-std of the last action dimension (CompoSuite's gripper), as "
                          "the paper's learner sets it")
    ppo.add_argument("--learn-log-std", action="store_true",
                     help="train the log-std with the policy (Spinning Up's original); the "
                          "paper's learner keeps it fixed")
    ppo.add_argument("--dtype", choices=["float32", "float64"], default="float32",
                     help="floating-point type of the parameters and the update (the paper's "
                          "PyTorch learner: float32)")
    ppo.add_argument("--hidden", type=int, nargs="+", default=[64, 64],
                     help="hidden layer sizes of both MLPs (tanh)")

    out = p.add_argument_group("output")
    out.add_argument("--log", default=None, metavar="FILE.csv",
                     help="append one CSV row per epoch (header written if the file is new)")
    out.add_argument("--save", default=None, metavar="PATH.npz",
                     help="save the final parameters (numpy .npz) here")
    out.add_argument("--dataset-out", default=None, metavar="RUN.hdf5",
                     help="record every episode the learner plays (in-process backend) into a "
                          "run file; `composuite-dataset subsample RUN.hdf5` turns it into a "
                          "medium-replay offline dataset")
    out.add_argument("--check-gradients", action="store_true",
                     help="only compare the analytic gradients with finite differences and exit "
                          "(status 1 if a relative error is >= 1e-4)")
    args = p.parse_args(argv)

    if args.backend is None:
        args.backend = "ros" if args.namespaces is not None else "native"
    if args.backend == "native" and args.namespaces is not None:
        p.error("--namespaces name the suite's environments: use them with --backend ros")
    if args.namespaces is not None:
        args.namespaces = [ns.strip() for ns in args.namespaces.split(",") if ns.strip()]
        if args.num_envs is None:
            args.num_envs = len(args.namespaces)
        elif args.num_envs != len(args.namespaces):
            p.error("--num-envs differs from the number of --namespaces")
    if args.num_envs is None:
        args.num_envs = 1
    if args.dataset_out and (args.gym_id or args.backend != "native"):
        p.error("--dataset-out records the in-process CompoSuite env: use it with --backend native")
    if args.num_envs < 1:
        p.error("--num-envs must be >= 1")
    if args.namespaces is None:
        args.namespaces = ["/"] if args.num_envs == 1 else [f"/env_{i:02}" for i in range(args.num_envs)]
    return args


def main(argv=None) -> int:
    args = parse_args(argv)
    if args.check_gradients:
        errors = check_gradients(seed=args.seed)
        print(f"max relative error: policy {errors['policy']:.2e}, value {errors['value']:.2e} "
              f"(clipped fraction of the test batch {errors['clipped_fraction']:.2f})")
        return 0 if max(errors["policy"], errors["value"]) < 1e-4 else 1
    train(args)
    return 0


if __name__ == "__main__":
    sys.exit(main())
