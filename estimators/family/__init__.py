"""The papers' comparison methods, one module each, each exporting ``INFO: MethodInfo``.

Collected by :mod:`wheelload.estimators.registry` (see ``FAMILY_MODULES``).
"""
