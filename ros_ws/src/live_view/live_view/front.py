"""The WebSocket server's front door: checks each connection's upgrade request, then pipes bytes.

foxglove-sdk's start_server (0.30) has no hook to look at a connecting client's request (no
Origin or Host check, no connect callback, no connection count), and every browser page may open
a WebSocket to 127.0.0.1. So the node puts this small asyncio server, in its own thread, on the
served host and port: it reads the HTTP upgrade request (at most MAX_HEAD bytes, within
HEAD_TIMEOUT), refuses with 403 a wrong Host (DNS rebinding) or Origin (a page of another site)
and with 503 a connection beyond ``max_clients``, each with a text naming what is wrong, counted
and logged by the node (on_refused); an accepted request goes to the SDK server and the bytes are
piped both ways until either side closes.

Subprotocols: the SDK server speaks ``foxglove.sdk.v1`` only, the name Foxglove gave in 2025 to
the protocol that was ``foxglove.websocket.v1``: the same messages, opcodes and fields (Foxglove's
stance, github.com/orgs/foxglove/discussions/1131: "currently identical"; Lichtblick PR 819 added
the new name beside the old for that reason; tests/ros/test_foxglove_older_client.py subscribes
and decodes with ``@foxglove/ws-protocol`` 0.8.0). So a client that offers only the older name (ws-protocol 0.8,
Lichtblick releases before December 2025) is passed on as if it had offered the new one,
and the server's answer names the protocol the client offered (negotiate_subprotocol). A request
offering neither is refused with 400 naming the two it may offer.

The SDK server itself listens on 127.0.0.1, on a port of the system's choosing, with TLS (a
key and self-signed certificate made at start-up by ``openssl``, never stored): a browser page
that finds that port cannot complete the handshake (the certificate is no one's it trusts, and a
page's WebSocket has no way to accept it), while this front door trusts exactly that certificate.
Without openssl the node serves without client publishing (see LiveViewNode).
"""
from __future__ import annotations

import asyncio
import os
import ssl
import subprocess
import tempfile
import threading
import time
from typing import Callable, Dict, Optional, Tuple

MAX_HEAD = 16384  # bytes of an upgrade request's line and headers
HEAD_TIMEOUT = 10.0  # s to send them
PIPE_CHUNK = 65536
SDK_SUBPROTOCOL = "foxglove.sdk.v1"  # what the SDK server speaks
OLDER_SUBPROTOCOLS = ("foxglove.websocket.v1",)  # the same protocol under its earlier name
_PROTOCOL_HEADER = b"sec-websocket-protocol:"


def make_certificate() -> Tuple[bytes, bytes]:
    """(certificate PEM, PKCS#8 key PEM) of a fresh P-256 key, self-signed for 127.0.0.1, made by
    the openssl command (OSError / CalledProcessError when it is not there or fails)."""
    with tempfile.TemporaryDirectory(prefix="live-view-tls-") as d:
        key, cert = os.path.join(d, "key.pem"), os.path.join(d, "cert.pem")
        subprocess.run(["openssl", "req", "-x509", "-newkey", "ec", "-pkeyopt", "ec_paramgen_curve:prime256v1",
                        "-nodes", "-keyout", key, "-out", cert, "-days", "30", "-subj", "/CN=tugsim-live-view",
                        "-addext", "subjectAltName=IP:127.0.0.1"],
                       check=True, capture_output=True, timeout=20)
        with open(cert, "rb") as f_cert, open(key, "rb") as f_key:
            return f_cert.read(), f_key.read()


def parse_head(head: bytes) -> Tuple[str, Dict[str, str]]:
    """(request line, headers by lower-case name) of an HTTP request head; a header sent twice
    keeps both values joined by ', ' (so a second Host or Origin cannot hide behind the first)."""
    lines = head.decode("latin-1").split("\r\n")
    headers: Dict[str, str] = {}
    for line in lines[1:]:
        if not line:
            continue
        name, sep, value = line.partition(":")
        if not sep:
            continue
        name = name.strip().lower()
        headers[name] = f"{headers[name]}, {value.strip()}" if name in headers else value.strip()
    return lines[0], headers


