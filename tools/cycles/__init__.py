"""Comparisons with Blender's Cycles (the reference renders run inside Blender)."""
