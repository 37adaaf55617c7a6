"""The CompoSuite benchmark's 256 tasks as Gymnasium environments, two ways:

- in-process (`composuite_ros.native`, no ROS needed): `CompoSuiteNativeEnv`, registered as
  `composuite_ros/CompoSuiteNative-v0`, and the batched `CompoSuiteNativeVectorEnv`
  (`gymnasium.make_vec("composuite_ros/CompoSuiteNative-v0", num_envs=N, ...)`), the
  simulation core running inside this process on a thread pool;
- over ROS 2 (needs rclpy and composuite_msgs): `CompoSuiteRosEnv`, registered as
  `composuite_ros/CompoSuite-v0`, one environment of a running suite, and
  `composuite_ros.vector.CompoSuiteRosVectorEnv`, N environments of `composuite launch --envs N`.

Both faces have the same spaces, seeding and `info`, and give the same numbers for the same
seed and actions. `composuite_ros.compat` is the reference's own API (`make`, `sample_tasks`);
`composuite_ros.evaluate` the paper's evaluation protocol (`composuite-eval`).

The ROS parts are imported when first used, so `import composuite_ros` and the in-process
environments work without rclpy.
"""

from __future__ import annotations

import importlib

import gymnasium

from .errors import EpisodeOverError, StepLostError, SuiteNotRunningError
from .tasks import Task, all_tasks

__all__ = ["CompoSuiteNativeEnv", "CompoSuiteNativeVectorEnv", "CompoSuiteRosEnv",
           "EpisodeOverError", "StepLostError", "SuiteNotRunningError", "Task", "all_tasks",
           "register_envs"]

# Imported on first use (PEP 562): the ROS env needs rclpy, the native ones the compiled module.
_LAZY = {"CompoSuiteRosEnv": ".env", "CompoSuiteNativeEnv": ".native",
         "CompoSuiteNativeVectorEnv": ".native"}


def __getattr__(name: str):
    if name in _LAZY:
        return getattr(importlib.import_module(_LAZY[name], __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def register_envs() -> None:
    """Register `composuite_ros/CompoSuite-v0` (over ROS 2) and
    `composuite_ros/CompoSuiteNative-v0` (in-process, with a vector entry point for
    `gymnasium.make_vec`) with Gymnasium (done on `import composuite_ros`)."""
    if "composuite_ros/CompoSuite-v0" not in gymnasium.registry:
        gymnasium.register(id="composuite_ros/CompoSuite-v0",
                           entry_point="composuite_ros.env:CompoSuiteRosEnv",
                           disable_env_checker=False)
    if "composuite_ros/CompoSuiteNative-v0" not in gymnasium.registry:
        gymnasium.register(id="composuite_ros/CompoSuiteNative-v0",
                           entry_point="composuite_ros.native:CompoSuiteNativeEnv",
                           vector_entry_point="composuite_ros.native:CompoSuiteNativeVectorEnv",
                           disable_env_checker=False)


register_envs()
