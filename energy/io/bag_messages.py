"""A bag's messages: topics and their types (a ROS 1 bag's own definitions included), times, fields by name."""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

import numpy as np

from terrawatt_base.checks import fmt_number
from terrawatt_base.containers import memory_limit_bytes, over_budget_message
from terrawatt_base.errors import DataError, FileFormatError, OptionalDependencyError

__all__ = [
    "Messages",
    "TopicMessages",
    "BAG_MESSAGE_BYTES",
    "import_rosbags",
    "bag_path",
    "read_messages",
    "expect_type",
    "topic_times",
    "message_fields",
    "field_values",
]

#: Deserialised messages per topic: (receive time in ns, message) in bag order.
Messages = dict[str, list[tuple[int, Any]]]


@dataclasses.dataclass(frozen=True)
class TopicMessages:
    """Messages grouped by topic, as read from a bag or buffered by a node: what a log is built from.

    Attributes
    ----------
    source : str
        The source's name in messages and ``meta.source`` (a bag path).
    raw : dict topic -> list of (int, message)
        Per topic, its messages with their receive times (ns), in receive order.
    types : dict topic -> str
        Per topic, its message type (``"nav_msgs/msg/Odometry"``, ...).
    container : str
        What held the messages, in notes and messages (``"the bag"``).
    """

    source: str
    raw: Messages
    types: dict[str, str]
    container: str = "the bag"


def import_rosbags() -> tuple[Any, Any, Any]:
    """``(AnyReader, Stores, get_typestore)`` of ``rosbags``; OptionalDependencyError without it."""
    try:
        from rosbags.highlevel import AnyReader
        from rosbags.typesys import Stores, get_typestore
    except ImportError as exc:
        raise OptionalDependencyError(
            "read_rosbag needs the optional dependency 'rosbags': pip install 'terrawatt[ros]'"
        ) from exc
    return AnyReader, Stores, get_typestore


def bag_path(path: Any) -> Path:
    """The bag to open: a ``.bag`` file or a ROS 2 bag directory (also from its ``.db3`` / ``.mcap``)."""
    bag = Path(path)
    if bag.is_file() and bag.suffix in (".db3", ".mcap") and (bag.parent / "metadata.yaml").exists():
        bag = bag.parent
    if not bag.exists():
        raise FileFormatError(f"bag {str(bag)!r} does not exist")
    return bag


#: Memory of one deserialised message (bytes): measured 2.6 kB on average over odometry (with
#: its covariances), IMU and status messages of a Husky bag; the bag reader's budget check
#: counts 3 kB per message of the topics it reads.
BAG_MESSAGE_BYTES = 3072


def read_messages(bag: Path, wanted: tuple[str, ...], optional: tuple[str, ...] = ()) -> tuple[Messages, dict[str, str]]:
    """Deserialised messages of each topic of ``wanted`` (all must be in the bag) and of
    ``optional`` (read when present), and the type of every topic of the bag.

    Message types come from the bag itself where it defines them — every ROS 1 bag carries
    each connection's full message definition, so vendor messages such as
    ``husky_msgs/HuskyStatus`` are registered from it (``rosbags`` does this with
    ``get_types_from_msg`` into the reader's typestore) — and from the latest ROS 2 type
    store for ROS 2 bags that do not.

    Raises
    ------
    DataError
        A wanted topic is not in the bag (the message lists the bag's topics and types).
    FileFormatError
        The bag cannot be read or a message cannot be deserialised; the messages of the
        topics read would not fit the memory budget (:data:`BAG_MESSAGE_BYTES` each).
    """
    any_reader, stores, get_typestore = import_rosbags()
    try:
        with any_reader([bag], default_typestore=get_typestore(stores.LATEST)) as reader:
            available = {c.topic: c.msgtype for c in reader.connections}
            missing = [t for t in wanted if t not in available]
            if missing:
                raise DataError(f"{bag}: topic(s) {missing!r} not in the bag; it has {available!r}")
            raw: Messages = {t: [] for t in (*wanted, *optional) if t in available}
            conns = [c for c in reader.connections if c.topic in raw]
            budget = memory_limit_bytes()
            limit = budget // BAG_MESSAGE_BYTES
            declared = sum(int(getattr(c, "msgcount", 0) or 0) for c in conns)
            if declared > limit:
                raise FileFormatError(over_budget_message(
                    repr(str(bag)), f"the {declared} messages of topics {sorted(raw)!r}",
                    declared * BAG_MESSAGE_BYTES, budget))
            n = 0
            for conn, ts_ns, data in reader.messages(connections=conns):
                n += 1
                if n > limit:  # a header that under-declares its messages
                    raise FileFormatError(over_budget_message(
                        repr(str(bag)), f"more than {limit} messages of topics {sorted(raw)!r}",
                        n * BAG_MESSAGE_BYTES, budget))
                raw[conn.topic].append((ts_ns, reader.deserialize(data, conn.msgtype)))
    except (DataError, FileFormatError, OptionalDependencyError):
        raise
    except Exception as exc:  # rosbags raises its own error classes per format
        raise FileFormatError(f"cannot read bag {str(bag)!r}: {type(exc).__name__}: {exc}") from exc
    return raw, available


