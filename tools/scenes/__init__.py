"""Procedural scenes and camera paths."""
