"""Acceleration structures: whole host processes compared, the render bench's split as a
chart."""
