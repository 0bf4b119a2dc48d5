"""Vehicle physics, written once, symbolically in CasADi."""

from wheelload.models.conventions import GRAVITY, WHEELS
from wheelload.models.equilibrium import equilibrium_function, paper_equilibrium_function
from wheelload.models.inputs import INPUTS, OPTIONAL_INPUTS
from wheelload.models.mass_properties import MassCentre, static_loads, vehicle_mass_centre
from wheelload.models.parameters import ModelParameters
from wheelload.models.suspension.pseudo_measurement import suspension_function, travel_function
from wheelload.models.terms import DROPPABLE, GATES, gates_function
from wheelload.models.vehicle.description import (
    ModelTerms,
    Vehicle,
    VehicleFileError,
    vehicle_from_dict,
)
from wheelload.models.vehicle.file import example_vehicle_path, load_vehicle, vehicle_template

__all__ = [
    "DROPPABLE",
    "GATES",
    "GRAVITY",
    "INPUTS",
    "OPTIONAL_INPUTS",
    "WHEELS",
    "MassCentre",
    "ModelParameters",
    "ModelTerms",
    "Vehicle",
    "VehicleFileError",
    "equilibrium_function",
    "example_vehicle_path",
    "gates_function",
    "load_vehicle",
    "paper_equilibrium_function",
    "static_loads",
    "suspension_function",
    "travel_function",
    "vehicle_from_dict",
    "vehicle_mass_centre",
    "vehicle_template",
]
