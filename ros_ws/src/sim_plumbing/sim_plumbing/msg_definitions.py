"""ros2msg schema text of a message type, as rosbag2 writes it into MCAP and the Foxglove
WebSocket protocol carries it: the type's .msg text, then every dependency once
("=" * 80, "MSG: pkg/Type", its text). Read from share/<pkg>/msg/<Type>.msg of the installed
interface packages (no ROS import; ament_index_python is a file lookup).

Written once: the recorder (recording.recorder) and the live view take their schemas from here, so the
live view and the recording describe a type identically.
"""
from __future__ import annotations

import os
import re
from typing import List

PRIMITIVES = {"bool", "byte", "char", "float32", "float64", "int8", "uint8", "int16", "uint16", "int32", "uint32",
              "int64", "uint64", "string", "wstring"}
SEPARATOR = "=" * 80


def msg_file(full_type: str) -> str:
    pkg, _, name = full_type.split("/")
    from ament_index_python.packages import get_package_share_directory
    return os.path.join(get_package_share_directory(pkg), "msg", name + ".msg")


def _dependencies(pkg: str, text: str) -> List[str]:
    deps = []
    for line in text.splitlines():
        line = line.split("#", 1)[0].strip()
        if not line:
            continue
        parts = line.split(None, 1)
        if len(parts) > 1 and "=" in parts[1]:
            continue  # constant
        base = re.sub(r"\[.*\]$", "", parts[0])
        base = re.sub(r"<=\d+$", "", base)
        if base in PRIMITIVES:
            continue
        if base == "Header":
            base = "std_msgs/Header"
        if "/" not in base:
            base = f"{pkg}/{base}"
        deps.append(base if base.count("/") == 2 else base.replace("/", "/msg/", 1))
    return deps


def message_definition(full_type: str) -> str:
    """rosbag2's ros2msg schema text for e.g. 'nav_msgs/msg/Odometry'."""
    seen: List[str] = []

    def visit(t: str) -> None:
        with open(msg_file(t)) as f:
            text = f.read()
        for dep in _dependencies(t.split("/")[0], text):
            if dep not in seen and dep != full_type:
                seen.append(dep)
                visit(dep)

    with open(msg_file(full_type)) as f:
        main = f.read()
    visit(full_type)
    parts = [main.rstrip("\n")]
    for dep in seen:
        pkg, _, name = dep.split("/")
        with open(msg_file(dep)) as f:
            parts.append(f"{SEPARATOR}\nMSG: {pkg}/{name}\n{f.read().rstrip(chr(10))}")
    return "\n".join(parts) + "\n"


def type_name(msg_class) -> str:
    """'pkg/msg/Type' of a generated message class."""
    return f"{msg_class.__module__.split('.')[0]}/msg/{msg_class.__name__}"
