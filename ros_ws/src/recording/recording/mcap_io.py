"""Tolerant MCAP reading shared by the replay and analysis tools.

The mcap library's readers stop at the first damaged byte (a seeking reader needs the summary
section at the end of the file, a stream reader raises on a cut chunk). A recording that was
cut short (disk full, power loss, a run killed with SIGKILL) or damaged in the middle still
holds most of its messages, so this module parses the MCAP records itself and keeps going:

- records are read one by one from the data section (``mmap``, no full copy in memory);
- a chunk is decompressed in slices (zstd, lz4 or none), so a chunk cut by the end of the
  file still yields the messages of its complete compressed blocks;
- a chunk whose CRC does not match is still read as far as its records parse; its messages
  are marked ``suspect`` (the tools decode each one before use and drop what does not decode);
- after an unreadable stretch (bad opcode, impossible length) the reader resynchronises on
  the next record that passes structural checks (a chunk header with a known compression and
  consistent lengths, or a message on a known channel followed by another valid record);
- every problem is kept as a ``Problem`` (byte offset + what is wrong); ``report()`` gives
  one line per problem, each naming the file;
- metadata records are kept by name (``metadata``; rosbag2's bag metadata: ``rosbag2_metadata()``);
- ``locate_recording`` maps what a user hands the tools (an MCAP file, a rosbag2 directory) to
  the MCAP file to read, and says what to do with what is not MCAP (rosbag2 sqlite3 bags).

Nothing here needs ROS; ``message_class`` / ``decoder`` (bottom) import ROS types on demand.
"""
from __future__ import annotations

import dataclasses
import functools
import heapq
import importlib
import mmap
import os
import struct
import zlib
from typing import Callable, Dict, Iterator, List, Optional, Tuple

MAGIC = b"\x89MCAP0\r\n"

OP_HEADER, OP_FOOTER, OP_SCHEMA, OP_CHANNEL, OP_MESSAGE, OP_CHUNK = 0x01, 0x02, 0x03, 0x04, 0x05, 0x06
OP_MESSAGE_INDEX, OP_CHUNK_INDEX, OP_ATTACHMENT, OP_ATTACHMENT_INDEX = 0x07, 0x08, 0x09, 0x0A
OP_STATISTICS, OP_METADATA, OP_METADATA_INDEX, OP_SUMMARY_OFFSET, OP_DATA_END = 0x0B, 0x0C, 0x0D, 0x0E, 0x0F
KNOWN_OPCODES = set(range(0x01, 0x10))
OP_NAMES = {OP_HEADER: "header", OP_FOOTER: "footer", OP_SCHEMA: "schema", OP_CHANNEL: "channel",
            OP_MESSAGE: "message", OP_CHUNK: "chunk", OP_MESSAGE_INDEX: "message index",
            OP_CHUNK_INDEX: "chunk index", OP_ATTACHMENT: "attachment", OP_ATTACHMENT_INDEX: "attachment index",
            OP_STATISTICS: "statistics", OP_METADATA: "metadata", OP_METADATA_INDEX: "metadata index",
            OP_SUMMARY_OFFSET: "summary offset", OP_DATA_END: "data end"}
COMPRESSIONS = ("", "zstd", "lz4")
MAX_RECORD = 1 << 34  # 16 GiB: a longer record is taken as corrupt length bytes
SLICE = 1 << 16  # compressed bytes fed to the decompressor at a time


class McapReadError(RuntimeError):
    """Nothing readable (not an MCAP file, unreadable path); the message names the file."""


@dataclasses.dataclass
class Problem:
    offset: int  # byte offset in the file where it was found
    what: str

    def __str__(self) -> str:
        return f"byte {self.offset}: {self.what}"


@dataclasses.dataclass
class Schema:
    id: int
    name: str  # e.g. "nav_msgs/msg/Odometry"
    encoding: str  # "ros2msg", "ros2idl", ...
    data: bytes


@dataclasses.dataclass
class Channel:
    id: int
    topic: str
    message_encoding: str  # "cdr" for ROS 2
    metadata: Dict[str, str]
    schema: Optional[Schema]

    @property
    def type_name(self) -> str:
        return self.schema.name if self.schema else ""


