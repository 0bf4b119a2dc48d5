"""The log formats the readers take, by file suffix (lower case)."""

CSV_SUFFIXES = (".csv",)
PARQUET_SUFFIXES = (".parquet", ".pq")
MDF_SUFFIXES = (".mf4", ".mdf", ".dat")
ERG_SUFFIXES = (".erg",)
#: Vector CAN logs, decoded with a DBC (``readers/can_bus.py``).
CAN_SUFFIXES = (".blf", ".asc")
#: Every log format: CSV, Parquet, MDF4, CarMaker ERG, Vector BLF and ASC.
SUFFIXES = (*CSV_SUFFIXES, *PARQUET_SUFFIXES, *MDF_SUFFIXES, *ERG_SUFFIXES, *CAN_SUFFIXES)