def expect_type(src: str, raw: Messages, types: dict[str, str], topic: str, allowed: tuple[str, ...],
                hint: str = "", parameter: str | None = None) -> str:
    """The topic's type, checked against ``allowed``, and that it has messages (``hint``: what else to give, naming
    the reader's ``parameter``, which the error carries)."""
    if types[topic] not in allowed:
        raise DataError(f"{src}: topic {topic!r} has type {types[topic]!r}; expected one of {allowed!r}{hint}",
                        parameter=parameter)
    if not raw[topic]:
        raise DataError(f"{src}: topic {topic!r} has no messages")
    return types[topic]


def _stamp_ns(msg: Any) -> int:
    stamp = msg.header.stamp
    return int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec)


def topic_times(
    src: str, topic: str, msgs: list[tuple[int, Any]], use_header_stamps: bool, max_clock_offset_s: float,
    notes: list[str],
) -> np.ndarray:
    """One topic's times (ns): header stamps when asked, all non-zero and near the receive
    times; else the receive times. Appends which to ``notes``.

    Raises
    ------
    DataError
        Header stamps whose median distance to the receive times exceeds ``max_clock_offset_s``.
    """
    received = np.array([ts for ts, _ in msgs], dtype=np.int64)
    if not (use_header_stamps and hasattr(msgs[0][1], "header")):
        notes.append(f"{topic}: receive time")
        return received
    hdr = np.array([_stamp_ns(m) for _, m in msgs], dtype=np.int64)
    if not (hdr != 0).all():
        notes.append(f"{topic}: receive time ({int((hdr == 0).sum())} zero header stamp(s))")
        return received
    offset_s = float(np.median((received - hdr).astype(np.float64))) / 1e9
    if abs(offset_s) > max_clock_offset_s:
        raise DataError(
            f"{src}: topic {topic!r}: median (receive time - header stamp) is {fmt_number(offset_s, 6)} s, "
            f"expected within +/-{fmt_number(max_clock_offset_s)} s (max_clock_offset_s): the publisher's "
            f"and the recorder's clocks disagree, and the receive-time current topics would be "
            f"shifted against this topic; pass use_header_stamps=False to put every topic on the "
            f"receive time"
        )
    notes.append(f"{topic}: header stamps (median receive time - stamp {offset_s:.3g} s)")
    return hdr


def message_fields(msg: Any, prefix: str = "") -> list[str]:
    """The numeric scalar fields of a message, nested ones as dotted paths (``header`` left out).

    Examples
    --------
    >>> from dataclasses import make_dataclass
    >>> Inner = make_dataclass("Inner", [("volts", float)])
    >>> Status = make_dataclass("Status", [("header", object), ("left", float), ("bat", Inner), ("name", str)])
    >>> message_fields(Status(None, 1.0, Inner(24.0), "a"))
    ['left', 'bat.volts']
    """
    out: list[str] = []
    if not dataclasses.is_dataclass(msg):
        return out
    for f in dataclasses.fields(msg):
        value = getattr(msg, f.name)
        if f.name == "header" and not prefix:
            continue
        if dataclasses.is_dataclass(value):
            out += message_fields(value, f"{prefix}{f.name}.")
        elif isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, bool):
            out.append(f"{prefix}{f.name}")
    return out


def field_values(src: str, topic: str, msgtype: str, msgs: list[tuple[int, Any]], name: str, option: str) -> np.ndarray:
    """The values of field ``name`` (a dotted path for nested fields) of every message, as float64.

    Raises
    ------
    DataError
        The message type has no such numeric field: the message names the topic, its type,
        the option (``option``, the reader's parameter: the error carries it) and the numeric fields it does have.
    """
    def bad(why: str) -> DataError:
        return DataError(
            f"{src}: topic {topic!r} ({msgtype}) {why} (named by {option}); its numeric fields are "
            f"{message_fields(msgs[0][1])!r}", parameter=option
        )

    def get(msg: Any) -> Any:
        for part in name.split("."):
            if not dataclasses.is_dataclass(msg) or part not in {f.name for f in dataclasses.fields(msg)}:
                raise bad(f"has no field {name!r}")
            msg = getattr(msg, part)
        return msg

    first = get(msgs[0][1])
    if isinstance(first, bool) or not isinstance(first, (int, float, np.integer, np.floating)):
        raise bad(f"field {name!r} is not a number (got {type(first).__name__})")
    return np.array([get(m) for _, m in msgs], dtype=np.float64)
