"""Charts of rendering error against time."""
