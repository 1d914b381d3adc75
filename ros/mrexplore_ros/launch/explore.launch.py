"""mrexplore on a Nav2 team: the computing centre and one robot node per robot.

The robots are named and placed in the syntax of nav2_bringup's cloned multi-robot launch
(cloned_multi_tb3_simulation_launch.py's ``robots`` argument), so one string serves both launches::

    ros2 launch mrexplore_ros explore.launch.py \
        robots:="{name: 'robot1', pose: {x: 0.5, y: 0.5, yaw: 0}};{name: 'robot2', pose: {x: -0.5, y: -0.5, yaw: 1.5707}}"

Each robot's map frame is placed where the robot started (one slam_toolbox per robot), or all in the team
frame with ``shared_map:=True`` (AMCL on one map). ``params_file`` holds the team's grid and timing as ROS
parameters (written by ``mrexplore ros2 params``); ``deployment`` may name a deployment file for the rest
(each robot's topics and frames). docs/ros2.md has the whole recipe.
"""

import os
import tempfile

import yaml
from ament_index_python.packages import get_package_share_directory
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument, OpaqueFunction
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node

ROBOTS = (
    "{name: 'robot1', pose: {x: 0.5, y: 0.5, yaw: 0}};"
    "{name: 'robot2', pose: {x: -0.5, y: -0.5, z: 0, roll: 0, pitch: 0, yaw: 1.5707}}"
)
"""nav2_bringup's own default, so that both launches start the same team unchanged."""


def _flag(context, name):
    return LaunchConfiguration(name).perform(context).strip().lower() in ("true", "1", "yes")


def _team(context):
    from mrexplore.ros2.bringup import bringup_deployment
    from mrexplore.ros2.deployment import read_deployment

    base_file = LaunchConfiguration("deployment").perform(context).strip()
    base = read_deployment(base_file) if base_file else None
    team = bringup_deployment(LaunchConfiguration("robots").perform(context), _flag(context, "shared_map"), base)
    fd, path = tempfile.mkstemp(prefix="mrexplore_team_", suffix=".yaml")
    with os.fdopen(fd, "w") as f:
        yaml.safe_dump(team.to_dict(), f, sort_keys=False)
    use_sim_time = _flag(context, "use_sim_time")
    parameters = [LaunchConfiguration("params_file"), {"use_sim_time": use_sim_time}]
    strategy = LaunchConfiguration("strategy").perform(context)
    # --network: the system's DDS settings, as every node of the team uses them.
    nodes = [
        Node(
            package="mrexplore_ros",
            executable="centre",
            name="mrexplore_centre",
            output="screen",
            arguments=["--deployment", path, "--strategy", strategy, "--network"],
            parameters=parameters,
        )
    ]
    for robot in team.robots:
        nodes.append(
            Node(
                package="mrexplore_ros",
                executable="robot",
                name=f"mrexplore_{robot.name}",
                output="screen",
                arguments=["--name", robot.name, "--deployment", path, "--network"],
                parameters=parameters,
            )
        )
    if _flag(context, "use_rviz"):
        nodes.append(
            Node(
                package="rviz2",
                executable="rviz2",
                arguments=["-d", LaunchConfiguration("rviz_config").perform(context)],
                parameters=[{"use_sim_time": use_sim_time}],
            )
        )
    return nodes


def generate_launch_description():
    share = get_package_share_directory("mrexplore_ros")
    arguments = [
        ("robots", ROBOTS, "robots and their start poses, as nav2_bringup's cloned multi-robot launch reads them"),
        ("use_sim_time", "True", "every node on sim time (/clock), as nav2_bringup's simulation runs"),
        ("shared_map", "False", "True: the robots localise on one map (AMCL); False: one SLAM map per robot"),
        ("params_file", os.path.join(share, "config", "mrexplore.yaml"), "the team's grid and timing"),
        ("deployment", "", "a deployment file for each robot's topics and frames (optional)"),
        ("strategy", "hier-plan-nolocal", "the planner: hier-plan-nolocal (default), hier, utility, nearest, coscan"),
        ("use_rviz", "True", "start RViz with the team map, the frontiers and each robot's goal"),
        ("rviz_config", os.path.join(share, "rviz", "mrexplore.rviz"), "RViz configuration"),
    ]
    return LaunchDescription(
        [DeclareLaunchArgument(name, default_value=default, description=doc) for name, default, doc in arguments]
        + [OpaqueFunction(function=_team)]
    )