def offered_subprotocols(headers: Dict[str, str]) -> list:
    """The subprotocols a WebSocket upgrade request offers, in its order."""
    return [p.strip() for p in headers.get("sec-websocket-protocol", "").split(",") if p.strip()]


def negotiate_subprotocol(offered: list) -> Tuple[Optional[str], Optional[str]]:
    """(the subprotocol to answer the client with, None if it is refused; why refused). The SDK's
    name is preferred; an older name of the same protocol is answered with that name."""
    if SDK_SUBPROTOCOL in offered:
        return SDK_SUBPROTOCOL, None
    for name in offered:
        if name in OLDER_SUBPROTOCOLS:
            return name, None
    return None, (f"the WebSocket subprotocols offered ({', '.join(offered) or 'none'}) are not the Foxglove "
                  f"protocol: offer {SDK_SUBPROTOCOL} or {', '.join(OLDER_SUBPROTOCOLS)}")


def with_subprotocol(head: bytes, name: str) -> bytes:
    """An HTTP head (request or answer) whose Sec-WebSocket-Protocol header says only `name`."""
    lines = head.split(b"\r\n")
    for i, line in enumerate(lines):
        if line.lower().startswith(_PROTOCOL_HEADER):
            lines[i] = line[:len(_PROTOCOL_HEADER)] + b" " + name.encode("latin-1")
    return b"\r\n".join(lines)


def _answer(code: int, reason: str, text: str) -> bytes:
    body = (text + "\n").encode()
    return (f"HTTP/1.1 {code} {reason}\r\nContent-Type: text/plain; charset=utf-8\r\n"
            f"Content-Length: {len(body)}\r\nConnection: close\r\n\r\n").encode() + body


