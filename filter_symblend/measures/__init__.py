"""Before/after checks: landmark and surface mirror asymmetry, Hausdorff distance, pictures."""
