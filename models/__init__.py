"""Vehicle physics, written once, symbolically in CasADi."""

from wheelload.models.equilibrium import equilibrium_function
from wheelload.models.mass_properties import MassCentre, static_loads, vehicle_mass_centre
from wheelload.models.parameters import ModelParameters
from wheelload.models.suspension import suspension_function
from wheelload.models.vehicle import (
    GRAVITY,
    WHEELS,
    Vehicle,
    VehicleFileError,
    example_vehicle_path,
    load_vehicle,
    vehicle_from_dict,
    vehicle_template,
)

__all__ = [
    "GRAVITY",
    "WHEELS",
    "MassCentre",
    "ModelParameters",
    "Vehicle",
    "VehicleFileError",
    "equilibrium_function",
    "example_vehicle_path",
    "load_vehicle",
    "static_loads",
    "suspension_function",
    "vehicle_from_dict",
    "vehicle_mass_centre",
    "vehicle_template",
]
