"""An agent class for `composuite-eval --agent eval_agents:ClosingGripper` in the tests: what a
user's own agent looks like to the evaluation (a class with `act`, optionally `reset`)."""

import numpy as np


class ClosingGripper:
    """Holds the arm still and closes the gripper; counts its calls so the test can check them."""

    resets: list[tuple[str, int]] = []

    def reset(self, task: str, seed: int) -> None:
        ClosingGripper.resets.append((task, seed))

    def act(self, observation):
        assert observation.shape == (93,)
        return np.array([0.0] * 7 + [1.0])
