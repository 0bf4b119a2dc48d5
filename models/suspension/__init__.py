"""The suspension: force laws of its elements, the loads its parts carry, the pseudo-measurement."""