@dataclasses.dataclass
class Message:
    channel: Channel
    sequence: int
    log_time: int  # ns
    publish_time: int  # ns
    data: bytes
    index: int  # position in the file (0, 1, ...), keeps ties in file order
    suspect: bool = False  # from a chunk whose CRC did not match

    @property
    def topic(self) -> str:
        return self.channel.topic


def _u16(b, o):
    return struct.unpack_from("<H", b, o)[0]


def _u32(b, o):
    return struct.unpack_from("<I", b, o)[0]


def _u64(b, o):
    return struct.unpack_from("<Q", b, o)[0]


class _Cursor:
    """Bounds-checked reads from a bytes-like object; raises ValueError past `end`."""

    def __init__(self, buf, pos: int, end: int):
        self.buf, self.pos, self.end = buf, pos, end

    def take(self, n: int) -> int:
        if n < 0 or self.pos + n > self.end:
            raise ValueError(f"field of {n} bytes runs past the end of the record")
        p = self.pos
        self.pos += n
        return p

    def u16(self) -> int:
        return _u16(self.buf, self.take(2))

    def u32(self) -> int:
        return _u32(self.buf, self.take(4))

    def u64(self) -> int:
        return _u64(self.buf, self.take(8))

    def bytes(self, n: int) -> bytes:
        p = self.take(n)
        return bytes(self.buf[p:p + n])

    def string(self) -> str:
        n = self.u32()
        return self.bytes(n).decode("utf-8")

    def string_map(self) -> Dict[str, str]:
        n = self.u32()
        stop = self.pos + n
        if stop > self.end:
            raise ValueError("map runs past the end of the record")
        out = {}
        while self.pos < stop:
            k = self.string()
            out[k] = self.string()
        return out


