"""The geometry of triangle meshes: checks, face, vertex and corner normals, topology,
orientation and what is seen from outside."""
