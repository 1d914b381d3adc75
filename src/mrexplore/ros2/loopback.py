"""Keep DDS on this machine: loopback-only discovery and transport, and a domain of the run's own.

DDS finds its peers by multicast on every interface unless told otherwise. :func:`keep_on_loopback` sets,
before rclpy is imported, ``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST``, a Fast DDS profile whose only
transport is UDP on 127.0.0.1 (no shared-memory or multicast peers elsewhere), and a ``ROS_DOMAIN_ID``: the
user's own where one is exported (a ROS user's shell often has one), else one drawn for the run, so that
concurrent runs never meet. The tests, the benchmarks and ``mrexplore ros2 launch`` call it; a real
deployment leaves it out (``--network``) and configures DDS as its robots need.
"""

from __future__ import annotations

import os
import random
import sys
import tempfile
from pathlib import Path

from mrexplore.types import MrExploreError

__all__ = ["keep_on_loopback", "exported_domain_id", "LOOPBACK_PROFILE", "MAX_DOMAIN_ID"]

LOOPBACK_PROFILE = """<?xml version="1.0" encoding="UTF-8" ?>
<profiles xmlns="http://www.eprosima.com/XMLSchemas/fastRTPS_Profiles">
  <transport_descriptors>
    <transport_descriptor>
      <transport_id>loopback_udp</transport_id>
      <type>UDPv4</type>
      <interfaceWhiteList><address>127.0.0.1</address></interfaceWhiteList>
      <maxInitialPeersRange>32</maxInitialPeersRange>
    </transport_descriptor>
  </transport_descriptors>
  <participant profile_name="mrexplore_loopback" is_default_profile="true">
    <rtps>
      <userTransports><transport_id>loopback_udp</transport_id></userTransports>
      <useBuiltinTransports>false</useBuiltinTransports>
    </rtps>
  </participant>
</profiles>
"""
"""A Fast DDS profile whose one transport is UDP on 127.0.0.1. Discovery on loopback is by unicast to the
first participants' ports; Fast DDS's default reaches 4 participants a machine, too few for a launch of a
simulator, a centre and a robot node per robot: 32 here."""


MAX_DOMAIN_ID = 232
"""The largest ROS domain id: DDS derives its UDP ports from it, and above 232 they leave the port range."""


def exported_domain_id() -> int | None:
    """The ``ROS_DOMAIN_ID`` exported in this environment (None where unset or empty); one line naming the
    variable and the range where it holds something else."""
    text = os.environ.get("ROS_DOMAIN_ID", "").strip()
    if not text:
        return None
    if not text.isdigit() or int(text) > MAX_DOMAIN_ID:
        raise MrExploreError(
            f"ROS_DOMAIN_ID must be an integer in [0, {MAX_DOMAIN_ID}], got {text!r}; export another, or unset it"
        )
    return int(text)


def keep_on_loopback(domain_id: int | None = None) -> dict[str, str]:
    """Set this process's (and its children's) environment so that ROS 2 traffic stays on loopback; returns
    the variables set. ``domain_id``: None keeps the exported ``ROS_DOMAIN_ID``, or, where none is, draws one
    in 1-101 (Linux's safe range) so that concurrent runs do not meet; the variables pass to the processes a
    launch starts.

    Must run before rclpy is imported: DDS reads them once, when the first participant starts.
    """
    if "rclpy" in sys.modules:
        raise MrExploreError("keep_on_loopback() must run before rclpy is imported; call it first")
    if domain_id is None:
        domain_id = exported_domain_id()
    if domain_id is not None and not 0 <= domain_id <= MAX_DOMAIN_ID:
        raise MrExploreError(f"ROS domain id must be in [0, {MAX_DOMAIN_ID}], got {domain_id}")
    profile = Path(tempfile.gettempdir()) / "mrexplore_fastdds_loopback.xml"
    if not profile.exists() or profile.read_text() != LOOPBACK_PROFILE:
        tmp = profile.with_suffix(f".{os.getpid()}.tmp")
        tmp.write_text(LOOPBACK_PROFILE)
        tmp.replace(profile)
    env = {
        "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST",
        "RMW_IMPLEMENTATION": "rmw_fastrtps_cpp",
        "FASTRTPS_DEFAULT_PROFILES_FILE": str(profile),
        "FASTDDS_DEFAULT_PROFILES_FILE": str(profile),
        "ROS_DOMAIN_ID": str(random.SystemRandom().randint(1, 101) if domain_id is None else domain_id),
    }
    os.environ.update(env)
    return env


def rclpy_problem() -> str | None:
    """Why rclpy cannot be used here, in one line (None: it can). Checked in a child process, so that this
    process has imported no DDS yet: a ROS 2 of another distribution sourced in the shell puts its own rclpy,
    built for another Python, ahead of the one installed with mrexplore."""
    import importlib.util
    import subprocess
    import sys

    spec = importlib.util.find_spec("rclpy")
    if spec is None:
        return "ROS 2 commands need rclpy; install it with: pip install -e '.[ros2]'"
    probe = subprocess.run([sys.executable, "-c", "import rclpy"], capture_output=True, text=True)
    if probe.returncode == 0:
        return None
    where = spec.origin or "?"
    distro = os.environ.get("ROS_DISTRO")
    last = probe.stderr.strip().splitlines()[-1] if probe.stderr.strip() else f"exit {probe.returncode}"
    sourced = f" (ROS_DISTRO={distro} is sourced)" if distro else ""
    return (
        f"rclpy at {where} does not load in Python {sys.version_info.major}.{sys.version_info.minor}{sourced}: "
        f"{last}; use a shell without that ROS 2 sourced, or one built for this Python"
    )
