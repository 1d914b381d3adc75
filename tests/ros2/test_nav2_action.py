"""The centre's NavigateToPose action client against the Nav2 double's action servers. nav2_msgs is not on
PyPI: the test builds the interface as Nav2 defines it (``tests/ros2/nav2_msgs``) with colcon and rosidl's
generators from PyPI (the ``ros2-interfaces`` extra), then runs a Nav2 team with it on the path: every goal
goes through the action, every abort the double causes is read, and the team finishes the map."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from conftest import requires_rclpy

PACKAGE = Path(__file__).with_name("nav2_msgs")
PREFIX = Path(sys.prefix)


def _missing() -> str | None:
    for tool in ("colcon", "cmake", "cc"):
        if shutil.which(tool) is None:
            return f"{tool} not found"
    if not (PREFIX / "share" / "rosidl_default_generators").is_dir():
        return "rosidl's generators not installed here (pip install -e '.[ros2-interfaces]')"
    return None


pytestmark = [requires_rclpy, pytest.mark.slow, pytest.mark.skipif(_missing() is not None, reason=str(_missing()))]


def test_the_action_client_drives_a_nav2_team(tmp_path: Path) -> None:
    env = {**os.environ, "CMAKE_PREFIX_PATH": str(PREFIX), "AMENT_PREFIX_PATH": str(PREFIX)}
    build = subprocess.run(
        [shutil.which("colcon") or "colcon", "--log-base", str(tmp_path / "log"), "build"]
        + ["--base-paths", str(PACKAGE), "--build-base", str(tmp_path / "build")]
        + ["--install-base", str(tmp_path / "install"), "--cmake-args", "-DBUILD_TESTING=OFF"]
        + [f"-DPython3_EXECUTABLE={sys.executable}"],
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert build.returncode == 0, build.stdout[-3000:] + build.stderr[-3000:]
    installed = tmp_path / "install" / "nav2_msgs"
    site = installed / "lib" / f"python{sys.version_info.major}.{sys.version_info.minor}" / "site-packages"
    env = {
        **os.environ,
        "PYTHONPATH": os.pathsep.join([str(site), os.environ.get("PYTHONPATH", "")]),
        "LD_LIBRARY_PATH": os.pathsep.join([str(installed / "lib"), os.environ.get("LD_LIBRARY_PATH", "")]),
    }
    probe = subprocess.run([sys.executable, "-c", "from nav2_msgs.action import NavigateToPose"], env=env)
    assert probe.returncode == 0
    args = ["--map", "generated:0", "--resolution", "0.2", "--robots", "2", "--strategy", "utility"]
    args += ["--speed", "20", "--nav2", "--clock-rate", "2", "--json"]
    out = subprocess.run(
        [sys.executable, "-m", "mrexplore", "ros2", "launch", *args],
        env=env,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert out.returncode == 0, out.stderr[-2000:]
    run = json.loads(out.stdout.strip().splitlines()[-1])
    assert run["centre"]["goal_via"] == ["action"]  # the client, not goal_pose
    assert run["coverage"] >= 0.99
    double = run["nav2_double"]
    assert double["goals_received"] == run["goals_sent"] and run["goals_resent"] == 0
    assert double["preempted"] > 0  # replaced goals' aborts were not read as aborts
    assert run["aborts_read"] == double["aborts_caused"]
