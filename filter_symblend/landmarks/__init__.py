"""Landmark input: file formats, pairing by name, by a pair table or by geometry, snapping to vertices, curves."""
