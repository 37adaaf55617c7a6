"""`ros2 launch` file for the CompoSuite-ROS node suite: the same three nodes, with the same
parameters, as `composuite launch` starts for one environment.

    ros2 launch launch_scripts/composuite.launch.py task:=Panda/plate/goal_wall/trash_can \
        mode:=lockstep namespace:=/env_00

The node binaries (`task_manager_node`, `sim_node`, `reward_node`, built by
`cargo build --release -p composuite_ros`) are taken from `bin_dir` (default: the
COMPOSUITE_BIN_DIR environment variable), or from PATH when that is empty. Every argument maps to
the node parameter of the same name (see params/composuite.yaml).
"""

import os

from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument, OpaqueFunction
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node

# (argument, default, description); each is the parameter of that name of the node listed.
ARGUMENTS = [
    ("task", "IIWA/box/no_obstacle/pick_place", "task of the first episode, robot/object/obstacle/objective"),
    ("mode", "lockstep", "lockstep (one control period per joint_command) or realtime"),
    ("realtime_factor", "1.0", "realtime mode: sim seconds per wall second"),
    ("seed", "0", "seed of the first episode"),
    ("horizon", "500", "control steps per episode"),
    ("service_mapping", "fastdds", "service wire format: fastdds (rmw_fastrtps) or cyclone (rmw_cyclonedds)"),
    ("auto_reset", "false", "start the next episode as soon as one ends"),
    ("reward_shaping", "true", "staged rewards (true) or sparse ones: 1 on success, else 0"),
    ("reward_scale", "1.0", "every reward is multiplied by this"),
]
NODE_PARAMETERS = {
    "task_manager": ["task", "seed", "horizon", "auto_reset", "service_mapping"],
    "sim": ["mode", "realtime_factor", "service_mapping"],
    "reward": ["reward_shaping", "reward_scale", "service_mapping"],
}


def _nodes(context):
    bin_dir = LaunchConfiguration("bin_dir").perform(context)
    namespace = LaunchConfiguration("namespace").perform(context)
    log_level = LaunchConfiguration("log_level").perform(context)
    nodes = []
    for name, parameters in NODE_PARAMETERS.items():
        executable = f"{name}_node"
        if bin_dir:
            executable = os.path.join(bin_dir, executable)
        nodes.append(Node(
            executable=executable,
            name=name,
            namespace=namespace,
            parameters=[{p: LaunchConfiguration(p) for p in parameters}],
            arguments=["--ros-args", "--log-level", log_level],
            output="screen",
        ))
    return nodes


def generate_launch_description():
    declared = [DeclareLaunchArgument(name, default_value=default, description=text)
                for name, default, text in ARGUMENTS]
    declared += [
        DeclareLaunchArgument("namespace", default_value="", description="namespace of the environment"),
        DeclareLaunchArgument("log_level", default_value="info", description="debug, info, warn, error, fatal"),
        DeclareLaunchArgument("bin_dir", default_value=os.environ.get("COMPOSUITE_BIN_DIR", ""),
                              description="directory of the node binaries (empty: PATH)"),
    ]
    return LaunchDescription(declared + [OpaqueFunction(function=_nodes)])
