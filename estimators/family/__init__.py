"""The papers' comparison methods, one module each, each exporting ``INFO: MethodInfo``.

Every method is a :class:`~wheelload.estimators.family.step_method.FamilyMethod`
(one constructor: a vehicle and its vehicle model, ``suspension``) over one
CasADi step Function; collected by :mod:`wheelload.estimators.registry` (see
``FAMILY_MODULES``).
"""
