"""ASAM MDF4 (``.mf4``, ``.mdf``) logs through ``asammdf``.

Each channel keeps its own time stamps and declared unit; values are the
physical values of the file's conversion rules. Only the channels a channel
map names are read.

A damaged file (truncated, overwritten blocks) is one :class:`ChannelMapError`
naming the file: asammdf's half-built object, whose ``__del__`` fails on such a
file, is collected while its unraisable-exception report is held back, so no
traceback follows the message.
"""

from __future__ import annotations

import contextlib
import gc
import sys
from collections.abc import Iterator
from pathlib import Path

import numpy as np

from wheelload.estimators.logs.readers.channel_map import Channel, ChannelMapError
from wheelload.estimators.logs.readers.formats import MDF_SUFFIXES

SUFFIXES = MDF_SUFFIXES


def _from_asammdf(unraisable) -> bool:
    """Whether an unraisable exception comes from an asammdf object's ``__del__``."""
    owner = getattr(unraisable.object, "__module__", None) or type(unraisable.object).__module__
    return str(owner).startswith("asammdf")


@contextlib.contextmanager
def _quiet_finaliser() -> Iterator[None]:
    """Hold back asammdf's ``__del__`` reports (others go to the usual hook) until the
    objects made inside are collected."""
    previous = sys.unraisablehook

    def hook(unraisable) -> None:
        if not _from_asammdf(unraisable):
            previous(unraisable)

    sys.unraisablehook = hook
    try:
        yield
    finally:
        gc.collect()
        sys.unraisablehook = previous


@contextlib.contextmanager
def open_mdf(path: Path) -> Iterator:
    """The open ``asammdf.MDF`` of ``path``, closed on leaving; a damaged file is one line."""
    from asammdf import MDF

    message = None
    with _quiet_finaliser():
        try:
            mdf = MDF(path)
        except Exception as error:  # asammdf raises many kinds for a damaged file
            message = f"{path}: not a readable MDF file ({type(error).__name__}: {error})"
        if message is None:
            try:
                with mdf:
                    yield mdf
            except ChannelMapError:
                raise
            except Exception as error:  # a damaged data block, found when read
                message = f"{path}: not a readable MDF file ({type(error).__name__}: {error})"
    if message is not None:
        raise ChannelMapError(message + ": export it again from the logger software")


def mdf_channel_names(path: Path) -> list[str]:
    """Names of the channels in an MDF file (time channels left out)."""
    with open_mdf(path) as mdf:
        return _names(mdf)


def _names(mdf) -> list[str]:
    return sorted(name for name in mdf.channels_db if name.lower() not in ("t", "time"))


def read_mdf_channels(path: Path, names: list[str]) -> dict[str, Channel]:
    """The named channels of an MDF file with their time stamps and units."""
    channels = {}
    with open_mdf(path) as mdf:
        for name in dict.fromkeys(names):
            if name not in mdf.channels_db:
                raise ChannelMapError(
                    f"{path}: no channel '{name}'; the file has {', '.join(_names(mdf)[:30])}"
                )
            if len(mdf.channels_db[name]) > 1:
                raise ChannelMapError(
                    f"{path}: channel '{name}' is in {len(mdf.channels_db[name])} channel groups; "
                    "export one of them under its own name"
                )
            signal = mdf.get(name)
            channels[name] = Channel(
                t=np.asarray(signal.timestamps, float),
                values=np.asarray(signal.samples, float),
                unit=str(signal.unit or ""),
            )
    return channels
