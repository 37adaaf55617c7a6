"""Offline RL end to end on one task: expert data written by the suite, d3rlpy's behaviour
cloning (BC) trained on it, and the cloned policy evaluated in-process with `composuite-eval`'s
protocol beside the expert on the same seeds.

    pip install './python[d3rlpy]'            # h5py and d3rlpy 2.x (which pulls in torch)
    python examples/offline_bc.py --task IIWA/box/no_obstacle/pick_place --out runs/bc

1. `composuite-dataset generate --types expert` for the task (`--transitions`, default 100,000
   rows: 200 episodes of 500 steps, seeds 0 on), into OUT/data (kept and reused when present).
2. `datasets.to_d3rlpy` turns the file into d3rlpy's `MDPDataset`; `BCConfig` (d3rlpy's
   defaults but for the batch of 256 and standardised observations) is fitted for `--steps` gradient steps on the CPU and
   saved as OUT/bc.d3.
3. `composuite_ros.evaluate` runs `--episodes` episodes of the task (seeds `--eval-seed` on,
   none of them in the data) with the class `BCAgent` below as the agent — as
   `composuite-eval --tasks TASK --agent offline_bc:BCAgent` would, with COMPOSUITE_BC_MODEL
   naming the saved policy — and the same episodes are played by the expert. Both success
   rates and mean returns are printed and written to OUT/result.json. The agent reads the
   regressed gripper value as the nearest of the expert's -1, 0, +1 (the environment moves the
   gripper by the value's sign, so a value near 0 would move it every step: without this the
   cloned policy never closes on the object; COMPOSUITE_BC_RAW_GRIPPER=1 turns it off).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

import numpy as np

from composuite_ros import datasets, evaluate
from composuite_ros.datasets import medium

MODEL_VARIABLE = "COMPOSUITE_BC_MODEL"
ROUND_GRIPPER = os.environ.get("COMPOSUITE_BC_RAW_GRIPPER") != "1"


class BCAgent:
    """`composuite-eval`'s agent interface over a saved d3rlpy policy: the file named by the
    environment variable COMPOSUITE_BC_MODEL, loaded once per environment."""

    def __init__(self):
        import d3rlpy
        path = os.environ.get(MODEL_VARIABLE)
        if not path:
            raise RuntimeError(f"set {MODEL_VARIABLE} to the saved policy (OUT/bc.d3)")
        self.policy = d3rlpy.load_learnable(path, device="cpu:0")

    def act(self, observation):
        action = np.clip(self.policy.predict(np.asarray(observation, dtype=np.float32)[None])[0],
                         -1.0, 1.0)
        if ROUND_GRIPPER:
            # The expert's gripper values are -1, 0 and +1 (open, hold, close), and the
            # environment moves the gripper by the sign of the value: a regressed value near 0
            # would move it every step. Read it as the nearest of the three.
            action[7] = np.round(action[7])
        return action


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter,
                                     epilog=__doc__.split("\n\n", 1)[1])
    parser.add_argument("--task", default="IIWA/box/no_obstacle/pick_place")
    parser.add_argument("--out", type=Path, default=Path("runs/bc"))
    parser.add_argument("--transitions", type=int, default=100_000, help="rows of expert data")
    parser.add_argument("--steps", type=int, default=30_000, help="BC gradient steps")
    parser.add_argument("--episodes", type=int, default=20, help="evaluation episodes")
    parser.add_argument("--eval-seed", type=int, default=10_000,
                        help="seed of the first evaluation episode (the data starts at 0)")
    parser.add_argument("--seed", type=int, default=0, help="d3rlpy's and torch's seed")
    args = parser.parse_args()
    import d3rlpy

    [task] = datasets.select_tasks([args.task])
    started = time.monotonic()
    data_root = args.out / "data"
    if not datasets.task_file(data_root, "expert", task).exists():
        print(f"1. expert data: {args.transitions:,} rows of {task.task}", flush=True)
        datasets.generate(data_root, [task], ["expert"], transitions=args.transitions,
                          overwrite=True, progress=lambda line: print("  " + line, flush=True))
    data = datasets.load(data_root, "expert", tasks=[task.folder])
    won = data.parts[0].episode_successes()
    print(f"   {len(data):,} rows, {len(won)} episodes, {won.mean():.0%} of them succeed "
          f"({time.monotonic() - started:.0f} s)", flush=True)

    print(f"2. BC: {args.steps:,} steps on the CPU", flush=True)
    d3rlpy.seed(args.seed)
    bc = d3rlpy.algos.BCConfig(
        batch_size=256, observation_scaler=d3rlpy.preprocessing.StandardObservationScaler()
    ).create(device="cpu:0")
    fit_started = time.monotonic()
    bc.fit(datasets.to_d3rlpy(data), n_steps=args.steps,
           n_steps_per_epoch=max(args.steps // 10, 1), show_progress=False,
           save_interval=args.steps + 1, experiment_name="offline_bc", with_timestamp=False,
           logger_adapter=d3rlpy.logging.NoopAdapterFactory())
    model = args.out / "bc.d3"
    bc.save(str(model))
    fit_seconds = time.monotonic() - fit_started
    print(f"   saved {model} ({fit_seconds:.0f} s)", flush=True)

    print(f"3. evaluation: {args.episodes} episodes from seed {args.eval_seed:,}", flush=True)
    os.environ[MODEL_VARIABLE] = str(model)
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    _, results, _ = evaluate.evaluate(backend="native", tasks=[str(task.task)],
                                      episodes=args.episodes, seed=args.eval_seed,
                                      agent="offline_bc:BCAgent", envs=1, progress=False)
    bc_success = float(np.mean([r.success for r in results]))
    bc_return = float(np.mean([r.episode_return for r in results]))
    expert_success = medium.success_rate(str(task.task), 0.0, episodes=args.episodes,
                                         first_seed=args.eval_seed, threads=2)
    result = {"task": str(task.task), "rows": len(data), "episodes_in_data": int(len(won)),
              "data_success": float(won.mean()), "bc_steps": args.steps,
              "bc_fit_seconds": fit_seconds, "eval_episodes": args.episodes,
              "eval_first_seed": args.eval_seed, "bc_success": bc_success,
              "bc_mean_return": bc_return, "expert_success": expert_success}
    (args.out / "result.json").write_text(json.dumps(result, indent=1) + "\n")
    print(f"   BC success {bc_success:.0%} (mean return {bc_return:.1f}); the expert on the same "
          f"seeds {expert_success:.0%}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
