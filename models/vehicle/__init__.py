"""The vehicle file: its description, ranges, section checks, and reading and writing its text."""
