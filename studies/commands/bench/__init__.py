"""``wheelload bench WHAT``: one front end per benchmark (``command`` holds the group)."""
