"""A node group: several of a run's nodes composed in one process on one executor, as ROS
composition hosts C++ nodes (issue 34). The runner starts one per group of `--layout groups`
(node_processes.py); each node is the same class, with the same name, parameters, topics and
private step channel, as the executable `ros2 run` starts alone.

    node_group GROUP.json    (written by the runner: the nodes' NodeSpec fields, in order)

The channels come in TUGSIM_STEP_CHANNEL_FDS, the recorder's pipe in TUGSIM_RECORD_FD (one for
the group). Exit status as a node's (sim_plumbing.ros_common.run_nodes): 0 stopped, 2 bad input,
3 a model failed; the first failure ends the group.
"""
from __future__ import annotations

import json
import sys
from typing import List, Optional

from scenario_runner.run_nodes import NodeSpec
from sim_plumbing import ros_common as rc
from sim_plumbing import step_channel


def read_group(path: str) -> List[NodeSpec]:
    """The group's NodeSpecs (ValueError naming the file if it is not one the runner wrote)."""
    try:
        with open(path) as f:
            return [NodeSpec(**entry) for entry in json.load(f)]
    except (OSError, TypeError, ValueError) as exc:
        raise ValueError(f"{path}: not a node group file ({exc})") from None


def main(args: Optional[List[str]] = None) -> int:
    argv = sys.argv[1:] if args is None else args
    paths = [a for a in argv if not a.startswith("-")][:1]
    if not paths:
        sys.stderr.write("usage: node_group GROUP.json (a file the scenario runner writes)\n")
        return 2
    try:
        specs = read_group(paths[0])
    except ValueError as exc:
        sys.stderr.write(f"node_group: {exc}\n")
        return 2
    from rope_model.models import ModelFailure
    from scenario_runner.node_processes import in_process_nodes
    channels = step_channel.group_channels()
    step_channel.install(channels.get)
    return rc.run_nodes(lambda: in_process_nodes(specs), "node_group", ["node_group"], failures=(ModelFailure,))


if __name__ == "__main__":
    sys.exit(main())