class McapFile:
    """A tolerant reader of one MCAP file.

    ``messages()`` yields every readable message in file order; ``messages_in_time_order()``
    by log time (ties in file order). ``problems`` fills while reading; ``complete`` is True
    once a pass ended at the footer without any problem. Each pass re-reads the file; problems
    are recorded by the first pass only (``scan()`` makes one without keeping messages).
    """

    def __init__(self, path: str):
        self.path = path
        if not os.path.isfile(path):
            raise McapReadError(f"{path}: no such file")
        self.size = os.path.getsize(path)
        self.problems: List[Problem] = []
        self.schemas: Dict[int, Schema] = {}
        self.channels: Dict[int, Channel] = {}
        self.profile = ""
        self.library = ""
        self.message_count = 0  # messages read by the first complete pass
        self.counts: Dict[int, int] = {}  # channel id -> messages read
        self.start_time: Optional[int] = None  # log time range of what was read, ns
        self.end_time: Optional[int] = None
        self.footer_found = False
        self.declared_message_count: Optional[int] = None  # from the statistics record, if read
        self.suspect_messages = 0
        self.metadata: Dict[str, Dict[str, str]] = {}  # metadata records by name (the last of a name wins)
        self._passes = 0
        self._recording = True

    # -- public ---------------------------------------------------------------------------
    @property
    def complete(self) -> bool:
        return self.footer_found and not self.problems

    def scan(self) -> "McapFile":
        """One pass over the file: channels, counts, time range and problems."""
        for _ in self.messages():
            pass
        return self

    def report(self) -> str:
        """What is wrong with the file, one line per problem, each naming the file."""
        if not self.problems:
            return f"{self.path}: OK ({self.message_count} messages, {len(self.channels)} channels)"
        lines = [f"{self.path}: {p}" for p in self.problems]
        if self.message_count:
            t0 = (self.start_time or 0) * 1e-9
            t1 = (self.end_time or 0) * 1e-9
            lines.append(f"{self.path}: readable part: {self.message_count} messages on "
                         f"{len([c for c in self.counts if self.counts[c]])} topics, log time {t0:.3f} .. {t1:.3f} s")
        else:
            lines.append(f"{self.path}: no readable messages")
        return "\n".join(lines)

    def rosbag2_metadata(self) -> Optional[dict]:
        """The bag metadata rosbag2's MCAP storage keeps in the file (metadata record "rosbag2",
        key "serialized_metadata", BagMetadata YAML) as a dict; None if absent or unreadable.
        Filled by the first pass (scan())."""
        text = self.metadata.get("rosbag2", {}).get("serialized_metadata", "")
        if not text.strip():
            return None
        import yaml
        try:
            data = yaml.safe_load(text)
        except yaml.YAMLError:
            return None
        return data if isinstance(data, dict) else None

    def topics(self) -> Dict[str, Channel]:
        """Topic -> channel (the first channel of a topic if several)."""
        out: Dict[str, Channel] = {}
        for ch in sorted(self.channels.values(), key=lambda c: c.id):
            out.setdefault(ch.topic, ch)
        return out

    def messages(self, topics: Optional[Callable[[str], bool]] = None) -> Iterator[Message]:
        """Every readable message in file order (optionally only topics for which topics(t))."""
        first = self._passes == 0
        self._passes += 1
        self._recording = first
        try:
            with open(self.path, "rb") as f:
                if self.size == 0:
                    self._problem(0, "empty file (0 bytes)")
                    return
                with mmap.mmap(f.fileno(), 0, access=mmap.ACCESS_READ) as buf:
                    for msg in self._read(buf):
                        if first:
                            self.message_count += 1
                            self.counts[msg.channel.id] = self.counts.get(msg.channel.id, 0) + 1
                            self.suspect_messages += int(msg.suspect)
                            self.start_time = msg.log_time if self.start_time is None else min(self.start_time, msg.log_time)
                            self.end_time = msg.log_time if self.end_time is None else max(self.end_time, msg.log_time)
                        if topics is None or topics(msg.channel.topic):
                            yield msg
                    if first and self.declared_message_count is not None and self.footer_found and \
                            self.declared_message_count != self.message_count:
                        self._problem(self.size, f"the statistics record declares {self.declared_message_count} "
                                                 f"messages but {self.message_count} were readable")
        except OSError as exc:
            raise McapReadError(f"{self.path}: cannot read: {exc}") from None

    def messages_in_time_order(self, topics: Optional[Callable[[str], bool]] = None,
                               window: int = 200_000) -> Iterator[Message]:
        """Messages by log time, ties in file order. Sorting uses a buffer of `window` messages:
        files written in arrival order (every recorder) come out fully sorted."""
        heap: List[Tuple[int, int, Message]] = []
        for msg in self.messages(topics):
            heapq.heappush(heap, (msg.log_time, msg.index, msg))
            if len(heap) > window:
                yield heapq.heappop(heap)[2]
        while heap:
            yield heapq.heappop(heap)[2]

    # -- internals ------------------------------------------------------------------------
    def _problem(self, offset: int, what: str) -> None:
        if self._recording:
            self.problems.append(Problem(offset, what))

    def _read(self, buf) -> Iterator[Message]:
        size = len(buf)
        self._index = 0
        self.footer_found = False
        if size < len(MAGIC) or bytes(buf[:len(MAGIC)]) != MAGIC:
            self._problem(0, f"not an MCAP file: the first bytes are {bytes(buf[:8])!r}, expected the MCAP magic "
                             f"{MAGIC!r}; looking for readable records further on")
            pos = self._resync(buf, 0)
            if pos is None:
                return
        else:
            pos = len(MAGIC)
        last_chunk = None  # (offset, message start time, end time, uncompressed size) of the last chunk
        while True:
            if pos >= size:
                self._problem(size, f"the file ends after {size} bytes without a footer: truncated (the recording "
                                    f"was not closed, or the file was cut)")
                return
            if pos + 9 > size:
                self._problem(pos, f"truncated: the file ends inside a record header ({size - pos} of 9 bytes)")
                return
            op = buf[pos]
            length = _u64(buf, pos + 1)
            body, end = pos + 9, pos + 9 + length
            if op not in KNOWN_OPCODES or length > MAX_RECORD or (op == OP_MESSAGE and length < 22):
                self._problem(pos, f"corrupt data: a record with opcode 0x{op:02x} and length {length} cannot be "
                                   f"valid; skipping to the next readable record")
                nxt = self._resync(buf, pos + 1)
                if nxt is None:
                    self._problem(pos, "no readable record after this point")
                    return
                self._problem(nxt, f"resumed reading ({nxt - pos} bytes skipped)")
                pos = nxt
                continue
            if end > size:
                what = OP_NAMES.get(op, f"opcode 0x{op:02x}")
                if op == OP_CHUNK:
                    before = self._index
                    yield from self._chunk(buf, pos, body, size, truncated=True)
                    self._problem(pos, f"truncated: the file ends inside a chunk (record of {length} bytes, only "
                                       f"{size - body} present); {self._index - before} messages recovered from its "
                                       f"readable part")
                else:
                    self._problem(pos, f"truncated: the file ends inside a {what} record ({length} bytes, only "
                                       f"{size - body} present)")
                return
            try:
                if op == OP_CHUNK:
                    last_chunk = (pos, _u64(buf, body), _u64(buf, body + 8), _u64(buf, body + 16))
                    yield from self._chunk(buf, pos, body, end, truncated=False)
                elif op in (OP_SCHEMA, OP_CHANNEL, OP_MESSAGE):
                    m = self._inner(buf, op, body, end, pos, suspect=False)
                    if m is not None:
                        yield m
                elif op == OP_HEADER:
                    c = _Cursor(buf, body, end)
                    self.profile, self.library = c.string(), c.string()
                elif op == OP_STATISTICS:
                    c = _Cursor(buf, body, end)
                    self.declared_message_count = c.u64()
                elif op == OP_METADATA and self._recording:
                    c = _Cursor(buf, body, end)
                    name = c.string()
                    self.metadata[name] = c.string_map()
                elif op == OP_MESSAGE_INDEX:
                    self._check_message_index(buf, pos, body, end, last_chunk)
                elif op == OP_DATA_END:
                    crc = _Cursor(buf, body, end).u32()
                    if crc and zlib.crc32(buf[:pos]) != crc:
                        self._problem(pos, "the data section fails its CRC check: some bytes before this point are "
                                           "corrupt")
                elif op == OP_FOOTER:
                    self.footer_found = True
                    c = _Cursor(buf, body, end)
                    summary_start, _, summary_crc = c.u64(), c.u64(), c.u32()
                    if summary_start and summary_crc and summary_start < pos and \
                            zlib.crc32(buf[summary_start:body + 16]) != summary_crc:
                        self._problem(summary_start, "the summary section (indexes, statistics) fails its CRC "
                                                     "check: it is corrupt (the messages were read without it)")
                    if bytes(buf[end:end + len(MAGIC)]) != MAGIC:
                        self._problem(end, "the closing magic after the footer is missing or damaged")
                    return
            except (ValueError, UnicodeDecodeError, struct.error) as exc:
                self._problem(pos, f"unreadable {OP_NAMES.get(op)} record: {exc}")
            pos = end

    def _check_message_index(self, buf, pos: int, body: int, end: int, chunk) -> None:
        """A message index (after its chunk) must list times within the chunk's time range and
        offsets within its data; the messages themselves come from the chunk, so a damaged
        index loses nothing, but it means the file is damaged there."""
        c = _Cursor(buf, body, end)
        try:
            c.u16()  # channel id
            n = c.u32()
            if n != end - c.pos or n % 16:
                raise ValueError(f"its entries take {n} bytes of {end - c.pos}")
            if chunk is None:
                raise ValueError("no chunk before it")
            _, t0, t1, usize = chunk
            for i in range(c.pos, end, 16):
                t, off = _u64(buf, i), _u64(buf, i + 8)
                if not (t0 <= t <= t1 and off < usize):
                    raise ValueError(f"an entry (time {t}, offset {off}) lies outside its chunk")
        except ValueError as exc:
            self._problem(pos, f"corrupt message index ({exc}); the chunk's messages were read without it")

    def _inner(self, buf, op: int, body: int, end: int, pos: int, suspect: bool) -> Optional[Message]:
        """A schema, channel or message record (top level or in a chunk)."""
        c = _Cursor(buf, body, end)
        if op == OP_SCHEMA:
            sid = c.u16()
            name, enc = c.string(), c.string()
            data = c.bytes(c.u32())
            if sid not in self.schemas:
                self.schemas[sid] = Schema(sid, name, enc, data)
            return None
        if op == OP_CHANNEL:
            cid, sid = c.u16(), c.u16()
            topic, enc = c.string(), c.string()
            meta = c.string_map()
            if cid not in self.channels:
                schema = self.schemas.get(sid)
                if sid and schema is None:
                    self._problem(pos, f"channel {topic!r} names schema id {sid}, which was not readable")
                self.channels[cid] = Channel(cid, topic, enc, meta, schema)
            return None
        cid = c.u16()
        seq = c.u32()
        log_time, pub_time = c.u64(), c.u64()
        ch = self.channels.get(cid)
        if ch is None:
            self._problem(pos, f"message on unknown channel id {cid} skipped (its channel record was not readable)")
            return None
        msg = Message(ch, seq, log_time, pub_time, bytes(buf[c.pos:end]), self._index, suspect)
        self._index += 1
        return msg

    def _chunk(self, buf, pos: int, body: int, end: int, truncated: bool) -> Iterator[Message]:
        c = _Cursor(buf, body, end)
        try:
            c.u64(), c.u64()  # message start / end time
            usize, crc = c.u64(), c.u32()
            comp = c.string()
            dlen = c.u64()
        except (ValueError, UnicodeDecodeError) as exc:
            self._problem(pos, f"unreadable chunk header: {exc}")
            return
        if comp not in COMPRESSIONS:
            self._problem(pos, f"chunk with unsupported compression {comp!r} skipped")
            return
        start = c.pos
        stop = min(start + dlen, end)
        data, err = _decompress(comp, buf, start, stop, usize)
        if err:
            self._problem(pos, f"corrupt chunk: its data cannot be decompressed ({comp}: {err}); "
                               f"{len(data)} of {usize} bytes recovered")
        suspect = False
        if not truncated and not err and crc != 0 and len(data) == usize and zlib.crc32(data) != crc:
            suspect = True
            self._problem(pos, "chunk fails its CRC check: its data are corrupt; its records are read as far as "
                               "they parse and its messages marked suspect")
        elif not truncated and not err and len(data) != usize:
            self._problem(pos, f"chunk decompresses to {len(data)} bytes, its header says {usize}")
        p, n = 0, len(data)
        while p + 9 <= n:
            op = data[p]
            length = _u64(data, p + 1)
            if op not in (OP_SCHEMA, OP_CHANNEL, OP_MESSAGE) and op not in KNOWN_OPCODES or length > n:
                if not truncated:
                    self._problem(pos, f"chunk holds a corrupt record (opcode 0x{op:02x}, length {length}) at "
                                       f"offset {p} of its data; the rest of this chunk is skipped")
                return
            if p + 9 + length > n:
                if not truncated:
                    self._problem(pos, f"chunk record at offset {p} of its data runs past the chunk's end")
                return
            if op in (OP_SCHEMA, OP_CHANNEL, OP_MESSAGE):
                try:
                    m = self._inner(data, op, p + 9, p + 9 + length, pos, suspect)
                except (ValueError, UnicodeDecodeError, struct.error) as exc:
                    self._problem(pos, f"unreadable {OP_NAMES[op]} record in chunk: {exc}")
                    m = None
                if m is not None:
                    yield m
            p += 9 + length

    def _valid_record_at(self, buf, p: int, depth: int = 0) -> bool:
        """Does a plausible record start at p? (structure only; used to resynchronise)"""
        size = len(buf)
        if p == size:
            return True  # end of file right after a record: plausible
        if p + 9 > size:
            return False
        op, length = buf[p], _u64(buf, p + 1)
        if op not in KNOWN_OPCODES or length > MAX_RECORD:
            return False
        end = p + 9 + length
        if op == OP_CHUNK:
            if length < 8 + 8 + 8 + 4 + 4 + 8:
                return False
            t0, t1 = _u64(buf, p + 9), _u64(buf, p + 17)
            clen = _u32(buf, p + 37) if p + 41 <= size else -1
            if t0 > t1 or clen not in (0, 3, 4) or p + 41 + clen + 8 > size:
                return False
            if bytes(buf[p + 41:p + 41 + clen]).decode("latin-1") not in COMPRESSIONS:
                return False
            dlen = _u64(buf, p + 41 + clen)
            return length == 8 + 8 + 8 + 4 + 4 + clen + 8 + dlen
        if op == OP_MESSAGE:
            if length < 22 or p + 11 > size or _u16(buf, p + 9) not in self.channels:
                return False
        if end > size:
            return op == OP_CHUNK
        if depth >= 1:
            return True
        return self._valid_record_at(buf, end, depth + 1)

    def _resync(self, buf, start: int) -> Optional[int]:
        """The first offset >= start where a plausible chunk or message record begins."""
        size = len(buf)
        candidates = []
        for comp in (b"\x04\x00\x00\x00zstd", b"\x03\x00\x00\x00lz4", b"\x00\x00\x00\x00"):
            i = buf.find(comp, start + 37)
            while i != -1:
                if self._valid_record_at(buf, i - 37):
                    candidates.append(i - 37)
                    break
                i = buf.find(comp, i + 1)
        if self.channels:
            # a message record found in damaged data must end before the first chunk found: records
            # do not overlap, and a false one (a 0x05 byte in index entries) would otherwise swallow
            # every chunk up to its bogus end
            i = buf.find(b"\x05", start)
            limit = min(candidates) if candidates else size
            while i != -1 and i < limit:
                if i + 9 <= size and i + 9 + _u64(buf, i + 1) <= limit and self._valid_record_at(buf, i):
                    candidates.append(i)
                    break
                i = buf.find(b"\x05", i + 1)
        return min(candidates) if candidates else None


