"""The ament_python package of mrexplore's ROS 2 nodes: entry points, launch file, parameters, RViz view."""

from glob import glob

from setuptools import setup

PACKAGE = "mrexplore_ros"

setup(
    name=PACKAGE,
    version="0.1.0",
    packages=[PACKAGE],
    data_files=[
        ("share/ament_index/resource_index/packages", [f"resource/{PACKAGE}"]),
        (f"share/{PACKAGE}", ["package.xml"]),
        (f"share/{PACKAGE}/launch", glob("launch/*.launch.py")),
        (f"share/{PACKAGE}/config", glob("config/*.yaml")),
        (f"share/{PACKAGE}/rviz", glob("rviz/*.rviz")),
    ],
    install_requires=["setuptools"],
    zip_safe=True,
    maintainer="mrexplore developers",
    maintainer_email="mrexplore@example.org",
    description="mrexplore's robot and centre nodes for a Nav2 team",
    license="MIT",
    entry_points={
        "console_scripts": [
            "robot = mrexplore_ros.nodes:robot",
            "centre = mrexplore_ros.nodes:centre",
        ],
    },
)
