#!/usr/bin/env python3
"""Several hosts on one machine: every host its own Linux network namespace with its own
address on one IPv4 subnet, for running the scenario runner and each node as if on its own PC
(tests/ros/test_multi_host.py, benchmarks/bench_multi_host.py). Needs root and `nft`
(Debian: apt-get install nftables).

Links (one per host, to a switch in a namespace of its own):
  - delay 0: a veth pair per host into a Linux bridge (the kernel switches);
  - delay > 0: this kernel has no sch_netem (`tc qdisc ... netem` is refused) and no nft
    `queue`, so delay comes from a small user-space switch instead of the bridge: each host's
    eth0 is a TUN device whose other end is read by `hosts_harness.py switch`, which forwards
    every IPv4 packet to the host owning its destination (multicast and broadcast to every other
    host) `delay` ms after it left its sender (one-way, host to host);
  - loss: nftables in each host drops that percentage of what leaves its eth0
    (`numgen random mod 10000 < loss*100`, counted: dropped()), so every packet from one host
    to another is lost with that probability, in either direction.

Fast DDS on such hosts: UDPv4 only (FASTDDS_BUILTIN_TRANSPORTS=UDPv4: the namespaces share
/dev/shm, and Fast DDS would otherwise carry the data over shared memory past the links, as it
would never do between real PCs), discovery by multicast on the subnet
(ROS_AUTOMATIC_DISCOVERY_RANGE=SUBNET), and the LAN profile fastdds_lan.xml beside this script
(FASTRTPS_DEFAULT_PROFILES_FILE): fast repair of lost packets (Fast DDS's 3 s heartbeat makes
every lost packet of a lockstep run a 0-3 s stall) and a 3 s participant lease.

    with Hosts(["runner", "tug", "towline"], loss_percent=1.0, delay_ms=1.0) as hosts:
        proc = hosts.popen("tug", ["ros2", "run", ...], env=hosts.env(), stdout=...)
        hosts.cut("tug")            # the host's link goes down (as a pulled cable)

Command line: `hosts_harness.py up runner tug towline --loss 1 --delay 1` sets the hosts up
and keeps them until Ctrl-C (run programs in them with `ip netns exec <namespace> ...`);
`hosts_harness.py clean` removes hosts a killed harness left behind.
"""
from __future__ import annotations

import argparse
import heapq
import os
import secrets
import selectors
import signal
import struct
import subprocess
import sys
import time
from typing import Dict, List, Optional

PREFIX = "tugsim-"  # every namespace of this harness starts with it (clean removes them)
SUBNET = "10.23.0"  # /24; hosts get .1, .2, ... in the order given (each harness has its own switch)
FASTDDS_PROFILE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "fastdds_lan.xml")


def _ip(*args: str, check: bool = True) -> subprocess.CompletedProcess:
    return subprocess.run(["ip", *args], check=check, capture_output=True, text=True)


def _in(ns: str, *args: str, check: bool = True) -> subprocess.CompletedProcess:
    return subprocess.run(["ip", "netns", "exec", ns, *args], check=check, capture_output=True, text=True)


def _have(tool: str) -> bool:
    return subprocess.run(["sh", "-c", f"command -v {tool}"], capture_output=True).returncode == 0


def available() -> Optional[str]:
    """Why hosts cannot be set up here, or None. Installs Debian's nftables when it is missing
    and apt-get can (as root)."""
    if os.geteuid() != 0:
        return "network namespaces need root"
    if not _have("nft") and _have("apt-get"):
        env = dict(os.environ, DEBIAN_FRONTEND="noninteractive")
        install = ["apt-get", "install", "-y", "-qq", "nftables"]
        if subprocess.run(install, env=env, capture_output=True).returncode:
            subprocess.run(["apt-get", "update", "-qq"], env=env, capture_output=True)
            subprocess.run(install, env=env, capture_output=True)
    for tool in ("ip", "nft"):
        if not _have(tool):
            return f"`{tool}` not found (Debian: apt-get install {'iproute2' if tool == 'ip' else 'nftables'})"
    return None


