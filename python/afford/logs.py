"""A run's log as Python data: afford.read_log(run_folder).

The log is read by the project's own log reader and each message is decoded
and checked as the processes' edge checks it (the C++ module _afford): no
file format or message layout is written again in Python. The messages come
in step order (docs/watching.md, "A log's order"), whatever the log's
interleaving of its channels. Scenes come as
height x width x 3 arrays of bytes; focus images (and the other images of
side x side RGB pixels) as side x side x 3 arrays.
"""
from __future__ import annotations

import math
import warnings
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Iterator

import numpy as np
import pandas as pd

from . import _afford

# Fields holding focus images, row-major RGB, flat in the message.
_IMAGE_FIELDS = ("image", "images", "diff_image", "what")


def _shaped(fields: dict[str, Any]) -> dict[str, Any]:
    for name in _IMAGE_FIELDS:
        a = fields.get(name)
        if not isinstance(a, np.ndarray) or a.ndim == 3 or a.size == 0:
            continue
        per_image = a.shape[-1]
        side = math.isqrt(per_image // 3)
        if side * side * 3 == per_image:
            fields[name] = a.reshape(a.shape[:-1] + (side, side, 3))
    return fields


def _short(value: Any) -> str:
    """A field's value as a repr shows it: arrays by shape and type, long text and lists cut."""
    if isinstance(value, np.ndarray):
        return f"<{value.dtype} array {'x'.join(map(str, value.shape)) or 'scalar'}>"
    if isinstance(value, (list, tuple)) and len(value) > 8:
        return f"<{type(value).__name__} of {len(value)}>"
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "...'" if isinstance(value, str) else text[:57] + "..."


@dataclass(frozen=True, eq=False)
class Message(Mapping):
    """One message of a run's log: its channel, when it was recorded, and its fields.

    A read-only mapping of its fields (m["step"], m.keys(), m.items(),
    dict(m)); `fields` is the same dict.
    """

    channel: str
    utime: int                 # when the logger recorded it, microseconds (not always in step order)
    fields: dict[str, Any]     # the message's fields by name (docs/processes-and-channels.md)

    def __getitem__(self, name: str) -> Any:
        try:
            return self.fields[name]
        except KeyError:
            raise KeyError(f"{self.channel} has no field {name!r} (its fields: {', '.join(self.fields)})") from None

    def __iter__(self) -> Iterator[str]:
        return iter(self.fields)

    def __len__(self) -> int:
        return len(self.fields)

    def __repr__(self) -> str:
        shown = ", ".join(f"{k}={_short(v)}" for k, v in self.fields.items())
        return f"Message({self.channel}, utime={self.utime}: {shown})"


@dataclass
class RunLog:
    run_id: str
    config_yaml: str           # the run's configuration, as its RUN_CONFIG carried it
    messages: list[Message]
    refused: int               # events their channel's type refuses (corrupted), skipped
    first_refusal: str         # ... and why the first one was refused
    unknown_channels: int      # events of channels the protocol does not have, skipped
    malformed: int             # malformed parts of the files, skipped
    torn_bytes: int            # an incomplete last event (a writer cut mid-write)
    cut: list[str]             # what the log lacks of the run when it is cut short (empty: whole)

    def __iter__(self) -> Iterator[Message]:
        return iter(self.messages)

    def __len__(self) -> int:
        return len(self.messages)

    def channel(self, name: str) -> list[Message]:
        """The messages of one channel, in their order."""
        return [m for m in self.messages if m.channel == name]

    def frame(self, name: str) -> pd.DataFrame:
        """The scalar fields of one channel's messages, one row each (arrays left out)."""
        rows = [{"utime": m.utime, **{k: v for k, v in m.fields.items()
                                      if not isinstance(v, (np.ndarray, list, dict))}} for m in self.channel(name)]
        return pd.DataFrame(rows)

    def __repr__(self) -> str:
        counts: dict[str, int] = {}
        for m in self.messages:
            counts[m.channel] = counts.get(m.channel, 0) + 1
        cut = f", CUT: {'; '.join(self.cut)}" if self.cut else ""
        return f"RunLog({self.run_id!r}: {len(self.messages)} messages, {counts}{cut})"


class LogCutWarning(UserWarning):
    """A log read is cut short: it holds less than its run (what is missing is in the message)."""


def read_log(log: str | Path, run: str | None = None, bus_key: str | Path | None = None,
             channels: list[str] | None = None) -> RunLog:
    """The messages of one run, in step order: `log` a run's log folder (logs/<run-id>) or one .lcm file.

    `run` picks a run in a log of several (default: the first); `bus_key`, the
    key file of a keyed bus an lcm-logger recording was made on; `channels`
    keeps only those channels (faster: the others are not decoded). Raises
    RuntimeError naming the file when there is no log or no run in it. A log
    cut short (a copy of part of it, a writer killed) is read as far as it
    goes, with a warning (LogCutWarning) saying what is missing; `cut` says it too.
    """
    raw = _afford.read_log(str(log), run or "", str(bus_key) if bus_key else "", list(channels or []))
    messages = [Message(channel, utime, _shaped(fields)) for channel, utime, fields in raw["messages"]]
    if raw["cut"]:
        warnings.warn(f"{log}: the log is cut, it is not the whole run: {'; '.join(raw['cut'])}", LogCutWarning,
                      stacklevel=2)
    return RunLog(raw["run_id"], raw["config_yaml"], messages, raw["refused"], raw["first_refusal"],
                  raw["unknown_channels"], raw["malformed"], raw["torn_bytes"], list(raw["cut"]))

