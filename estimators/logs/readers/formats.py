"""The log formats the readers take, by file suffix (lower case)."""

CSV_SUFFIXES = (".csv",)
PARQUET_SUFFIXES = (".parquet", ".pq")
MDF_SUFFIXES = (".mf4", ".mdf", ".dat")
ERG_SUFFIXES = (".erg",)
#: Every log format: CSV, Parquet, MDF4, CarMaker ERG.
SUFFIXES = (*CSV_SUFFIXES, *PARQUET_SUFFIXES, *MDF_SUFFIXES, *ERG_SUFFIXES)