class Hosts:
    """Namespaces <PREFIX><tag>-<host> joined by a switch in <PREFIX><tag>-sw."""

    def __init__(self, names: List[str], *, loss_percent: float = 0.0, delay_ms: float = 0.0,
                 tag: Optional[str] = None):
        if len(set(names)) != len(names) or len(names) > 250:
            raise ValueError(f"host names must be distinct (at most 250): {names}")
        self.names = list(names)
        self.loss_percent = float(loss_percent)
        self.delay_ms = float(delay_ms)
        # the harness's pid first: clean() tells namespaces of a killed harness from live ones
        self.tag = tag or f"{os.getpid()}-{secrets.token_hex(2)}"
        self.switch_ns = f"{PREFIX}{self.tag}-sw"
        self.addresses = {n: f"{SUBNET}.{i + 1}" for i, n in enumerate(self.names)}
        self.switch: Optional[subprocess.Popen] = None
        self.procs: List[subprocess.Popen] = []

    def ns(self, name: str) -> str:
        return f"{PREFIX}{self.tag}-{name}"

    # ---- set-up and tear-down ----------------------------------------------------------
    def __enter__(self) -> "Hosts":
        try:
            self.up()
        except BaseException:
            self.down()
            raise
        return self

    def __exit__(self, *exc) -> None:
        self.down()

    def up(self) -> None:
        why = available()
        if why:
            raise RuntimeError(f"hosts harness: {why}")
        clean(dead_only=True)  # what a killed harness (e.g. a test stopped by its timeout) left
        _ip("netns", "add", self.switch_ns)
        _in(self.switch_ns, "ip", "link", "set", "lo", "up")
        for name in self.names:
            _ip("netns", "add", self.ns(name))
        if self.delay_ms > 0:
            self._up_tun_switch()
        else:
            self._up_bridge()
        for i, name in enumerate(self.names):
            ns = self.ns(name)
            _in(ns, "sysctl", "-qw", "net.ipv6.conf.all.disable_ipv6=1")
            _in(ns, "ip", "link", "set", "lo", "up")
            _in(ns, "ip", "addr", "add", f"{self.addresses[name]}/24", "dev", "eth0")
            _in(ns, "ip", "link", "set", "eth0", "multicast", "on", "up")
            _in(ns, "ip", "route", "add", "224.0.0.0/4", "dev", "eth0")  # DDS discovery (SPDP multicast)
            if self.loss_percent > 0:
                n = int(round(self.loss_percent * 100))
                rules = (f"table inet tugsim_loss {{\n chain out {{\n"
                         f"  type filter hook output priority 0; policy accept;\n"
                         f"  oifname \"eth0\" numgen random mod 10000 < {n} counter drop\n }}\n}}\n")
                subprocess.run(["ip", "netns", "exec", ns, "nft", "-f", "-"], input=rules, text=True,
                               check=True, capture_output=True)

    def _up_bridge(self) -> None:
        sw = self.switch_ns
        _in(sw, "ip", "link", "add", "br0", "type", "bridge")
        _in(sw, "ip", "link", "set", "br0", "type", "bridge", "mcast_snooping", "0")
        _in(sw, "ip", "link", "set", "br0", "up")
        for i, name in enumerate(self.names):
            port = f"p{i}"
            _in(sw, "ip", "link", "add", port, "type", "veth", "peer", "name", "eth0", "netns", self.ns(name))
            _in(sw, "ip", "link", "set", port, "master", "br0", "up")

    def _up_tun_switch(self) -> None:
        args = ["ip", "netns", "exec", self.switch_ns, sys.executable, os.path.abspath(__file__), "switch",
                "--delay", repr(self.delay_ms)] + [self.addresses[n] for n in self.names]
        self.switch = subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                       start_new_session=True)
        line = self.switch.stdout.readline()
        if line.strip() != "ready":
            raise RuntimeError(f"user-space switch did not start: {line}{self.switch.stderr.read()}")
        for i, name in enumerate(self.names):
            _in(self.switch_ns, "ip", "link", "set", f"t{i}", "netns", self.ns(name))
            _in(self.ns(name), "ip", "link", "set", f"t{i}", "name", "eth0")

    def down(self) -> None:
        """Stop what runs in the hosts, then remove them (also after a failed set-up)."""
        for p in self.procs:
            _kill_group(p)
        if self.switch is not None:
            _kill_group(self.switch)
            self.switch = None
        for name in [self.switch_ns] + [self.ns(n) for n in self.names]:
            kill_namespace_processes(name)
            _ip("netns", "delete", name, check=False)

    # ---- use --------------------------------------------------------------------------
    def env(self, base: Optional[Dict[str, str]] = None, **extra: str) -> Dict[str, str]:
        """The environment of a ROS process on these hosts (see the module doc)."""
        env = dict(os.environ if base is None else base)
        for key in ("ROS_STATIC_PEERS", "ROS_LOCALHOST_ONLY", "FASTDDS_DEFAULT_PROFILES_FILE",
                    "RMW_FASTRTPS_USE_QOS_FROM_XML"):
            env.pop(key, None)
        env.update(ROS_AUTOMATIC_DISCOVERY_RANGE="SUBNET", FASTDDS_BUILTIN_TRANSPORTS="UDPv4",
                   FASTRTPS_DEFAULT_PROFILES_FILE=FASTDDS_PROFILE, PYTHONUNBUFFERED="1")
        env.update(extra)
        return env

    def popen(self, name: str, args: List[str], **kwargs) -> subprocess.Popen:
        """A process on host `name` (its own process group; stopped by down())."""
        p = subprocess.Popen(["ip", "netns", "exec", self.ns(name), *args], start_new_session=True, **kwargs)
        self.procs.append(p)
        return p

    def run(self, name: str, args: List[str], **kwargs) -> subprocess.CompletedProcess:
        return subprocess.run(["ip", "netns", "exec", self.ns(name), *args], **kwargs)

    def cut(self, name: str) -> None:
        """Host `name` loses its link (as a pulled cable): nothing goes in or out any more."""
        _in(self.ns(name), "ip", "link", "set", "eth0", "down")

    def dropped(self) -> Dict[str, int]:
        """Packets the loss rule of each host dropped so far."""
        out = {}
        for name in self.names:
            r = _in(self.ns(name), "nft", "list", "table", "inet", "tugsim_loss", check=False)
            words = r.stdout.split()
            out[name] = int(words[words.index("packets") + 1]) if "packets" in words else 0
        return out


