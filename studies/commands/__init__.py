"""Sub-commands of the ``wheelload`` console command."""
