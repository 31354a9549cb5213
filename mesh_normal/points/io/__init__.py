"""Point-cloud files: reading PLY, PCD, LAS and LAZ, XYZ-like tables and the vertices of
mesh files; writing PLY, XYZ and CSV."""