def start_nodes(hosts: Hosts, specs, env: Dict[str, str], log_dir: str) -> Dict[str, subprocess.Popen]:
    """Each scenario node (scenario_runner.run_nodes.NodeSpec) as `ros2 run` would start it, on the
    host named like its namespace ("/tug/vessel" on host "tug"); logs in log_dir/<host>.log."""
    from scenario_runner.run_nodes import executable_path
    os.makedirs(log_dir, exist_ok=True)
    procs = {}
    for spec in specs:
        host = spec.namespace.strip("/")
        with open(os.path.join(log_dir, f"{host}.log"), "wb") as log:
            procs[spec.name] = hosts.popen(host, [executable_path(spec.package, spec.executable), "--ros-args",
                                                  *spec.ros_args()], env=env, stdout=log, stderr=subprocess.STDOUT)
    return procs


def _kill_group(p: subprocess.Popen, timeout: float = 3.0) -> None:
    if p.poll() is None:
        try:
            os.killpg(p.pid, signal.SIGINT)
            p.wait(timeout)
        except (ProcessLookupError, subprocess.TimeoutExpired):
            try:
                os.killpg(p.pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
            p.wait()


def kill_namespace_processes(ns: str) -> None:
    r = _ip("netns", "pids", ns, check=False)
    for pid in r.stdout.split():
        try:
            os.kill(int(pid), signal.SIGKILL)
        except (ProcessLookupError, ValueError):
            pass


def clean(dead_only: bool = False) -> List[str]:
    """Remove the namespaces of this harness: all, or (dead_only) those whose harness process
    (the pid in their name) has ended."""
    removed = []
    for line in _ip("netns", "list", check=False).stdout.splitlines():
        name = line.split()[0] if line.split() else ""
        if not name.startswith(PREFIX):
            continue
        pid = name[len(PREFIX):].split("-")[0]
        if dead_only and (not pid.isdigit() or os.path.exists(f"/proc/{pid}")):
            continue
        kill_namespace_processes(name)
        _ip("netns", "delete", name, check=False)
        removed.append(name)
    return removed


# ---- the user-space switch (delay) -----------------------------------------------------
TUNSETIFF, IFF_TUN, IFF_NO_PI = 0x400454CA, 0x0001, 0x1000


def switch_main(addresses: List[str], delay_ms: float) -> None:
    """Forward IPv4 packets between TUN devices t0, t1, ... (one per host address, created here)
    delay_ms after they were read; multicast and broadcast go to every other device."""
    import fcntl
    import socket
    fds = []
    for i in range(len(addresses)):
        fd = os.open("/dev/net/tun", os.O_RDWR | os.O_NONBLOCK)
        fcntl.ioctl(fd, TUNSETIFF, struct.pack("16sH", f"t{i}".encode(), IFF_TUN | IFF_NO_PI))
        fds.append(fd)
    owner = {socket.inet_aton(a): fd for a, fd in zip(addresses, fds)}
    print("ready", flush=True)
    signal.signal(signal.SIGINT, lambda *a: sys.exit(0))
    signal.signal(signal.SIGTERM, lambda *a: sys.exit(0))
    sel = selectors.DefaultSelector()
    for fd in fds:
        sel.register(fd, selectors.EVENT_READ)
    delay = delay_ms * 1e-3
    queue: list = []  # (due, sequence, destination fds, packet)
    seq = 0
    while True:
        now = time.monotonic()
        while queue and queue[0][0] <= now:
            _, _, dests, pkt = heapq.heappop(queue)
            for fd in dests:
                try:
                    os.write(fd, pkt)
                except OSError:
                    pass  # that host's link is down: the packet is lost, as on a wire
        timeout = max(0.0, queue[0][0] - time.monotonic()) if queue else None
        for key, _ in sel.select(timeout):
            src = key.fd
            while True:
                try:
                    pkt = os.read(src, 65536)
                except (BlockingIOError, OSError):
                    break
                if len(pkt) < 20 or pkt[0] >> 4 != 4:
                    continue  # IPv4 only
                dst = pkt[16:20]
                if dst[0] >= 224 or dst[3] == 255:
                    dests = [fd for fd in fds if fd != src]
                else:
                    fd = owner.get(dst)
                    if fd is None or fd == src:
                        continue
                    dests = [fd]
                seq += 1
                heapq.heappush(queue, (time.monotonic() + delay, seq, dests, pkt))


def main(argv: Optional[List[str]] = None) -> int:
    parser = argparse.ArgumentParser(prog="hosts_harness.py", description=__doc__.split("\n\n")[0])
    sub = parser.add_subparsers(dest="cmd", required=True)
    up = sub.add_parser("up", help="set hosts up and keep them until Ctrl-C")
    up.add_argument("hosts", nargs="+")
    up.add_argument("--loss", type=float, default=0.0, help="%% of the packets each host sends, dropped")
    up.add_argument("--delay", type=float, default=0.0, help="ms one-way delay host to host (user-space switch)")
    sub.add_parser("clean", help="remove namespaces a killed harness left behind")
    sw = sub.add_parser("switch", help=argparse.SUPPRESS)
    sw.add_argument("addresses", nargs="+")
    sw.add_argument("--delay", type=float, required=True)
    args = parser.parse_args(argv)
    if args.cmd == "switch":
        switch_main(args.addresses, args.delay)
        return 0
    if args.cmd == "clean":
        print("\n".join(f"removed {n}" for n in clean()) or "nothing to remove")
        return 0
    hosts = Hosts(args.hosts, loss_percent=args.loss, delay_ms=args.delay)
    with hosts:
        for name in hosts.names:
            print(f"{name}: {hosts.addresses[name]}  ip netns exec {hosts.ns(name)} <command>")
        env = hosts.env({})
        print("in each, set: " + " ".join(f"{k}={v}" for k, v in env.items() if k != "PYTHONUNBUFFERED"))
        print("Ctrl-C removes them", flush=True)
        try:
            signal.pause()
        except KeyboardInterrupt:
            pass
    return 0


if __name__ == "__main__":
    sys.exit(main())
