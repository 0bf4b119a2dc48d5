"""Vehicle physics, written once, symbolically in CasADi.

Every name of this face is imported on first use, by module (``_LAZY_MODULES``,
:mod:`~wheelload.models.runtime.lazy_names`): reading a vehicle file imports none of the
symbolic models, and a warm estimate takes their numbers from compiled C
(:mod:`~wheelload.models.runtime.function_library`).
"""

from wheelload.models.runtime.lazy_names import lazy_names

_LAZY_MODULES = {
    "wheelload.models.conventions": ("GRAVITY", "WHEELS"),
    "wheelload.models.equilibrium": ("equilibrium_function", "paper_equilibrium_function"),
    "wheelload.models.inputs": ("INPUTS", "OPTIONAL_INPUTS"),
    "wheelload.models.mass_properties": ("MassCentre", "static_loads", "vehicle_mass_centre"),
    "wheelload.models.parameters": ("ModelParameters",),
    "wheelload.models.suspension.pseudo_measurement": ("suspension_function", "travel_function"),
    "wheelload.models.terms": ("DROPPABLE", "GATES", "gates_function"),
    "wheelload.models.vehicle.description": (
        "ModelTerms",
        "Vehicle",
        "VehicleFileError",
        "vehicle_from_dict",
    ),
    "wheelload.models.vehicle.file": ("example_vehicle_path", "load_vehicle", "vehicle_template"),
}
__getattr__, __dir__, _LAZY_NAMES = lazy_names(__name__, _LAZY_MODULES)

__all__ = list(_LAZY_NAMES)
