"""examples/ppo_train.py, the numpy PPO trainer: its gradients against finite differences, the
NEXT_STEP rollout masking on a scripted fake vector env, and short runs on Gymnasium's
Pendulum-v1 (no ROS involved). A few seconds on two cores."""

import csv
import importlib.util
import math
import subprocess
import sys
from pathlib import Path

import gymnasium
import numpy as np
import pytest
from gymnasium.spaces import Box
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

SCRIPT = Path(__file__).resolve().parents[2] / "examples" / "ppo_train.py"


def load_script():
    spec = importlib.util.spec_from_file_location("ppo_train", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    # dataclasses look their module up in sys.modules while the module executes
    sys.modules["ppo_train"] = module
    spec.loader.exec_module(module)
    return module


ppo = load_script()


# ------------------------------------------------------------------------------------------------
# 1. gradients
# ------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("seed", [0, 1, 2])
def test_analytic_gradients_match_finite_differences(seed):
    errors = ppo.check_gradients(seed=seed)
    assert errors["policy"] < 1e-4, errors
    assert errors["value"] < 1e-4, errors
    # the batch must exercise both branches of the clipped objective
    assert 0.0 < errors["clipped_fraction"] < 1.0, errors


def test_the_gradient_check_catches_a_wrong_gradient(monkeypatch):
    right = ppo.mlp_backward

    def off_by_a_bit(params, cache, d_out, **kwargs):
        grads = right(params, cache, d_out, **kwargs)
        grads[0] = grads[0] * 1.001
        return grads

    monkeypatch.setattr(ppo, "mlp_backward", off_by_a_bit)
    errors = ppo.check_gradients(seed=0)
    assert errors["policy"] > 1e-4 and errors["value"] > 1e-4, errors


def test_check_gradients_flag_exits_0():
    done = subprocess.run([sys.executable, str(SCRIPT), "--check-gradients"],
                          capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stdout + done.stderr
    assert "max relative error" in done.stdout


# ------------------------------------------------------------------------------------------------
# 3. NEXT_STEP masking on a scripted vector env
# ------------------------------------------------------------------------------------------------

class ScriptedVectorEnv(VectorEnv):
    """Env i runs episodes of exactly lengths[i] steps, ending them by termination if
    terminates[i] else by truncation, with Gymnasium's NEXT_STEP autoreset. The observation is
    (episode index, step within the episode); the reward of the k-th step of an episode is k.

    info["success"]: env 0 reports it on every step, true only on step 2 of odd episodes; env 1
    reports success=True only on its reset steps, which belong to no episode."""

    metadata = {"autoreset_mode": AutoresetMode.NEXT_STEP}

    def __init__(self, lengths=(3, 4), terminates=(True, False)):
        self.lengths, self.terminates = np.array(lengths), np.array(terminates)
        self.num_envs = len(lengths)
        self.single_observation_space = Box(-np.inf, np.inf, (2,), np.float64)
        self.single_action_space = Box(-1.0, 1.0, (1,), np.float32)
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self.actions_used = []  # the actions of non-reset steps, as the env received them

    def _obs(self):
        return np.stack([self.episode, self.step_in_ep], axis=1).astype(np.float64)

    def reset(self, *, seed=None, options=None):
        self.episode = np.zeros(self.num_envs, np.int64)
        self.step_in_ep = np.zeros(self.num_envs, np.int64)
        self.reset_pending = np.zeros(self.num_envs, bool)
        return self._obs(), {}

    def step(self, actions):
        n = self.num_envs
        rew, term, trunc = np.zeros(n), np.zeros(n, bool), np.zeros(n, bool)
        success, reported = np.zeros(n, bool), np.zeros(n, bool)
        for i in range(n):
            if self.reset_pending[i]:  # NEXT_STEP: ignore the action, start the next episode
                self.episode[i] += 1
                self.step_in_ep[i] = 0
                if i == 1:
                    success[i] = reported[i] = True
                continue
            self.actions_used.append(np.array(actions[i]))
            self.step_in_ep[i] += 1
            rew[i] = self.step_in_ep[i]
            if self.step_in_ep[i] == self.lengths[i]:
                (term if self.terminates[i] else trunc)[i] = True
            if i == 0:
                reported[i] = True
                success[i] = self.episode[i] % 2 == 1 and self.step_in_ep[i] == 2
        self.reset_pending = term | trunc
        return self._obs(), rew, term, trunc, {"success": success, "_success": reported}


def scripted_act(obs):
    """Actions outside the bounds (to see the clipping), value 10 x step-within-episode."""
    n = obs.shape[0]
    return np.full((n, 1), 5.0), np.zeros(n), 10.0 * obs[:, 1]


def test_rollout_masks_exactly_the_reset_steps_and_counts_episodes():
    env = ScriptedVectorEnv()
    collector = ppo.RolloutCollector(env, seed=0)

    first = collector.collect(10, scripted_act)
    # env 0: 3-step episodes then a reset step; env 1: 4-step episodes then a reset step
    assert first.valid[:, 0].tolist() == [1, 1, 1, 0, 1, 1, 1, 0, 1, 1]
    assert first.valid[:, 1].tolist() == [1, 1, 1, 1, 0, 1, 1, 1, 1, 0]
    assert np.flatnonzero(first.terminated[:, 0]).tolist() == [2, 6]
    assert np.flatnonzero(first.truncated[:, 1]).tolist() == [3, 8]
    assert not first.terminated[:, 1].any() and not first.truncated[:, 0].any()
    # the observation fed into a reset step is the final one of the episode that ended
    assert first.obs[3, 0].tolist() == [0, 3] and first.obs[4, 1].tolist() == [0, 4]
    assert [(e.ret, e.length, e.success) for e in first.episodes] == [
        (6.0, 3, False), (10.0, 4, None), (6.0, 3, True), (10.0, 4, None)]
    assert collector.total_steps == 20

    # episodes carry over the epoch boundary: env 0's third episode began in the first batch
    second = collector.collect(10, scripted_act)
    assert second.valid[:, 0].tolist() == [1, 0, 1, 1, 1, 0, 1, 1, 1, 0]
    assert second.valid[:, 1].tolist() == [1, 1, 1, 1, 0, 1, 1, 1, 1, 0]
    # (env 0 ends episodes 2, 3, 4 at t = 0, 4, 8; env 1 ends episodes 2, 3 at t = 3, 8)
    assert [(e.ret, e.length, e.success) for e in second.episodes] == [
        (6.0, 3, False), (10.0, 4, None), (6.0, 3, True), (6.0, 3, False), (10.0, 4, None)]
    assert collector.total_steps == 40

    # stored actions are the unclipped samples; the env only ever saw the clipped ones
    assert (first.act == 5.0).all()
    assert env.actions_used and all(a.tolist() == [1.0] for a in env.actions_used)


def test_advantages_bootstrap_truncations_not_terminations_and_skip_reset_steps():
    env = ScriptedVectorEnv()
    collector = ppo.RolloutCollector(env, seed=0)
    ro = collector.collect(10, scripted_act)
    ro.last_val = scripted_act(collector.obs)[2]
    gamma = 0.5
    adv, ret = ppo.compute_advantages(ro, gamma=gamma, lam=1.0)

    # env 0 terminates at t=2 (rewards 1, 2, 3): no bootstrap
    assert ret[:3, 0].tolist() == [1 + gamma * (2 + gamma * 3), 2 + gamma * 3, 3]
    # env 1 is truncated at t=3 in observation (0, 4): bootstrap V = 40
    assert ret[3, 1] == 4 + gamma * 40
    assert ret[2, 1] == 3 + gamma * ret[3, 1]
    # the epoch ends in env 0's third episode, after its step 2: bootstrap V = 20
    assert ret[9, 0] == 2 + gamma * 20 and ret[8, 0] == 1 + gamma * ret[9, 0]
    # reset steps carry nothing, and nothing flows through them
    assert (adv[~ro.valid] == 0).all() and (ret[~ro.valid] == 0).all()
    # with lambda = 1, GAE is the bootstrapped return minus the baseline
    np.testing.assert_allclose(adv[ro.valid], (ret - ro.val)[ro.valid], rtol=0, atol=1e-12)

    # lambda < 1 mixes in the one-step TD error: the terminal step's advantage is r - V
    adv_td, _ = ppo.compute_advantages(ro, gamma=gamma, lam=0.0)
    assert adv_td[2, 0] == 3 - 20
    assert adv_td[3, 1] == 4 + gamma * 40 - 30


def test_collector_refuses_same_step_autoreset():
    env = ScriptedVectorEnv()
    env.metadata = {"autoreset_mode": AutoresetMode.SAME_STEP}
    with pytest.raises(ValueError, match="NEXT_STEP"):
        ppo.RolloutCollector(env, seed=0)


# ------------------------------------------------------------------------------------------------
# 2 and 4. short runs on Pendulum-v1
# ------------------------------------------------------------------------------------------------

def run_pendulum(tmp_path: Path, name: str, seed: int = 42,
                 extra: list[str] = ()) -> tuple[list[str], list[dict], Path]:
    log, save = tmp_path / f"{name}.csv", tmp_path / f"{name}.npz"
    done = subprocess.run(
        [sys.executable, str(SCRIPT), "--gym-id", "Pendulum-v1", "--num-envs", "2",
         "--epochs", "2", "--steps-per-epoch", "400", "--max-ep-len", "100",
         "--pi-iters", "5", "--v-iters", "5", "--seed", str(seed),
         "--log", str(log), "--save", str(save), *extra],
        capture_output=True, text=True, timeout=120, cwd=tmp_path)
    assert done.returncode == 0, done.stdout + done.stderr
    assert len([line for line in done.stdout.splitlines() if line.startswith("epoch")]) == 2
    with open(log, newline="") as f:
        reader = csv.DictReader(f)
        return list(reader.fieldnames), list(reader), save


@pytest.fixture(scope="module")
def pendulum_run(tmp_path_factory):
    return run_pendulum(tmp_path_factory.mktemp("ppo"), "a")


def test_pendulum_run_writes_the_csv(pendulum_run):
    header, rows, _ = pendulum_run
    assert header == ppo.CSV_COLUMNS
    assert [int(r["epoch"]) for r in rows] == [1, 2]
    assert [int(r["total_steps"]) for r in rows] == [400, 800]
    for r in rows:
        assert r["success_rate"] == ""  # Pendulum reports no success
        for column in ppo.CSV_COLUMNS:
            if column != "success_rate":
                assert math.isfinite(float(r[column])), (column, r)
        assert float(r["ep_len_mean"]) == 100.0  # --max-ep-len 100 < Pendulum's own 200
        assert 1 <= int(r["pi_iters"]) <= 5
    # 200 steps per env and epoch: one 100-step episode per env in epoch 1 (a reset step
    # follows each), two per env in epoch 2
    assert [int(r["episodes"]) for r in rows] == [2, 4]


def test_pendulum_run_saves_parameters_shaped_by_the_spaces(pendulum_run):
    _, _, save = pendulum_run
    env = gymnasium.make("Pendulum-v1")
    obs_dim, act_dim = env.observation_space.shape[0], env.action_space.shape[0]
    env.close()
    expected = {
        "pi/W0": (obs_dim, 64), "pi/b0": (64,), "pi/W1": (64, 64), "pi/b1": (64,),
        "pi/W2": (64, act_dim), "pi/b2": (act_dim,), "log_std": (act_dim,),
        "v/W0": (obs_dim, 64), "v/b0": (64,), "v/W1": (64, 64), "v/b1": (64,),
        "v/W2": (64, 1), "v/b2": (1,),
    }
    with np.load(save) as params:
        assert {k: params[k].shape for k in params.files} == expected
        for k in params.files:
            assert np.isfinite(params[k]).all(), k
        # the paper's learner: the log-std is a constant, -0.5 on the last action dimension
        assert params["log_std"].tolist() == [-0.5] * act_dim


def test_the_policy_mean_is_squashed_and_the_log_std_learned_only_when_asked(tmp_path):
    # The paper's policy mean is tanh(MLP): inside (-1, 1) whatever the weights.
    rng = np.random.default_rng(0)
    agent = ppo.ActorCritic(5, 3, (8,), ppo.initial_log_std(3, 0.0, -0.5), rng)
    agent.pi[-3] *= 100.0  # a huge last layer: the mean saturates, never leaves the bounds
    mean = ppo.mlp_forward(agent.pi[:-1], rng.normal(size=(64, 5)), tanh_output=True)[0]
    assert np.abs(mean).max() <= 1.0 and np.abs(mean).max() > 0.99
    assert agent.pi[-1].tolist() == [0.0, 0.0, -0.5]
    # --learn-log-std trains it (Spinning Up's original)
    _, _, save = run_pendulum(tmp_path, "learned", extra=["--learn-log-std"])
    with np.load(save) as params:
        assert params["log_std"].shape == (1,) and params["log_std"][0] != -0.5


def test_same_seed_same_numbers(pendulum_run, tmp_path):
    _, rows_a, _ = pendulum_run
    _, rows_b, _ = run_pendulum(tmp_path, "b")
    _, rows_other, _ = run_pendulum(tmp_path, "other", seed=7)

    def numbers(rows):
        return [{k: v for k, v in r.items() if k not in ppo.TIMING_COLUMNS} for r in rows]

    assert numbers(rows_a) == numbers(rows_b)
    assert numbers(rows_a) != numbers(rows_other)  # the comparison is not vacuous


PLOT_SCRIPT = SCRIPT.with_name("plot_learning_curve.py")


def test_the_learning_curve_plot_draws_a_log_and_names_a_bad_one(pendulum_run, tmp_path):
    _, rows, save = pendulum_run
    log = save.with_suffix(".csv")
    png = tmp_path / "curve.png"
    done = subprocess.run([sys.executable, str(PLOT_SCRIPT), str(log), "--out", str(png),
                           "--return-line", "-500", "a baseline"], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    data = png.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    assert (int.from_bytes(data[16:20], "big"), int.from_bytes(data[20:24], "big")) == (800, 600)
    # A log with no finished episode, and a CSV that is not a log, are refused by name.
    empty = tmp_path / "empty.csv"
    empty.write_text(",".join(ppo.CSV_COLUMNS) + "\n1,400" + "," * (len(ppo.CSV_COLUMNS) - 2) + "\n")
    other = tmp_path / "other.csv"
    other.write_text("a,b\n1,2\n")
    done = subprocess.run([sys.executable, str(PLOT_SCRIPT), str(log), str(log), "--label", "only one",
                           "--out", str(tmp_path / "x.png")], capture_output=True, text=True, timeout=120)
    assert done.returncode != 0 and "1 --label for 2 logs" in done.stderr, done.stderr
    for path, says in ((empty, "no epoch with a finished episode"), (other, "not a ppo_train.py log")):
        done = subprocess.run([sys.executable, str(PLOT_SCRIPT), str(path), "--out", str(tmp_path / "x.png")],
                              capture_output=True, text=True, timeout=120)
        assert done.returncode != 0 and says in done.stderr and str(path) in done.stderr, done.stderr
