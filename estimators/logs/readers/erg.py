"""CarMaker ERG results: the binary ``NAME.erg`` and its text ``NAME.erg.info``.

No maintained reader of this format is packaged (the one on PyPI has had no
release for long and reads whole files), so this is a small reader of the
documented layout:

- ``NAME.erg.info`` is a text "infofile": ``key = value`` lines (``#``
  comments), with ``File.Format = erg``, ``File.ByteOrder = LittleEndian``
  or ``BigEndian``, and for each column ``i = 1, 2, ...`` its
  ``File.At.i.Name`` and ``File.At.i.Type`` (``Double``, ``Float``,
  ``LongLong``, ``ULongLong``, ``Int``, ``UInt``, ``Short``, ``UShort``,
  ``Char``, ``UChar``, or ``N Bytes`` of padding), and for a quantity its
  ``Quantity.NAME.Unit``.
- ``NAME.erg`` is a 16-byte header (starting ``CM-ERG``) followed by
  fixed-size records, one per time step, the columns packed in ``File.At``
  order without alignment.
- The infofile may declare the number of records, ``File.NRecords = N``
  (:func:`write_erg` does): a file cut on a record boundary is then found.
  Without it only a cut inside a record is.

All columns share the time column ``Time`` [s]. The file is memory-mapped,
so only the columns read are touched. :func:`write_erg` writes the same
layout (for tests and for exporting a log).
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from wheelload.estimators.logs.readers.channel_map import Channel, ChannelMapError
from wheelload.estimators.logs.readers.formats import ERG_SUFFIXES

SUFFIXES = ERG_SUFFIXES
HEADER_SIZE = 16
MAGIC = b"CM-ERG"
HEADER = MAGIC + bytes(HEADER_SIZE - len(MAGIC))
TIME = "Time"
RECORDS = "File.NRecords"
TYPES = {
    "Double": "f8",
    "Float": "f4",
    "LongLong": "i8",
    "ULongLong": "u8",
    "Int": "i4",
    "UInt": "u4",
    "Short": "i2",
    "UShort": "u2",
    "Char": "i1",
    "UChar": "u1",
}
ORDERS = {"LittleEndian": "<", "BigEndian": ">"}


def info_path(path: Path) -> Path:
    """``NAME.erg.info`` beside ``NAME.erg``."""
    return path.with_name(path.name + ".info")


def parse_info(path: Path) -> dict[str, str]:
    """``key = value`` lines of an infofile (multi-line ``key:`` values are skipped)."""
    if not path.exists():
        raise ChannelMapError(f"{path}: no such file (an ERG log needs its .erg.info beside it)")
    entries = {}
    for line in path.read_text(encoding="utf-8", errors="replace").splitlines():
        line = line.strip()
        if not line or line.startswith("#") or "=" not in line:
            continue
        key, value = line.split("=", 1)
        entries[key.strip()] = value.strip()
    return entries


def erg_layout(path: Path) -> tuple[np.dtype, dict[str, str]]:
    """The record dtype and the units of an ERG file, from its infofile."""
    info_file = info_path(path)
    info = parse_info(info_file)
    with path.open("rb") as stream:
        head = stream.read(len(MAGIC))
    if head != MAGIC:
        raise ChannelMapError(
            f"{path}: does not start with '{MAGIC.decode()}' ({head!r}): not a CarMaker ERG "
            "file; export the results as ERG again"
        )
    if "File.Format" not in info or info["File.Format"] != "erg":
        raise ChannelMapError(f"{info_file}: 'File.Format = erg' is missing")
    order = info["File.ByteOrder"] if "File.ByteOrder" in info else "LittleEndian"
    if order not in ORDERS:
        raise ChannelMapError(f"{info_file}: unknown File.ByteOrder '{order}'")
    fields, i = [], 1
    while f"File.At.{i}.Name" in info:
        name = info[f"File.At.{i}.Name"]
        kind = info[f"File.At.{i}.Type"] if f"File.At.{i}.Type" in info else ""
        padding = re.fullmatch(r"(\d+)\s+Bytes", kind)
        if padding:
            fields.append((f"__pad{i}", f"V{padding.group(1)}"))
        elif kind in TYPES:
            fields.append((name, ORDERS[order] + TYPES[kind]))
        else:
            raise ChannelMapError(f"{info_file}: unknown type '{kind}' of File.At.{i} ('{name}')")
        i += 1
    if not fields:
        raise ChannelMapError(f"{info_file}: no File.At.1.Name: no columns")
    units = {
        key[len("Quantity.") : -len(".Unit")]: value
        for key, value in info.items()
        if key.startswith("Quantity.") and key.endswith(".Unit")
    }
    return np.dtype(fields), units


def declared_records(info_file: Path) -> int | None:
    """The infofile's ``File.NRecords`` (None when absent); not a count is an error."""
    info = parse_info(info_file)
    if RECORDS not in info:
        return None
    value = info[RECORDS]
    if not value.isdigit():
        raise ChannelMapError(f"{info_file}: '{RECORDS} = {value}' is not a record count")
    return int(value)


