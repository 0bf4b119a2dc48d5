"""Files the library writes: the private build folder, owner-named temporaries."""
