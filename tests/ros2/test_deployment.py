"""The deployment file every ROS 2 node reads, the lockstep exchange's JSON, and the ros2 commands' one-line
errors (no middleware started)."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import requires_rclpy

from mrexplore.cli import main
from mrexplore.ros2.deployment import Deployment, TeamGrid, read_deployment
from mrexplore.ros2.lockstep import DecisionReply, DecisionRequest
from mrexplore.types import MrExploreError

FILE = """team_frame: world
team_grid: {x0: -2.0, y0: -1.0, width: 4.0, height: 2.5, resolution: 0.1}
round_period_s: 0.5
robots:
  - name: scout
    offset: [1.0, 2.0, 1.5708]
    pose_type: odometry
    pose_topic: /scout/odom
  - mule
"""


def test_a_deployment_file_names_robots_frames_topics_and_timing(tmp_path) -> None:
    path = tmp_path / "team.yaml"
    path.write_text(FILE)
    d = read_deployment(path)
    assert [r.name for r in d.robots] == ["scout", "mule"] and [r.index for r in d.robots] == [0, 1]
    scout, mule = d.robots
    assert (scout.offset.x_m, scout.offset.y_m, scout.offset.yaw_rad) == (1.0, 2.0, 1.5708)
    assert scout.pose_topic == "/scout/odom" and scout.pose_type == "odometry" and scout.map_topic == "/scout/map"
    assert mule.goal_topic == "/mule/goal_pose" and mule.nav_status_topic == "/mule/navigate_to_pose/_action/status"
    assert mule.frontiers_topic == "/mrexplore/mule/frontiers"
    assert d.team_frame == "world" and d.round_period_s == 0.5 and d.lost_after_s == 5.0
    frame = d.team_grid.frame(10**6)
    assert (frame.height, frame.width, frame.origin_xy) == (25, 40, (-2.0, -1.0))
    assert Deployment.from_dict(d.to_dict()) == d


@pytest.mark.parametrize(
    ("data", "message"),
    [
        ({}, "deployment must list its robots: robots: [robot1, robot2]"),
        ({"robots": ["a"], "speed": 2}, "deployment has unknown setting 'speed'; known: blacklist_s, lost_after_s"),
        (
            {"robots": ["1st"]},
            "deployment: robot name must be letters, digits and _ (a ROS name), from a letter, got '1st'",
        ),
        ({"robots": [{"name": "a", "offset": [0, 0]}]}, "deployment: robot a's offset must be [x, y, yaw]"),
        (
            {"robots": [{"name": "a", "pose_type": "gps"}]},
            "deployment: robot a's pose_type must be 'pose_with_covariance', 'odometry' or 'tf', got 'gps'",
        ),
        ({"robots": ["a"], "round_period_s": 0}, "deployment: round_period_s must be > 0 seconds, got 0.0"),
        ({"robots": ["a"], "team_grid": {"x0": "left"}}, "deployment: team_grid.x0 must be a finite number"),
    ],
)
def test_a_bad_deployment_is_one_line_naming_the_problem(data: dict, message: str) -> None:
    with pytest.raises(MrExploreError) as err:
        Deployment.from_dict(data)
    assert str(err.value).startswith(message) and "\n" not in str(err.value)


def test_a_team_grid_too_large_or_empty_is_refused() -> None:
    with pytest.raises(MrExploreError, match="team grid holds 4,000,000 cells at 0.1 m, more than 1,000,000"):
        TeamGrid(0, 0, 200.0, 200.0, 0.1).frame(10**6)
    with pytest.raises(MrExploreError, match=r"^width must be > 0 metres, got 0.0$"):
        TeamGrid(0, 0, 0.0, 2.0, 0.1)


def test_the_lockstep_exchange_round_trips_and_refuses_garbage() -> None:
    route = np.array([[2, 3], [2, 4]], np.int32)
    req = DecisionRequest(7, (3, 0), [0, 2], [0, 1, 2], [route, np.zeros((0, 2), np.int32)], [5, 9], {"k": 1})
    back = DecisionRequest.from_json(req.to_json())
    assert back == req and back.current[0].tolist() == [[2, 3], [2, 4]]
    reply = DecisionReply(
        7, [0], np.array([[2, 3]], np.int32), [route], [route], [1], np.array([[2, 3]]), [4], None, {}, "ab", 1.5
    )
    again = DecisionReply.from_json(reply.to_json())
    assert again.goals_rc.tolist() == [[2, 3]] and again.paths[0].tolist() == route.tolist()
    with pytest.raises(MrExploreError, match=r"decision request is not JSON \(Expecting value at character 0\)"):
        DecisionRequest.from_json("nonsense")
    with pytest.raises(MrExploreError, match="decision reply lacks or mistypes a field"):
        DecisionReply.from_json('{"round": 1}')


def test_ros2_help_documents_the_deployment_file(capsys) -> None:
    assert main(["ros2", "--help"]) == 0
    out = capsys.readouterr().out
    assert "A deployment file (--deployment, YAML)" in out and "launch" in out and "centre" in out


@requires_rclpy
@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["ros2", "centre", "--deployment", "missing.yaml"], "deployment file missing.yaml not found"),
        (["ros2", "centre", "--names", "a,b", "--strategy", "oracle"], "the oracle needs the ground truth"),
        (["ros2", "robot", "--name", "r1"], "give the robot's place in the team: --index N"),
        (["ros2", "centre"], "name the robots: --names robot1,robot2 or --deployment FILE"),
    ],
)
def test_ros2_commands_refuse_bad_input_before_starting(argv: list[str], message: str, capsys) -> None:
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"mrexplore: error: {message}") and "\n" not in err