SQLITE_MAGIC = b"SQLite format 3\x00"
ZSTD_MAGIC = b"\x28\xb5\x2f\xfd"


def _head(path: str, n: int = 16) -> bytes:
    try:
        with open(path, "rb") as f:
            return f.read(n)
    except OSError:
        return b""


def _convert_hint(src: str) -> str:
    src = os.path.normpath(src)
    dst = os.path.join(os.path.dirname(src), os.path.splitext(os.path.basename(src))[0] + "_mcap")
    return (f"convert it with the rosbags tool installed here:\n"
            f"    rosbags-convert --src {src} --dst {dst} --dst-storage mcap\n"
            f"  and give this tool the directory it writes ({dst}, holding {os.path.basename(dst)}.mcap);\n"
            f"  or, where rosbag2 is installed: ros2 bag convert -i {src} -o out.yaml   "
            f"(out.yaml: output_bags: [{{uri: {dst}, storage_id: mcap}}])")


def locate_recording(path: str) -> Tuple[str, str]:
    """The MCAP file to read for `path` and a note saying what was found ('' for a plain file).

    path may be an MCAP file (intact or damaged: the tolerant reader copes) or a rosbag2 bag
    directory (metadata.yaml + its storage files) holding one .mcap file. McapReadError, with a
    message naming the file and what to do, for what this reader cannot read: a missing path,
    rosbag2's sqlite3 storage (.db3 file or a directory of them), a zstd-compressed bag file, a
    directory with several .mcap files (a split bag) or none."""
    if os.path.isdir(path):
        return _locate_in_directory(path)
    if not os.path.exists(path):
        raise McapReadError(f"{path}: no such file or directory")
    head = _head(path)
    if head.startswith(SQLITE_MAGIC):
        raise McapReadError(f"{path}: a rosbag2 bag file in sqlite3 storage (.db3), not MCAP; this tool reads "
                            f"MCAP only: {_convert_hint(path)}")
    if head.startswith(ZSTD_MAGIC):
        raise McapReadError(f"{path}: this file is zstd-compressed (rosbag2 file compression), not MCAP: "
                            f"decompress it first (`zstd -d {path}`), or {_convert_hint(path)}")
    return path, ""