def erg_channel_names(path: Path) -> list[str]:
    """Names of the columns of an ERG file."""
    dtype, _ = erg_layout(path)
    return [name for name in dtype.names if not name.startswith("__pad") and name != TIME]


def read_erg_channels(path: Path, names: list[str]) -> dict[str, Channel]:
    """The named columns of an ERG file on its ``Time`` column, with their units."""
    dtype, units = erg_layout(path)
    size = path.stat().st_size - HEADER_SIZE
    if size < 0 or size % dtype.itemsize:
        raise ChannelMapError(
            f"{path}: {size} data bytes is not a whole number of {dtype.itemsize}-byte records "
            "(truncated file, or an infofile of another run)"
        )
    declared = declared_records(info_path(path))
    if declared is not None and declared != size // dtype.itemsize:
        raise ChannelMapError(
            f"{path}: has {size // dtype.itemsize} records but its infofile declares "
            f"{RECORDS} = {declared} (truncated file, or an infofile of another run): "
            "copy the whole file again"
        )
    records = np.memmap(path, dtype=dtype, mode="r", offset=HEADER_SIZE)
    if TIME not in dtype.names:
        raise ChannelMapError(f"{info_path(path)}: no column '{TIME}'")
    t = np.array(records[TIME], dtype=float)
    channels = {}
    for name in dict.fromkeys(names):
        if name not in dtype.names:
            raise ChannelMapError(f"{path}: no column '{name}'")
        unit = units[name] if name in units else ""
        channels[name] = Channel(t=t, values=np.array(records[name], dtype=float), unit=unit)
    del records
    return channels


def write_erg(path: Path, columns: dict[str, np.ndarray], units: dict[str, str]) -> None:
    """Write ``columns`` (the first must be ``Time``) as a little-endian ERG of doubles."""
    names = list(columns)
    if names[0] != TIME:
        raise ValueError(f"the first ERG column must be '{TIME}'")
    dtype = np.dtype([(name, "<f8") for name in names])
    records = np.zeros(len(columns[TIME]), dtype=dtype)
    for name in names:
        records[name] = columns[name]
    lines = ["#INFOFILE1.1 - Do not remove this line!", "File.Format = erg",
             "File.ByteOrder = LittleEndian"]  # fmt: skip
    for i, name in enumerate(names, start=1):
        lines += [f"File.At.{i}.Name = {name}", f"File.At.{i}.Type = Double"]
    lines += [f"Quantity.{name}.Unit = {unit}" for name, unit in units.items()]
    lines.append(f"{RECORDS} = {len(records)}")
    path.write_bytes(HEADER + records.tobytes())
    info_path(path).write_text("\n".join(lines) + "\n", encoding="utf-8")