class CheckedFront:
    """The front door (see the module docstring). check(headers) -> (kind, why) of a refusal or
    None; on_refused(kind, why) counts and logs it."""

    def __init__(self, host: str, port: int, backend_port: int, backend_ssl: Optional[ssl.SSLContext],
                 max_clients: int, check: Callable[[Dict[str, str], int], Optional[Tuple[str, str]]],
                 on_refused: Callable[[str, str], None]):
        self.backend_port, self.backend_ssl = backend_port, backend_ssl
        self.max_clients, self.check, self.on_refused = max_clients, check, on_refused
        self.active = 0
        self.accepted = 0  # connections passed on to the server
        self.cpu = 0.0  # s of the front door thread's CPU (known once stopped)
        self.loop = asyncio.new_event_loop()
        self._tasks: set = set()
        self._server = self.loop.run_until_complete(
            asyncio.start_server(self._serve, host, port, limit=MAX_HEAD, backlog=64))
        self.port = self._server.sockets[0].getsockname()[1]
        self.thread = threading.Thread(target=self.loop.run_forever, name="live-view-front", daemon=True)
        self.thread.start()

    async def _serve(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        task = asyncio.current_task()
        self._tasks.add(task)
        counted = False
        try:
            if self.active >= self.max_clients:
                await self._refuse(reader, writer, "connections", 503, "Service Unavailable",
                                   f"more than {self.max_clients} connections at once (parameter max_clients)")
                return
            self.active += 1
            counted = True
            try:
                head = await asyncio.wait_for(reader.readuntil(b"\r\n\r\n"), HEAD_TIMEOUT)
            except (asyncio.TimeoutError, asyncio.IncompleteReadError, asyncio.LimitOverrunError, OSError) as exc:
                why = {asyncio.TimeoutError: f"no complete request in {HEAD_TIMEOUT:g} s",
                       asyncio.LimitOverrunError: f"a request head of more than {MAX_HEAD} bytes"}.get(
                    type(exc), "the connection closed before its request was complete")
                await self._refuse(reader, writer, "request", 400, "Bad Request", why)
                return
            _, headers = parse_head(head)
            refusal = self.check(headers, self.port)
            if refusal is not None:
                kind, why = refusal
                await self._refuse(reader, writer, kind, 403, "Forbidden", why)
                return
            answer_as, why = negotiate_subprotocol(offered_subprotocols(headers))
            if answer_as is None:
                await self._refuse(reader, writer, "subprotocol", 400, "Bad Request", why)
                return
            try:
                b_reader, b_writer = await asyncio.open_connection(
                    "127.0.0.1", self.backend_port, ssl=self.backend_ssl,
                    server_hostname="127.0.0.1" if self.backend_ssl else None, limit=PIPE_CHUNK)
            except (OSError, ssl.SSLError) as exc:
                await self._refuse(reader, writer, "backend", 503, "Service Unavailable",
                                   f"the live view is not serving: {exc}")
                return
            self.accepted += 1
            if answer_as != SDK_SUBPROTOCOL:
                if not await self._upgrade_as(head, answer_as, writer, b_reader, b_writer):
                    return
            else:
                b_writer.write(head)
            # either side ending ends the connection (a WebSocket is not used half-closed)
            pipes = [asyncio.ensure_future(self._pipe(reader, b_writer)),
                     asyncio.ensure_future(self._pipe(b_reader, writer))]
            try:
                await asyncio.wait(pipes, return_when=asyncio.FIRST_COMPLETED)
            finally:
                for p in pipes:
                    p.cancel()
                b_writer.close()
        except asyncio.CancelledError:
            pass
        finally:
            if counted:
                self.active -= 1
            writer.close()
            self._tasks.discard(task)

    @staticmethod
    async def _upgrade_as(head: bytes, name: str, writer: asyncio.StreamWriter, b_reader: asyncio.StreamReader,
                          b_writer: asyncio.StreamWriter) -> bool:
        """Pass an upgrade request offering an older name of the protocol on as the SDK's, and the
        server's answer back naming the client's (a client checks that the server chose one it
        offered). False if the server closed before answering."""
        b_writer.write(with_subprotocol(head, SDK_SUBPROTOCOL))
        try:
            answer = await asyncio.wait_for(b_reader.readuntil(b"\r\n\r\n"), HEAD_TIMEOUT)
        except (asyncio.TimeoutError, asyncio.IncompleteReadError, asyncio.LimitOverrunError, OSError,
                ssl.SSLError):
            b_writer.close()
            return False
        writer.write(with_subprotocol(answer, name))
        return True

    @staticmethod
    async def _pipe(reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        try:
            while True:
                data = await reader.read(PIPE_CHUNK)
                if not data:
                    return
                writer.write(data)
                await writer.drain()
        except (OSError, ssl.SSLError, asyncio.IncompleteReadError):
            return

    async def _refuse(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter, kind: str, code: int,
                      reason: str, why: str) -> None:
        """Counted and logged by the node; the answer names why. The client's bytes are read
        until it closes (at most a second): closing with unread input would reset the connection
        and could lose the answer."""
        self.on_refused(kind, why)
        try:
            writer.write(_answer(code, reason, f"refused: {why}"))
            await writer.drain()
            writer.write_eof()
            end = self.loop.time() + 1.0
            while self.loop.time() < end and await asyncio.wait_for(reader.read(PIPE_CHUNK), end - self.loop.time()):
                pass
        except (OSError, RuntimeError, asyncio.TimeoutError, asyncio.LimitOverrunError):
            pass

    def stop(self) -> None:
        async def close() -> float:
            self._server.close()
            for task in list(self._tasks):
                task.cancel()
            await asyncio.sleep(0)
            return time.thread_time()  # this thread's CPU: what piping the clients' bytes cost
        if self.loop.is_running():
            self.cpu = asyncio.run_coroutine_threadsafe(close(), self.loop).result(5.0)
            self.loop.call_soon_threadsafe(self.loop.stop)
            self.thread.join(5.0)
        self.loop.close()
