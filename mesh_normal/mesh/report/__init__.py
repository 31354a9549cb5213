"""The report on a mesh: one analysis, its dataclasses, the diagnosis in words and the
comparison with the file's own normals."""
