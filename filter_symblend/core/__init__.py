"""The paper's method on arrays: neighbourhoods, local symmetries, the global solve, the warp, and the ``symmetrize`` entry. Imports nothing above it (only ``errors`` and ``parameters``)."""
