"""Log readers: CSV, Parquet, MDF4 and CarMaker ERG, through an optional channel map.

:func:`read_frame` returns our columns (SI units, one clock) as a DataFrame,
which ``signals_from_frame`` validates into ``Signals``. The names below are
imported on first use (:mod:`~wheelload.models.runtime.lazy_names`): the lean
whole-log path reads its chunks (``readers/chunks.py``) without the channel maps.
"""

from wheelload.estimators.logs.readers.formats import SUFFIXES
from wheelload.models.runtime.lazy_names import lazy_names

_LAZY_MODULES = {
    "wheelload.estimators.logs.readers.channel_map": (
        "ChannelMap",
        "ChannelMapError",
        "channel_map_template",
        "load_channel_map",
    ),
    "wheelload.estimators.logs.readers.frames": ("channel_names", "read_frame"),
    "wheelload.estimators.logs.readers.resample": ("Method",),
}
__getattr__, __dir__, _LAZY_NAMES = lazy_names(__name__, _LAZY_MODULES)

__all__ = ["SUFFIXES", *_LAZY_NAMES]
