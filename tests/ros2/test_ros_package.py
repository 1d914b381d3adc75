"""The ROS package ``ros/mrexplore_ros``: ``colcon build`` of it in a fresh workspace, its executables
answering ``--help``, its params file the one the settings give, and its launch file read (not run: the
``launch`` and ``launch_ros`` packages are not on PyPI, so it is compiled and its arguments checked here, and
its team comes from :func:`mrexplore.ros2.bringup.bringup_deployment`, which is tested)."""

from __future__ import annotations

import ast
import importlib.util
import os
import shutil
import subprocess
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from mrexplore.ros2.bringup import bringup_deployment
from mrexplore.ros2.deployment import Deployment, TeamGrid
from mrexplore.ros2.parameters import params_yaml
from mrexplore.types import MrExploreError

PACKAGE = Path(__file__).resolve().parents[2] / "ros" / "mrexplore_ros"


def _colcon() -> str | None:
    return shutil.which("colcon") if importlib.util.find_spec("ament_package") else None


@pytest.mark.slow
@pytest.mark.skipif(_colcon() is None, reason="colcon or ament_package not installed (pip install -e '.[dev]')")
def test_colcon_builds_the_package_in_a_fresh_workspace_and_its_nodes_answer_help(tmp_path: Path) -> None:
    colcon = _colcon()
    assert colcon is not None
    build = subprocess.run(
        [colcon, "--log-base", str(tmp_path / "log"), "build", "--base-paths", str(PACKAGE.parent)]
        + ["--build-base", str(tmp_path / "build"), "--install-base", str(tmp_path / "install")],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert build.returncode == 0, build.stdout[-2000:] + build.stderr[-2000:]
    assert "1 package finished" in build.stdout
    share = tmp_path / "install" / "mrexplore_ros" / "share" / "mrexplore_ros"
    for path in ("package.xml", "launch/explore.launch.py", "config/mrexplore.yaml", "rviz/mrexplore.rviz"):
        assert (share / path).is_file(), path
    for exe, usage in (("robot", "usage: mrexplore ros2 robot"), ("centre", "usage: mrexplore ros2 centre")):
        script = tmp_path / "install" / "mrexplore_ros" / "lib" / "mrexplore_ros" / exe
        run = subprocess.run(
            ["bash", "-c", f"source {tmp_path / 'install' / 'setup.bash'} && {script} --help"],
            capture_output=True,
            text=True,
            timeout=120,
            env={**os.environ, "COLCON_TRACE": ""},
        )
        assert run.returncode == 0, run.stderr[-2000:]
        assert run.stdout.startswith(usage)


def test_the_params_file_is_the_one_the_settings_give() -> None:
    shipped = (PACKAGE / "config" / "mrexplore.yaml").read_text()
    assert shipped == params_yaml(Deployment.of_names(["robot1"], TeamGrid()))  # mrexplore ros2 params


def test_package_xml_and_entry_points() -> None:
    root = ET.parse(PACKAGE / "package.xml").getroot()
    assert root.get("format") == "3" and root.findtext("name") == "mrexplore_ros"
    assert root.find("export/build_type").text == "ament_python"  # type: ignore[union-attr]
    depends = {e.text for e in root.findall("exec_depend")}
    assert {"rclpy", "nav2_msgs", "tf2_msgs", "rosgraph_msgs", "launch_ros"} <= depends
    setup = (PACKAGE / "setup.py").read_text()
    assert "robot = mrexplore_ros.nodes:robot" in setup and "centre = mrexplore_ros.nodes:centre" in setup


def test_the_launch_file_declares_nav2_bringups_robots_argument_and_builds_the_team_from_it() -> None:
    source = (PACKAGE / "launch" / "explore.launch.py").read_text()
    tree = ast.parse(source)  # it compiles
    names = {
        node.value
        for node in ast.walk(tree)
        if isinstance(node, ast.Constant) and isinstance(node.value, str) and node.value.isidentifier()
    }
    assert {"robots", "use_sim_time", "shared_map", "params_file", "rviz_config"} <= names
    imported = {a.name for node in ast.walk(tree) if isinstance(node, ast.ImportFrom) for a in node.names}
    assert "bringup_deployment" in imported
    default = next(
        node.value.value  # type: ignore[attr-defined]
        for node in ast.walk(tree)
        if isinstance(node, ast.Assign) and getattr(node.targets[0], "id", "") == "ROBOTS"
    )
    # nav2_bringup's own default team: robot2 starts a quarter turn round, its map frame with it
    team = bringup_deployment(default, False)
    assert [r.name for r in team.robots] == ["robot1", "robot2"]
    assert (team.robots[1].offset.x_m, team.robots[1].offset.y_m, team.robots[1].offset.yaw_rad) == (-0.5, -0.5, 1.5707)
    assert team.robots[1].tf_topic == "/robot2/tf" and team.robots[1].goal_topic == "/robot2/goal_pose"
    shared = bringup_deployment(default, True)
    assert all(r.offset.x_m == r.offset.y_m == r.offset.yaw_rad == 0 for r in shared.robots)


@pytest.mark.parametrize(
    ("robots", "message"),
    [
        ("", "robots argument names no robot"),
        ("{pose: {x: 1}}", "robots argument, robot 1: give {name: 'robotN', pose: {x: X, y: Y, yaw: A}}"),
        ("{name: r1, pose: {x: one}}", "robots argument, robot r1: pose must hold numbers x, y and yaw"),
        ("{name: r1};{name: r1}", "robots argument names robot 'r1' twice; give each robot its own name"),
    ],
)
def test_a_bad_robots_argument_is_one_line(robots: str, message: str) -> None:
    with pytest.raises(MrExploreError) as err:
        bringup_deployment(robots, False)
    assert str(err.value).startswith(message)
