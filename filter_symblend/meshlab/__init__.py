"""The MeshLab side: the MeshSet filter, landmark attributes, PLY attributes, .mlx scripts."""
