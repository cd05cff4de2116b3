"""Launch the bsp_ros cell on Jazzy: joint angles, identification, session recording (optionally the simulator)."""

import os

from ament_index_python.packages import get_package_share_directory
from launch.actions import DeclareLaunchArgument, OpaqueFunction
from launch.conditions import IfCondition
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node
from launch_ros.parameter_descriptions import ParameterValue

from bsp_ros.live.runtime.launch_parameters import node_parameters
from launch import LaunchContext, LaunchDescription


def _nodes(context: LaunchContext) -> list[Node]:
    """The nodes, each with the params file and, where the ``cell_file`` argument is given, that cell file."""
    params = node_parameters(
        LaunchConfiguration("params_file").perform(context), LaunchConfiguration("cell_file").perform(context)
    )
    # Given, the subject follows the params file (so it wins), a string even where the id is all digits (subject:=007
    # would otherwise be an integer); left empty it is not passed, so a params file's subject stands.
    subject = LaunchConfiguration("subject")
    named = [{"subject": ParameterValue(subject, value_type=str)}] if subject.perform(context).strip() else []
    return [
        Node(
            package="bsp_ros",
            executable="cell_simulator",
            parameters=params,
            condition=IfCondition(LaunchConfiguration("simulate")),
        ),
        Node(package="bsp_ros", executable="joint_angle_estimator", parameters=params),
        Node(package="bsp_ros", executable="bsp_identifier", parameters=params),
        Node(
            package="bsp_ros",
            executable="session_recorder",
            parameters=[*params, *named],
            condition=IfCondition(LaunchConfiguration("record_sessions")),
        ),
        Node(
            package="bsp_ros",
            executable="arm_visualizer",
            parameters=params,
            condition=IfCondition(LaunchConfiguration("visualize")),
        ),
    ]


def generate_launch_description() -> LaunchDescription:
    config = os.path.join(get_package_share_directory("bsp_ros"), "config", "bsp_cell.yaml")
    return LaunchDescription(
        [
            DeclareLaunchArgument("params_file", default_value=config, description="ros__parameters YAML"),
            DeclareLaunchArgument(
                "cell_file",
                default_value="",
                description="the cell description (bsp_ros/cell/1 YAML) for every node; empty: the params file's "
                "cell_file, else the shipped cell",
            ),
            DeclareLaunchArgument("simulate", default_value="false", description="also start the simulated cell"),
            DeclareLaunchArgument("record_sessions", default_value="false", description="start session_recorder"),
            DeclareLaunchArgument(
                "visualize", default_value="true", description="start arm_visualizer (bsp/arm_markers, segment /tf)"
            ),
            DeclareLaunchArgument(
                "subject",
                default_value="",
                description="pseudonymous id of the patient whose sessions session_recorder stores (never a name); "
                "empty: the params file's subject, else none",
            ),
            OpaqueFunction(function=_nodes),
        ]
    )
