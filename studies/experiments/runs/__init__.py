"""Running the studies: units of work, cache, runner, context, output-folder lock."""
