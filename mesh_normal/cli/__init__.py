"""The ``mesh-normal`` command: analyse, export normals, fix winding; point-cloud normals;
``batch``, the report on every file of a dataset (:mod:`mesh_normal.datasets.command`).

Exit codes a script can use:

- 0: done; for ``analyze``, the mesh has no problem of severity "error".
- 1: ``analyze`` found at least one problem of severity "error" (the report says which).
- 2: bad usage (an unknown option, a missing argument, an unsupported output type, an output
  that would overwrite the input).
- 3: the input file cannot be read or is not a valid mesh (the message names the problem).
- 4: the output file cannot be written.

It starts fast: this module imports only the standard library and the format table, and each
command imports the library (numpy, the compiled core) when it runs, so ``--help``
and usage errors answer at once.
"""

from mesh_normal.cli.commands import main

__all__ = ["main"]
