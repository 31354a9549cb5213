"""One triangle's normal, exact and rounded once, and many triangles' at once."""