def _bag_metadata(meta_path: str) -> Tuple[str, List[str], str]:
    """(storage_identifier, file names, problem) from a rosbag2 metadata.yaml; problem says why
    nothing could be taken from it ('' if read), and the caller then goes by the files present."""
    import yaml
    try:
        with open(meta_path) as f:
            data = yaml.safe_load(f)
    except (OSError, UnicodeDecodeError, yaml.YAMLError) as exc:
        return "", [], f"its metadata.yaml is unreadable: {exc}"
    info = data.get("rosbag2_bagfile_information") if isinstance(data, dict) else None
    if not isinstance(info, dict):
        return "", [], "its metadata.yaml has no rosbag2_bagfile_information mapping"
    paths = info.get("relative_file_paths")
    names = [os.path.basename(str(p)) for p in paths] if isinstance(paths, list) else []
    return str(info.get("storage_identifier") or ""), names, ""


def _locate_in_directory(path: str) -> Tuple[str, str]:
    meta_path = os.path.join(path, "metadata.yaml")
    storage, names, meta_problem = "", [], ""
    if os.path.isfile(meta_path):
        storage, names, meta_problem = _bag_metadata(meta_path)
    listed = sorted(os.listdir(path))
    files = [n for n in names if os.path.isfile(os.path.join(path, n))] or \
        [n for n in listed if n.endswith((".mcap", ".db3", ".mcap.zstd", ".db3.zstd"))
         and os.path.isfile(os.path.join(path, n))]
    kind = "rosbag2 bag directory" if os.path.isfile(meta_path) else "directory"
    sqlite = [n for n in files if n.endswith((".db3", ".db3.zstd")) or
              _head(os.path.join(path, n)).startswith(SQLITE_MAGIC)]
    if sqlite or storage == "sqlite3":
        what = ", ".join(os.path.join(path, n) for n in sqlite) or "metadata.yaml: storage_identifier sqlite3"
        # rosbags-convert reads a bag directory through its metadata.yaml, else a .db3 file itself
        src = path if os.path.isfile(meta_path) or len(sqlite) != 1 else os.path.join(path, sqlite[0])
        raise McapReadError(f"{path}: a {kind} in sqlite3 storage ({what}), not MCAP; this tool reads "
                            f"MCAP only: {_convert_hint(src)}")
    packed = [n for n in files if n.endswith(".zstd")]
    if packed:
        raise McapReadError(f"{path}: a {kind} with compressed bag files ({', '.join(packed)}), not MCAP; "
                            f"{_convert_hint(path)}")
    mcaps = [n for n in files if n.endswith(".mcap")]
    if len(mcaps) == 1:
        found = os.path.join(path, mcaps[0])
        why = f" ({meta_problem}; went by the files present)" if meta_problem else ""
        return found, f"{path}: a {kind} (MCAP storage){why}; reading {found}"
    if len(mcaps) > 1:
        raise McapReadError(f"{path}: a {kind} with {len(mcaps)} MCAP files ({', '.join(mcaps)}: a split bag); give "
                            f"one file, or merge them into one: `rosbags-convert --src {path} --dst "
                            f"{os.path.normpath(path)}_merged --dst-storage mcap`")
    raise McapReadError(f"{path}: a directory without a recording (no .mcap file"
                        + (", metadata.yaml names " + ", ".join(names) if names else "") + ")")


