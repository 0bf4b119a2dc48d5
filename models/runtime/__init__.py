"""Files the library writes and reads back (the private build folder, stored Functions and
their compiled C, owner-named temporaries), and package faces that import on first use."""
