"""The virtual test drive: roads, tracks, driver, speed profile, sensors, simulation, scenarios."""
