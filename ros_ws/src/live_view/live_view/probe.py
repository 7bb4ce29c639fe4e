"""A small Foxglove WebSocket client (the `websockets` package): what the tests and the live-view
benchmark connect with, speaking the protocol Foxglove and Lichtblick speak (subprotocol
foxglove.sdk.v1; JSON control messages, binary message data)."""
from __future__ import annotations

import asyncio
import json
import struct
from typing import Dict, List, Optional, Tuple

SUBPROTOCOL = "foxglove.sdk.v1"
OP_MESSAGE_DATA = 1  # server -> client binary: subscription id u32, log time u64, payload
OP_TIME = 2  # server -> client binary: time u64
OP_CLIENT_MESSAGE = 1  # client -> server binary: client channel id u32, payload


class Probe:
    def __init__(self, url: str):
        self.url = url
        self.ws = None
        self.server_info: dict = {}
        self.channels: Dict[int, dict] = {}  # channel id -> advertised channel
        self.subscriptions: Dict[int, int] = {}  # subscription id -> channel id
        self.messages: Dict[str, List[Tuple[int, bytes]]] = {}  # topic -> (log time, payload)
        self.times: List[int] = []
        self.status: List[dict] = []

    async def connect(self, timeout: float = 10.0, origin: Optional[str] = None) -> None:
        """Connect, retrying until the server listens (up to timeout s); origin: the Origin header a
        browser page would send (none: a program's connection)."""
        import websockets
        loop = asyncio.get_running_loop()
        deadline = loop.time() + timeout
        while True:
            try:
                self.ws = await websockets.connect(self.url, subprotocols=[SUBPROTOCOL], max_size=None,
                                                   open_timeout=timeout, origin=origin)
                return
            except OSError:
                if loop.time() > deadline:
                    raise
                await asyncio.sleep(0.2)

    async def wait_for_topics(self, topics, timeout: float = 10.0) -> None:
        """Read until every topic has been advertised."""
        loop = asyncio.get_running_loop()
        deadline = loop.time() + timeout
        while not set(topics) <= {c["topic"] for c in self.channels.values()}:
            await self.receive(max(0.01, deadline - loop.time()))
            if loop.time() > deadline:
                raise TimeoutError(f"not advertised: {sorted(set(topics) - {c['topic'] for c in self.channels.values()})}")

    async def subscribe_all(self) -> None:
        subs = []
        for cid in self.channels:
            if cid not in self.subscriptions.values():
                sid = len(self.subscriptions) + 1
                self.subscriptions[sid] = cid
                subs.append({"id": sid, "channelId": cid})
        if subs:
            await self.ws.send(json.dumps({"op": "subscribe", "subscriptions": subs}))

    async def receive(self, timeout: float) -> bool:
        """Handle one frame; False on timeout."""
        try:
            frame = await asyncio.wait_for(self.ws.recv(), timeout)
        except asyncio.TimeoutError:
            return False
        if isinstance(frame, str):
            msg = json.loads(frame)
            op = msg.get("op")
            if op == "serverInfo":
                self.server_info = msg
            elif op == "advertise":
                for c in msg["channels"]:
                    self.channels[c["id"]] = c
            elif op == "unadvertise":
                for cid in msg["channelIds"]:
                    self.channels.pop(cid, None)
            elif op == "status":
                self.status.append(msg)
            return True
        if frame[0] == OP_MESSAGE_DATA:
            sid, log_time = struct.unpack_from("<IQ", frame, 1)
            cid = self.subscriptions.get(sid)
            if cid is not None and cid in self.channels:
                self.messages.setdefault(self.channels[cid]["topic"], []).append((log_time, bytes(frame[13:])))
        elif frame[0] == OP_TIME:
            self.times.append(struct.unpack_from("<Q", frame, 1)[0])
        return True

    async def run_for(self, seconds: float) -> None:
        loop = asyncio.get_running_loop()
        end = loop.time() + seconds
        while loop.time() < end:
            await self.receive(max(0.001, end - loop.time()))

    async def advertise(self, channel_id: int, topic: str, encoding: str, schema_name: str,
                        schema: Optional[str] = None) -> None:
        c = {"id": channel_id, "topic": topic, "encoding": encoding, "schemaName": schema_name}
        if schema is not None:
            c["schema"], c["schemaEncoding"] = schema, "ros2msg"
        await self.ws.send(json.dumps({"op": "advertise", "channels": [c]}))

    async def publish(self, channel_id: int, payload: bytes) -> None:
        await self.ws.send(struct.pack("<BI", OP_CLIENT_MESSAGE, channel_id) + payload)

    async def close(self) -> None:
        if self.ws is not None:
            await self.ws.close()