def _decompressor(comp: str):
    """(decompressor object, the exceptions it raises for corrupt input) for "zstd" or "lz4";
    ImportError if the package is missing."""
    if comp == "zstd":
        import zstandard
        return zstandard.ZstdDecompressor().decompressobj(), (zstandard.ZstdError,)
    import lz4.frame
    return lz4.frame.LZ4FrameDecompressor(), (RuntimeError,)  # python-lz4 reports LZ4F errors so


def _decompress(comp: str, buf, start: int, stop: int, usize: int) -> Tuple[bytes, str]:
    """Decompress buf[start:stop] in slices; returns (what could be decompressed, error or '')."""
    if comp == "":
        return bytes(buf[start:stop]), ""
    try:
        d, corrupt = _decompressor(comp)
    except ImportError as exc:
        return b"", f"no decompressor for {comp}: {exc}"
    parts: List[bytes] = []
    try:
        for s in range(start, stop, SLICE):
            parts.append(d.decompress(bytes(buf[s:min(s + SLICE, stop)])))
    except corrupt as exc:
        return b"".join(parts), str(exc) or type(exc).__name__
    return b"".join(parts), ""


# ---------------------------------------------------------------------------------------
# ROS types and decoding
# ---------------------------------------------------------------------------------------
def ros_type_parts(type_name: str) -> Tuple[str, str, str]:
    """'nav_msgs/msg/Odometry' or 'nav_msgs/Odometry' -> ('nav_msgs', 'msg', 'Odometry')."""
    parts = [p for p in type_name.strip().split("/") if p]
    if len(parts) == 2:
        return parts[0], "msg", parts[1]
    if len(parts) == 3:
        return parts[0], parts[1], parts[2]
    raise ValueError(f"{type_name!r} is not a ROS message type name (package/msg/Type)")


