"""CSV exports of logger software: AiM Race Studio and MoTeC i2, with their metadata and units.

Both write key-value metadata rows above the channel names, then a row of units; the
layout (as the two programs export it; cells may be quoted, empty rows between the
blocks)::

    "Format","AiM CSV File"                  "Format","MoTeC CSV File",,,"Workbook",""
    "Venue","Track"                          "Venue","Track",,,"Worksheet",""
    "Vehicle","FS car"                       "Vehicle","FS car",,,"Vehicle Desc",""
    "Racer","Driver"                         "Driver","Driver",,,"Engine ID",""
    "Date","Saturday, May 4, 2024"           "Device","ADL3"
    "Time","10:04:37"                        "Log Date","04/05/2024",,,"Origin Time","0","s"
    "Sample Rate","100"                      "Sample Rate","100.000","Hz",,"End Time","60","s"
    "Duration","60.000"                      "Duration","60.000","s",,"Start Distance","0","m"
    "Segment","Session"                      "Beacon Markers","31.520"
    "Beacon Markers","31.520"
                                             "Time","Distance","G Force Lat",...
    "Time","GPS Speed","LateralAcc",...      "s","m","G",...
    "s","km/h","g",...
                                             "0.000","0","0.012",...
    "0.000","87.2","0.012",...

The export is told by its first row (``Format`` and the program's name); the channel-name
row is the first after the metadata block that starts with ``Time``; the units row follows
it; the data start at the first row after it whose first cell is a number. A ``;``
separator takes a decimal comma. Each channel's unit comes from the units row and is
converted by the units table (:mod:`~wheelload.estimators.logs.readers.units`), so a
channel map for an export needs no ``unit`` keys, and no ``[time]`` table (the ``Time``
column, in the units row's unit).
"""

from __future__ import annotations

import csv
from dataclasses import dataclass
from pathlib import Path

from wheelload.estimators.logs.readers.channel_map import Channel, ChannelMapError
from wheelload.estimators.logs.readers.formats import CSV_SUFFIXES

#: The first row's second cell of each program's export, lower case -> the program.
PROGRAMS = {"aim csv file": "AiM Race Studio", "motec csv file": "MoTeC i2"}
#: Rows read to find the channel-name row.
HEADER_ROWS = 200
#: The time column's name in both exports.
TIME = "Time"


@dataclass(frozen=True, kw_only=True)
class LoggerExport:
    """The layout of an AiM or MoTeC CSV export (see module docstring)."""

    program: str
    names: tuple[str, ...]  # channel names; a repeated name gets ".1", ".2" as pandas does
    units: tuple[str, ...]  # one per name ("" where the units row has none)
    data_row: int  # the first data row (0-based line number)
    separator: str
    decimal: str
    metadata: dict[str, str]


def _rows(path: Path) -> tuple[list[list[str]], str]:
    """The first :data:`HEADER_ROWS` rows split into cells, and the separator."""
    with path.open(encoding="utf-8-sig", newline="") as file:
        lines = [line for _, line in zip(range(HEADER_ROWS), file)]
    first = next((line for line in lines if line.strip()), "")
    separator = max((",", ";", "\t"), key=first.count)
    rows = list(csv.reader(lines, delimiter=separator))
    return [[cell.strip() for cell in row] for row in rows], separator


def _unique(names: list[str]) -> tuple[str, ...]:
    seen: dict[str, int] = {}
    result = []
    for name in names:
        count = seen.get(name, 0)
        seen[name] = count + 1
        result.append(name if count == 0 else f"{name}.{count}")
    return tuple(result)


def _is_number(cell: str, decimal: str) -> bool:
    try:
        float(cell.replace(decimal, ".") if decimal != "." else cell)
    except ValueError:
        return False
    return True


def logger_export(path: Path) -> LoggerExport | None:
    """The layout of ``path`` if it is an AiM or MoTeC CSV export, else None."""
    if path.suffix.lower() not in CSV_SUFFIXES:
        return None
    try:
        rows, separator = _rows(path)
    except (UnicodeDecodeError, csv.Error, OSError):
        return None
    filled = [k for k, row in enumerate(rows) if any(row)]
    if not filled:
        return None
    first = rows[filled[0]]
    if len(first) < 2 or first[0].lower() != "format" or first[1].lower() not in PROGRAMS:
        return None
    program = PROGRAMS[first[1].lower()]
    decimal = "," if separator == ";" else "."
    metadata = {}
    header = None
    for k in filled[1:]:
        row = rows[k]
        cells = [cell for cell in row if cell]
        # AiM's metadata has a "Time","10:04:37" row: the header has channel names after
        # Time (more than one, or it follows an empty row)
        if row[0] == TIME and (len(cells) > 2 or not any(rows[k - 1])):
            header = k
            break
        if row[0]:
            metadata[row[0]] = row[1] if len(row) > 1 else ""
    if header is None:
        raise ChannelMapError(
            f"{path}: a {program} CSV export without a channel-name row starting with "
            f"'{TIME}' in its first {HEADER_ROWS} rows: export it again with the time column"
        )
    names = list(rows[header])
    while names and not names[-1]:
        names.pop()
    following = [k for k in filled if k > header]
    units_row = following[0] if following else None
    units = [""] * len(names)
    if units_row is not None and not _is_number(rows[units_row][0], decimal):
        units = (rows[units_row] + [""] * len(names))[: len(names)]
    data = next((k for k in following if _is_number(rows[k][0], decimal)), None)
    if data is None:
        data = (units_row or header) + 1
    return LoggerExport(program=program, names=_unique(names), units=tuple(units),
                        data_row=data, separator=separator, decimal=decimal,
                        metadata=metadata)  # fmt: skip


def read_export_channels(path: Path, export: LoggerExport, names: list[str]) -> dict[str, Channel]:
    """The named channels of an export on its ``Time`` column, each with its unit from
    the units row (time in seconds: the units row's time unit converted)."""
    import pandas as pd

    from wheelload.estimators.logs.readers.units import Kind, UnitError, unit_factor

    missing = [name for name in names if name not in export.names]
    if missing:
        raise ChannelMapError(
            f"{path}: no channel '{missing[0]}' in the {export.program} export; its channels: "
            f"{', '.join(export.names[:40])}"
        )
    if TIME not in export.names:
        raise ChannelMapError(f"{path}: the {export.program} export has no '{TIME}' column")
    wanted = list(dict.fromkeys([TIME, *names]))
    frame = pd.read_csv(
        path,
        sep=export.separator,
        decimal=export.decimal,
        header=None,
        names=list(export.names),
        usecols=wanted,
        skiprows=export.data_row,
        skip_blank_lines=True,
        encoding="utf-8-sig",
    )
    unit = dict(zip(export.names, export.units, strict=True))
    try:
        factor = unit_factor(unit[TIME] or "s", Kind.TIME, f"{path}: column '{TIME}'")
    except UnitError as error:
        raise ChannelMapError(str(error)) from None
    t = pd.to_numeric(frame[TIME], errors="coerce").to_numpy(float) * factor
    return {
        name: Channel(
            t=t,
            values=pd.to_numeric(frame[name], errors="coerce").to_numpy(float),
            unit=unit[name],
        )
        for name in wanted
        if name != TIME
    } | {TIME: Channel(t=t, values=t, unit="s")}
