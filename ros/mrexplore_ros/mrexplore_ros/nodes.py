"""The package's executables: each runs the mrexplore command of the same name with the arguments it was
given (a launch file's ``arguments`` and ``--ros-args ...``, which rcl applies)."""

import sys


def _run(kind: str) -> None:
    try:
        from mrexplore.cli.main import main
    except ImportError:
        sys.exit(
            "mrexplore_ros needs the mrexplore Python package: pip install 'mrexplore[ros2]' "
            "(or pip install -e 'REPO[ros2]') in the Python that runs ROS 2"
        )
    sys.exit(main(["ros2", kind, *sys.argv[1:]]))


def robot() -> None:
    """``ros2 run mrexplore_ros robot --name robot1 --deployment team.yaml``."""
    _run("robot")


def centre() -> None:
    """``ros2 run mrexplore_ros centre --deployment team.yaml``."""
    _run("centre")