def message_class(type_name: str):
    """The Python class of a ROS 2 message type; ImportError says what is missing."""
    pkg, sub, name = ros_type_parts(type_name)
    try:
        module = importlib.import_module(f"{pkg}.{sub}")
    except ImportError as exc:
        raise ImportError(f"type {type_name} is not importable here ({exc}); source the workspace or install "
                          f"the package that defines it") from None
    try:
        return getattr(module, name)
    except AttributeError:
        raise ImportError(f"type {type_name}: package {pkg} has no {sub} {name!r} (different version?)") from None


@functools.lru_cache(maxsize=None)
def ros_decode_errors() -> Tuple[type, ...]:
    """What rclpy's deserialize_message raises for bytes that are not a message of the type: the
    failing rmw_deserialize comes back as rclpy's RMWError (the Jazzy wheels) or RCLError (newer
    rclpy), both RuntimeError subclasses from its C extension. Anything else (TypeError for data
    that are not bytes, AttributeError for a class that is not a ROS message) is a programming
    error and must propagate."""
    from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
    return tuple(getattr(_rclpy, name) for name in ("RMWError", "RCLError") if hasattr(_rclpy, name))


# What a decoder built from a ros2msg schema (mcap_ros2) raises for corrupt CDR: struct.error past
# the end of the data, ValueError (UnicodeDecodeError among them) for bad strings or a too short
# buffer, NotImplementedError for the types it cannot decode (wstring).
SCHEMA_DECODE_ERRORS = (struct.error, ValueError, NotImplementedError)


