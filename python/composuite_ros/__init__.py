"""Gymnasium environments over CompoSuite-ROS (the CompoSuite benchmark through ROS 2).

- `CompoSuiteRosEnv`: one environment of a running suite, registered as
  `composuite_ros/CompoSuite-v0` (`gymnasium.make("composuite_ros/CompoSuite-v0", task=...)`);
- `composuite_ros.vector.CompoSuiteRosVectorEnv`: N environments of `composuite launch --envs N`
  stepped concurrently;
- `composuite_ros.evaluate`: the paper's evaluation protocol (`composuite-eval`).
"""

from .env import CompoSuiteRosEnv, register_envs
from .errors import EpisodeOverError, StepLostError, SuiteNotRunningError
from .tasks import Task, all_tasks

__all__ = ["CompoSuiteRosEnv", "EpisodeOverError", "StepLostError", "SuiteNotRunningError", "Task",
           "all_tasks", "register_envs"]

register_envs()
