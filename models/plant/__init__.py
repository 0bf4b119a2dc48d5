"""The ground-truth plant: dynamics, equilibrium, tyre, slip control, road surface."""