class Decoder:
    """CDR -> message objects for a file's channels: the installed ROS type (fast, C) when it
    imports, else a decoder built from the file's own ros2msg schema (mcap_ros2, pure Python).

    Messages that do not decode are counted per topic in ``errors`` (``report()`` says so); any
    other exception of a decoder propagates. ``from_schema`` holds the ids of the channels decoded
    with the file's schema, whose messages may lack fields of the installed type (an older
    recording)."""

    def __init__(self):
        self._by_channel: Dict[int, Optional[Tuple[Callable[[bytes], object], Tuple[type, ...]]]] = {}
        self.errors: Dict[str, int] = {}
        self.notes: List[str] = []
        self.from_schema: set = set()

    def for_channel(self, ch: Channel) -> Optional[Tuple[Callable[[bytes], object], Tuple[type, ...]]]:
        """(decode function, the exceptions it raises for corrupt data) of a channel, or None
        (a note says why)."""
        if ch.id in self._by_channel:
            return self._by_channel[ch.id]
        entry = None
        if ch.message_encoding != "cdr":
            self.notes.append(f"{ch.topic}: message encoding {ch.message_encoding!r} is not CDR; not decoded")
        else:
            try:
                cls = message_class(ch.type_name)
                from rclpy.serialization import deserialize_message
            except (ImportError, ValueError) as exc:
                fn = self._from_schema(ch, str(exc))
                if fn is not None:
                    entry = (fn, SCHEMA_DECODE_ERRORS)
                    self.from_schema.add(ch.id)
            else:
                entry = (lambda data, cls=cls: deserialize_message(data, cls), ros_decode_errors())
        self._by_channel[ch.id] = entry
        return entry

    def _from_schema(self, ch: Channel, why: str):
        if ch.schema is None or ch.schema.encoding not in ("ros2msg", "ros2idl"):
            self.notes.append(f"{ch.topic}: {why}; and no ros2msg schema in the file to decode it with")
            return None
        try:
            from mcap.exceptions import McapError
            from mcap.records import Schema as LibSchema
            from mcap_ros2._vendor.rosidl_adapter.parser import InvalidSpecification
            from mcap_ros2.decoder import DecoderFactory
        except ImportError as exc:
            self.notes.append(f"{ch.topic}: {why}; and no decoder for the file's schema here ({exc})")
            return None
        try:
            dec = DecoderFactory().decoder_for("cdr", LibSchema(id=ch.schema.id, name=ch.schema.name,
                                                                encoding=ch.schema.encoding, data=ch.schema.data))
        except (McapError, InvalidSpecification, ValueError) as exc:  # the schema text does not parse
            self.notes.append(f"{ch.topic}: {why}; the file's schema does not give a decoder either ({exc})")
            return None
        if dec is None:
            self.notes.append(f"{ch.topic}: {why}; no decoder for its schema")
            return None
        self.notes.append(f"{ch.topic}: {why}; decoded with the file's own schema instead")
        return dec

    def decode(self, msg: Message):
        """The message object, or None if there is no decoder for its channel (a note says why)
        or its data do not decode (counted in errors)."""
        entry = self.for_channel(msg.channel)
        if entry is None:
            return None
        fn, corrupt = entry
        try:
            return fn(msg.data)
        except corrupt:
            self.errors[msg.channel.topic] = self.errors.get(msg.channel.topic, 0) + 1
            return None

    def report(self) -> List[str]:
        """One line per topic with messages that did not decode."""
        return [f"{topic}: {n} message(s) do not decode as its type (corrupt data); left out"
                for topic, n in sorted(self.errors.items())]
