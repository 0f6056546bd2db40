"""Landmark input: file formats, pairing by name or table, snapping to vertices, curves."""
